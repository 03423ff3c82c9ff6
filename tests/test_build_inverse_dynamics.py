"""Inverse dynamics (gac_inverse_dynamics, model.inverse_dynamics): the generalised forces that give a chosen
acceleration, against the independent reference model's I_f q_ddot - R (its mass matrix from geometric Jacobians,
its bias and the generalised forces of inputs, springs and dampers) on random driven 3D chains, and the round trip
through the forward dynamics with those forces added."""
from __future__ import annotations

import numpy as np

from conftest import driven_free_chain, random_parameters, random_states, reference_of


def test_inverse_dynamics_against_the_reference_model(compiled):
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)              # the derivative tests' model: one build
    names = scene.parameter_names()
    rng = np.random.default_rng(28)
    for trial, (q, qd) in enumerate(random_states(3, 28, 4)):
        p = random_parameters(scene, seed=2800 + trial)
        u = rng.normal(size=model.nu) * 3
        qdd = rng.normal(size=model.nq) * 5
        tau = model.inverse_dynamics(q, qd, qdd, p, u)
        ref = reference_of(scene, p)
        springs = {k: (p[names.index(f"stiffness_{k}")], p[names.index(f"rest_angle_{k}")])
                   for k, j in enumerate(scene.joints, start=2) if j.stiffness is not None}
        dampers = {k: p[names.index(f"damping_{k}")] for k, j in enumerate(scene.joints, start=2) if j.damping}
        M = ref.mass_matrix(q)
        R = ref.bias(q, qd) + ref.applied_forces(q, qd, u, scene.inputs, springs, dampers)
        expected = M @ qdd - R
        assert np.max(np.abs(tau - expected)) < 1e-10 * np.max(np.abs(M)) * max(1.0, np.max(np.abs(qdd)))
        # the round trip: those forces added, the forward dynamics gives qdd back
        back = model.forward_dynamics(q, qd, p, u) + model.inertia_solve(q, tau, p)
        assert np.max(np.abs(back - qdd)) < 1e-10 * max(1.0, np.max(np.abs(qdd)))


def test_inverse_dynamics_of_the_free_acceleration_is_zero(compiled):
    """At the forward dynamics' own acceleration no force is needed; at rest tau = -R holds the springs' forces."""
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)              # the derivative tests' model: one build
    for q, qd in random_states(3, 29, 3):
        free = model.forward_dynamics(q, qd)
        assert np.max(np.abs(model.inverse_dynamics(q, qd, free))) < 1e-12 * max(1.0, np.max(np.abs(free))) * 10
        still = model.inverse_dynamics(q, np.zeros(model.nq), np.zeros(model.nq))
        assert np.allclose(still, -model.generalized_momentum(q, model.forward_dynamics(q, np.zeros(model.nq))),
                           rtol=0, atol=1e-12)
