"""The compiled tangent kernel (NAME_forward_dynamics_tangent) and the linearisation (gac_linearize,
model.linearize): against 6th-order central differences of the compiled forward dynamics on the driven twisted 3D
chain, against the closed form of a spring-coupled pair of rods, and the refusals of models without a tangent."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from runtime import simulate

from codegen.options import build_options
from codegen.scene import Joint, LineLink, Scene
from conftest import chain, driven_free_chain, random_parameters, random_states

STEPS = ((1, 45.0), (2, -9.0), (3, 1.0))            # 6th-order central difference: sum c_k (f(+kh) - f(-kh)) / 60h


def central(f, h):
    return sum(c * (f(k * h) - f(-k * h)) for k, c in STEPS) / (60.0 * h)


def _case(model, scene, trial, rng):
    (q, qd), = random_states(3, 7100 + trial, 1)
    return q, qd, random_parameters(scene, seed=7100 + trial), rng.normal(size=model.nu) * 2


def test_tangent_kernel_against_finite_differences(compiled):
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)
    rng = np.random.default_rng(71)
    for trial in range(4):
        q, qd, p, u = _case(model, scene, trial, rng)
        dq, dqd, du = rng.normal(size=model.nq), rng.normal(size=model.nq), rng.normal(size=model.nu)
        dp = rng.normal(size=len(p)) * p * 0.2            # every parameter moves, by a fraction of its size
        got = model.forward_dynamics_tangent(q, qd, dq, dqd, p, u, du, dp)
        expected = central(lambda h: model.forward_dynamics(q + h * dq, qd + h * dqd, p + h * dp, u + h * du), 1e-3)
        assert np.max(np.abs(got - expected)) < 1e-9 * np.max(np.abs(expected))
        # linear in the direction, and the zero direction gives zero
        twice = model.forward_dynamics_tangent(q, qd, 2 * dq, 2 * dqd, p, u, 2 * du, 2 * dp)
        assert np.allclose(twice, 2 * got, rtol=1e-13, atol=0)
        assert not np.any(model.forward_dynamics_tangent(q, qd, 0 * dq, 0 * dqd, p, u))


def test_the_block_tangent_is_the_tangent_along_each_of_its_directions(compiled):
    """NAME_forward_dynamics_tangent_block (the primal part once, the tangent part in a loop over
    GAC_TANGENT_BLOCK directions) gives, direction by direction, the numbers of NAME_forward_dynamics_tangent, inputs
    and parameters moving too; its block size is gac.h's."""
    from codegen import interface
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)
    block = interface.TANGENT_BLOCK
    assert model.lib.GAC_TANGENT_BLOCK == block
    rng = np.random.default_rng(73)
    q, qd, p, u = _case(model, scene, 0, rng)
    dq, dqd = rng.normal(size=(block, model.nq)), rng.normal(size=(block, model.nq))
    du, dp = rng.normal(size=(block, model.nu)), rng.normal(size=(block, len(p))) * p * 0.2
    got = model._call("forward_dynamics_tangent_block", block * model.nq, q, qd, u, p, dq.ravel(), dqd.ravel(),
                      du.ravel(), dp.ravel()).reshape(block, model.nq)
    for j in range(block):
        single = model.forward_dynamics_tangent(q, qd, dq[j], dqd[j], p, u, du[j], dp[j])
        assert np.allclose(got[j], single, rtol=1e-13, atol=1e-13 * np.abs(single).max())


def test_point_tangents_against_finite_differences(compiled):
    """NAME_contact_points_tangent and NAME_contact_velocities_tangent (the second derivatives of the kinematics a
    link pair's or an obstacle's row needs) against 6th-order central differences of the compiled contact_points and
    contact_velocities, every parameter moving; linear in the direction, 0 along none; at qd = e_k, dqd = 0, the
    change of the points' Jacobian column k."""
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)
    rng = np.random.default_rng(74)
    for trial in range(4):
        q, qd, p, _ = _case(model, scene, trial, rng)
        dq, dqd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        dp = rng.normal(size=len(p)) * p * 0.2
        got = model.contact_points_tangent(q, dq, p, dp)
        expected = central(lambda h: model.contact_points(q + h * dq, p + h * dp), 1e-3)
        assert np.max(np.abs(got - expected)) < 1e-10 * np.max(np.abs(expected))
        assert np.allclose(got, model.contact_velocities(q, dq, p) + model.contact_points_tangent(q, 0 * dq, p, dp),
                           rtol=0, atol=1e-13 * np.max(np.abs(got)))     # dr/dq dq is the velocity at qd = dq
        got = model.contact_velocities_tangent(q, qd, dq, dqd, p, dp)
        expected = central(lambda h: model.contact_velocities(q + h * dq, qd + h * dqd, p + h * dp), 1e-3)
        assert np.max(np.abs(got - expected)) < 1e-10 * np.max(np.abs(expected))
        twice = model.contact_velocities_tangent(q, qd, 2 * dq, 2 * dqd, p, 2 * dp)
        assert np.allclose(twice, 2 * got, rtol=1e-13, atol=0)
        assert not np.any(model.contact_velocities_tangent(q, qd, 0 * dq, 0 * dqd, p))
        e = np.eye(model.nq)[trial]
        column = model.contact_velocities_tangent(q, e, dq, 0 * dqd, p, dp)
        expected = central(lambda h: model.contact_velocities(q + h * dq, e, p + h * dp), 1e-3)
        assert np.max(np.abs(column - expected)) < 1e-10 * max(np.max(np.abs(expected)), 1.0)


def test_linearize_against_finite_differences(compiled):
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)
    nq, nx = model.nq, 2 * model.nq
    rng = np.random.default_rng(72)
    names = ["l_1", "mu_2", "stiffness_2", "damping_3", "rest_angle_2"]
    for trial in range(2):
        q, qd, p, u = _case(model, scene, trial, rng)
        A, B, P = model.linearize(q, qd, p, u, parameters=names)
        assert A.shape == (nx, nx) and B.shape == (nx, model.nu) and P.shape == (nx, len(names))
        # the upper blocks: d(qd)/d(q, qd) = [0 I] exactly, and no input or parameter moves qd
        assert np.array_equal(A[:nq], np.hstack([np.zeros((nq, nq)), np.eye(nq)]))
        assert not np.any(B[:nq]) and not np.any(P[:nq])
        x = np.concatenate([q, qd])

        def xdot(x, p=p, u=u):
            return np.concatenate([x[nq:], model.forward_dynamics(x[:nq], x[nq:], p, u)])
        A_fd = np.column_stack([central(lambda h: xdot(x + h * e), 1e-3) for e in np.eye(nx)])
        B_fd = np.column_stack([central(lambda h: xdot(x, u=u + h * e), 1e-3) for e in np.eye(model.nu)])
        index = [scene.parameter_names().index(name) for name in names]
        P_fd = np.column_stack([central(lambda h: xdot(x, p=p + h * abs(p[i]) * np.eye(len(p))[i]), 1e-3)
                                / abs(p[i]) for i in index])
        for got, expected in ((A, A_fd), (B, B_fd), (P, P_fd)):
            assert np.max(np.abs(got - expected)) < 1e-9 * np.max(np.abs(expected))


def test_linearize_refuses_parameters_it_does_not_read(compiled):
    model = compiled(driven_free_chain(), tangent=True)
    q, qd = model.q0, model.qd0
    with pytest.raises(ValueError, match="parameters: no parameter 'mass_9'"):
        model.linearize(q, qd, parameters=["mass_9"])


def spring_pair(K: float, C: float, length: float, mu: float, J: float) -> Scene:
    """Two equal slender rods joined end to end by a joint spring and damper, floating, no gravity, no walls."""
    rod = LineLink(length, mu, (J, J, J))
    return Scene(name="spring_pair", links=(rod, rod), joints=(Joint(K, 0.0, C),), gravity=0.0,
                 walls=(), q0=(0.0,) * 7)


def test_spring_pair_against_its_closed_form(compiled):
    """Straight and at rest, the pair's only motion with force is the relative turn theta_2: momentum and angular
    momentum conservation keep the centre of mass still and turn the rods by -theta/2 and theta/2 about their centres,
    so T = I_c theta_dot^2 / 4 (I_c = mu l^3 / 12 + l Jzz, a rod about its centre) and
    theta_ddot = -(2 / I_c)(K theta + C theta_dot): A has the eigenvalues of [[0, 1], [-2K/I_c, -2C/I_c]] and
    zeros (the free rigid motions)."""
    K, C, length, mu, J = 7.0, 0.3, 0.8, 1.5, 2e-3
    model = compiled(spring_pair(K, C, length, mu, J), tangent=True)
    I_c = mu * length ** 3 / 12 + length * J
    A, B = model.linearize(np.zeros(model.nq), np.zeros(model.nq))
    assert B.shape == (2 * model.nq, 0)
    a, b = 2 * C / I_c, 2 * K / I_c                                      # lambda^2 + a lambda + b = 0
    root = complex(-a / 2, math.sqrt(b - a * a / 4))
    eigenvalues = np.linalg.eigvals(A)
    mode = sorted(eigenvalues, key=abs)[-2:]
    assert all(abs(ev - r) < 1e-9 * abs(root) for ev, r in zip(sorted(mode, key=lambda z: z.imag),
                                                                (root.conjugate(), root)))
    assert np.max(np.abs(sorted(eigenvalues, key=abs)[:-2])) < 1e-6 * abs(root)
    # the theta_2 row of d qdd/dq and d qdd/dqd alone: -2K/I_c and -2C/I_c on theta_2 (index 3 of q)
    nq = model.nq
    assert A[nq + 3, 3] == pytest.approx(-b, rel=1e-12) and A[nq + 3, nq + 3] == pytest.approx(-a, rel=1e-12)


def test_models_without_a_tangent_refuse_by_option(compiled):
    """Tangent kernels are built on request; a long chain asking for them gets straight-line forward dynamics
    (the rolled loops have no tangent), rolled=True with them is refused naming the option, and a model built
    without them says how to get them."""
    assert not build_options(chain(2)).tangent and build_options(chain(2), tangent=True).tangent
    assert build_options(chain(8)).rolled
    long = build_options(chain(8), tangent=True)
    assert long.tangent and not long.rolled
    with pytest.raises(ValueError, match=r"tangent: the rolled forward dynamics \(rolled=True: loops"):
        build_options(chain(8), rolled=True, tangent=True)
    with pytest.raises(TypeError, match="tangent: expected True or False"):
        build_options(chain(2), tangent="yes")
    with pytest.raises(TypeError, match="tangent: expected True or False"):
        build_options(chain(2), tangent=None)
    plain = compiled(chain(2))
    with pytest.raises(ValueError, match="linearize: this model has no tangent kernel .* tangent=True"):
        plain.linearize(plain.q0, plain.qd0)
    with pytest.raises(ValueError, match="sensitivities: .* tangent=True"):
        simulate(plain, 0.1, sensitivities=["g"])
