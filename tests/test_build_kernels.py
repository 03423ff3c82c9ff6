"""The compiled C of every kernel computes what the derivation says: the compiled models of a few of the suite's
fixed scenes against the same kernels run as Python (tests/derived.py), and against the independent reference
model, on random parameter vectors and states.  The derivation itself is checked in test_derive_*.py."""
import numpy as np
import pytest

from codegen.scene import default_scene
from conftest import chain, driven_free_chain, random_parameters, random_states, reference_of

SCENES = [chain(1), chain(3, ("rigid", "line"), twists=True), chain(4, twists=True)]


def close(a, b, tol):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.abs(a - b).max() <= tol * max(np.abs(b).max(), 1.0)


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: s.name)
def test_compiled_kernels_equal_the_derived_ones_and_the_reference(compiled, derived, scene):
    model, expected = compiled(scene), derived(scene)
    rng = np.random.default_rng(scene.n)
    for trial, (q, qd) in enumerate(random_states(scene.n, 60 + scene.n, 3)):
        p = random_parameters(scene, seed=600 + trial)
        u = rng.normal(size=max(model.nu, 1))
        Q = rng.normal(size=model.nq)
        f = rng.normal(size=len(model.contact_rows))
        for name, args, tol in (("mass_matrix", (q, p), 1e-13), ("bias", (q, qd, p), 1e-12),
                                ("forward_dynamics", (q, qd, p), 1e-11), ("energy", (q, qd, p), 1e-13),
                                ("forward_dynamics_energy", (q, qd, p), 1e-11),
                                ("inertia_solve", (q, Q, p), 1e-11), ("generalized_momentum", (q, qd, p), 1e-13),
                                ("contact_generalized_force", (q, f, p), 1e-13), ("contact_points", (q, p), 1e-14),
                                ("contact_velocities", (q, qd, p), 1e-13), ("contact_jacobian", (q, p), 1e-14),
                                ("contact_bias", (q, qd, p), 1e-13), ("contact_gaps", (q, p), 1e-14)):
            got, want = getattr(model, name)(*args), getattr(expected, name)(*args)
            if name == "forward_dynamics_energy":
                got, want = np.r_[got[0], got[1:]], np.r_[want[0], want[1:]]
            assert close(got, want, tol), (name, trial)
        ref = reference_of(scene, p)
        assert close(model.mass_matrix(q, p), ref.mass_matrix(q), 1e-10)
        assert close(model.forward_dynamics(q, qd, p), ref.forward_dynamics(q, qd), 1e-9)
        assert close(model.energy(q, qd, p), ref.energy(q, qd), 1e-12)
        assert close(model.contact_points(q, p), ref.points(q), 1e-12)


def test_compiled_driven_model_equals_the_derived_one(compiled, derived):
    """Inputs, joint springs and dampers: the generalised forces, power and spring energy in C."""
    scene = driven_free_chain()
    model, expected = compiled(scene, tangent=True), derived(scene)      # the derivative tests' model: one build
    rng = np.random.default_rng(91)
    for trial, (q, qd) in enumerate(random_states(3, 91, 3)):
        p = random_parameters(scene, seed=910 + trial)
        u = rng.normal(size=model.nu) * 3
        for name in ("bias", "forward_dynamics", "power"):
            assert close(getattr(model, name)(q, qd, p, u), getattr(expected, name)(q, qd, p, u), 1e-11), name
        assert close(model.energy(q, qd, p), expected.energy(q, qd, p), 1e-13)


def test_compiled_specialised_planar_model_equals_the_derived_one(compiled, derived):
    """The specialised layout (locked coordinates, built-in zero parameters) compiles to what it derives."""
    scene = default_scene(3)
    model, expected = compiled(scene, specialise=True), derived(scene, specialise=True)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = model.q0 + rng.normal(scale=0.3, size=model.nq)
        qd = rng.normal(size=model.nq)
        for name, args in (("mass_matrix", (q,)), ("forward_dynamics", (q, qd)), ("energy", (q, qd)),
                           ("contact_jacobian", (q,)), ("contact_gaps", (q,)), ("contact_bias", (q, qd))):
            assert close(getattr(model, name)(*args), getattr(expected, name)(*args), 1e-11), name
