"""Tangent kernels and inputs of a scene of several chains (codegen.combine): the sensitivities of a run through a strike of two
chains' links (head-on, and a spinning link's end on the side of the other) against central differences of whole
runs, the pair's row derivative across the chains (gac_contact_normal_tangent on global points) against central
differences, the linearisation block-diagonal with each chain's own model's blocks, the block tangent kernel
equal to its directions one at a time, and each chain's inputs acting on its own block (u stacked by chain)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from codegen.scene import Chains, Joint, LineLink, Scene, Wall
from runtime import load_model, simulate
from tests.test_sim_chains import LENGTH, MU, RADIUS, head_on
from tests.test_sim_chains_blocks import chains as tumbling
from tests.test_sim_sensitivities import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)


def tee() -> Chains:
    """Chain 1 along X1 at X2 = 0, spinning, thrown at chain 2 standing along X2 (from X2 = -0.15): chain 1's end
    strikes the inside of chain 2's link."""
    walls = (Wall("x1_min", -3.0, 1.0), Wall("x1_max", 3.0, 1.0))

    def chain(k, theta, x, y, v, w):
        return Scene(name=f"tee_c{k}", links=(LineLink(LENGTH, MU, radius=RADIUS),), gravity=0.0, walls=walls,
                     q0=(-math.pi / 2, 0.0, theta, x, y, 0.0), qd0=(0.0, 0.0, w, v, 0.0, 0.0))
    return Chains(name="tee", chains=(chain(1, -math.pi / 2, -0.6, 0.0, 1.0, 0.4), chain(2, 0.0, 0.3, -0.15, -0.5, 0.0)),
                  link_restitution=0.7)


def _run(scene, directions, t_end=0.5):
    model = load_model(scene, tangent=True)
    q0, qd0, p = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float), model.p.copy()
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["O2-L3"]], r.message
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    return model, r, (p, q0, qd0)


@pytest.mark.parametrize("e", [1.0, 0.5])
def test_the_head_on_strike_of_two_chains_matches_central_differences(e):
    directions = ["q0[c1.X1]", "qd0[c1.X1]", "qd0[c2.X1]", "q0[c2.X2]", "qd0[c2.theta_1]", "c1.l_1", "c2.mu_1"]
    model, r, (p, q0, qd0) = _run(head_on(e), directions)
    assert r.sensitivities.rows[:3] == ["q[c1.theta_1]", "q[c1.X1]", "q[c1.X2]"]
    central_differences(model, 0.5, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_a_spinning_links_end_on_the_side_of_another_chains_link_matches_central_differences():
    directions = ["q0[c1.X1]", "q0[c1.theta_1]", "qd0[c1.theta_1]", "qd0[c2.X1]", "q0[c2.X2]", "c1.l_1", "c2.mu_1"]
    model, r, (p, q0, qd0) = _run(tee(), directions)
    _, s, t, _ = model.link_gap(model.layout.reduce(r.impacts[0].q), 1, 3)
    assert s == 1.0 and 0.0 < t < 1.0                    # chain 1's end on the inside of chain 2's link
    central_differences(model, 0.5, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_the_pairs_row_derivative_across_the_chains_matches_central_differences():
    """gac_contact_normal_tangent of the pair L1-L3 (global points O_1, O_2 of chain 1 and O_3, O_4 of chain 2) along
    random directions of q and of both chains' parameters."""
    model = load_model(tee(), tangent=True)
    r = simulate(model, 0.5, **TIGHT)
    q_hit = model.layout.reduce(r.impacts[0].q)
    (c,) = [k for k, (_, what) in enumerate(model.contacts) if getattr(what, "name", "") == "L1-L3"]
    names = model.parameter_names
    indices = [names.index("c1.l_1"), names.index("c2.l_1")]
    rng = np.random.default_rng(11)
    for _ in range(4):
        q = q_hit + rng.uniform(-0.01, 0.01, model.nq)
        dq, dp = rng.normal(size=model.nq), np.zeros(len(model.p))
        dp[indices] = rng.normal(size=2)
        dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
        code = model.lib.gac_contact_normal_tangent(model.ffi.addressof(model.c.model), model._ptr(q),
                                                    model._ptr(model.p), c, model._ptr(dq), model._ptr(dp), dgap,
                                                    model._ptr(g), model._ptr(dg))
        assert code == model.lib.GAC_OK
        assert np.allclose(g, model.contact_normal(q, c), rtol=0, atol=1e-14)

        def at(h):
            p = model.p + h * dp
            return model.contact_gaps(q + h * dq, p)[c], model.contact_normal(q + h * dq, c, p)

        h = 1e-5
        (g1, n1), (g_1, n_1), (g2, n2), (g_2, n_2) = at(h), at(-h), at(2 * h), at(-2 * h)
        assert dgap[0] == pytest.approx((8 * (g1 - g_1) - (g2 - g_2)) / (12 * h), abs=1e-9)
        fd_row = (8 * (n1 - n_1) - (n2 - n_2)) / (12 * h)
        assert np.abs(dg - fd_row).max() <= 1e-8 * max(1.0, np.abs(fd_row).max())


@pytest.fixture(scope="module")
def tumble():
    scene = tumbling()
    return scene, load_model(scene, tangent=True), [load_model(chain, tangent=True) for chain in scene.chains]


def _split(scene, model, own, q):
    """The combined model's coordinates cut into each chain's own."""
    full, out, start = model.layout.expand(q), [], 0
    for chain, m in zip(scene.chains, own):
        out.append(m.layout.reduce(full[start:start + chain.nq]))
        start += chain.nq
    return out


def test_the_linearisation_is_block_diagonal_with_each_chains_own_blocks(tumble):
    scene, model, own = tumble
    rng = np.random.default_rng(4)
    parameters = ["g", "c1.l_2", "c2.mu_3"]
    for _ in range(3):
        q, qd = rng.uniform(-2, 2, model.nq), rng.uniform(-3, 3, model.nq)
        A, B, P = model.linearize(q, qd, parameters=parameters)
        nq = model.nq
        assert B.shape == (2 * nq, 0)
        start = 0
        for k, (m, qk, qdk) in enumerate(zip(own, _split(scene, model, own, q), _split(scene, model, own, qd)), 1):
            Ak, _, Pk = m.linearize(qk, qdk, parameters=["g", "l_2" if k == 1 else "mu_3"])
            n, rows = m.nq, slice(nq + start, nq + start + m.nq)
            mine = np.r_[start:start + n, nq + start:nq + start + n]
            assert np.allclose(A[rows][:, mine], Ak[n:], rtol=1e-12, atol=1e-12)
            others = np.setdiff1d(np.arange(2 * nq), mine)
            assert np.all(A[rows][:, others] == 0.0)                   # nothing couples the chains in flight
            assert np.allclose(P[rows, 0], Pk[n:, 0], rtol=1e-12, atol=1e-12)     # g: the box's, both chains'
            assert np.allclose(P[rows, k], Pk[n:, 1], rtol=1e-12, atol=1e-12)     # the chain's own parameter
            assert np.all(P[rows, 3 - k] == 0.0)                       # the other chain's parameter
            start += n


def test_the_block_tangent_kernel_is_its_directions_one_at_a_time(tumble):
    scene, model, _ = tumble
    block = model.lib.GAC_TANGENT_BLOCK
    rng = np.random.default_rng(8)
    nq, npar = model.nq, len(model.p)
    q, qd = rng.uniform(-2, 2, nq), rng.uniform(-3, 3, nq)
    dq, dqd, dp = rng.normal(size=(block, nq)), rng.normal(size=(block, nq)), rng.normal(size=(block, npar))
    out, u = np.zeros((block, nq)), np.zeros(1)
    getattr(model.lib, f"{model.name}_forward_dynamics_tangent_block")(
        model._ptr(q), model._ptr(qd), model._ptr(u), model._ptr(model.p), model._ptr(dq), model._ptr(dqd),
        model._ptr(np.zeros(block)), model._ptr(dp), model._ptr(out))
    for j in range(block):
        one = model.forward_dynamics_tangent(q, qd, dq[j], dqd[j], dp=dp[j])
        assert np.allclose(out[j], one, rtol=1e-13, atol=1e-13)


@pytest.mark.slow            # three models of their own (two 3D chains driven, with tangents): about 14 s cold
def test_each_chains_inputs_drive_its_own_block():
    """Chain 1 driven on theta_2, chain 2 on theta_1 and theta_3 (with a spring and damper on its first joint): the
    model's u is theirs stacked ('c1.theta_2', 'c2.theta_1', 'c2.theta_3'); qdd, the power and B are each chain's
    own model's with its slice of u."""
    a, b = tumbling().chains
    scene = Chains(name="tumble_driven", chains=(replace(a, inputs=("theta_2",)), replace(
        b, inputs=("theta_1", "theta_3"), joints=(Joint(stiffness=2.0, damping=0.3),) + b.joints[1:])),
        link_restitution=0.9)
    model = load_model(scene, tangent=True)
    own = [load_model(chain, tangent=True) for chain in scene.chains]
    assert model.input_names == ["c1.theta_2", "c2.theta_1", "c2.theta_3"] and model.nu == 3
    rng = np.random.default_rng(2)
    q, qd, u = rng.uniform(-2, 2, model.nq), rng.uniform(-3, 3, model.nq), rng.normal(size=3)
    qs, qds, us = _split(scene, model, own, q), _split(scene, model, own, qd), [u[:1], u[1:]]
    assert np.array_equal(model.forward_dynamics(q, qd, u=u),
                          np.concatenate([m.forward_dynamics(x, y, u=z) for m, x, y, z in zip(own, qs, qds, us)]))
    parts = np.array([m.power(x, y, u=z) for m, x, y, z in zip(own, qs, qds, us)])
    assert np.allclose(model.power(q, qd, u=u), parts.sum(axis=0), rtol=1e-14, atol=1e-14)
    _, B = model.linearize(q, qd, u=u)
    nq, n1 = model.nq, own[0].nq
    blocks = [m.linearize(x, y, u=z)[1] for m, x, y, z in zip(own, qs, qds, us)]
    assert np.allclose(B[nq:nq + n1, :1], blocks[0][n1:], rtol=1e-12, atol=1e-12)
    assert np.allclose(B[nq + n1:, 1:], blocks[1][own[1].nq:], rtol=1e-12, atol=1e-12)
    assert np.all(B[nq:nq + n1, 1:] == 0.0) and np.all(B[nq + n1:, :1] == 0.0)
    r = simulate(model, 0.5, u=u)
    assert r.success and r.impacts, r.message
