"""Coulomb friction at the impacts of two capsule links (friction.links, the frictional impact law's rows along the
pair's contact frame n, t1 = link i's axis off n, t2 = n x t1, at the closest points P, Q of the two axes): on random
states of a free spatial chain the strike keeps the chain's linear momentum (the impulses are internal), turns its
angular momentum by exactly (P - Q) x Lambda_T (the tangential impulses act at the axes, the radii apart), never
gains energy, keeps Coulomb's cone and the momentum balance along the frame's three directions; a strike together with a rough floor's contact is
solved by the same law; and with c_f = 0 the law is the frictionless one."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from studies.reference import reference_of

RADII = (0.0, 0.0, 0.06)          # O_1, on the rough floor, a bare point
TWISTS = (((1.0, 0, 0), (0, 0.0, -1.0), (0, 1.0, 0.0)), ((1.0, 0, 0), (0, 0.6, -0.8), (0, 0.8, 0.6)))


@pytest.fixture(scope="module")
def chain(compiled):
    """A free spatial three-link chain of capsules (twisted joints), no gravity, links 1 and 3 a rough pair
    (c_f = 0.6, e = 0.5), and a rough floor x2_min = -3 under O_1 (c_f = 0.4)."""
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), r) for l, mu, r in zip((1.0, 0.7, 0.9), (1.0, 2.0, 0.5), RADII))
    scene = Scene(name="rough_pair", links=links, twists=TWISTS, gravity=0.0, q0=(0.0,) * 8,
                  walls=(Wall("x2_min", -3.0, 0.7, (1,), 0.4),), link_restitution=0.5, link_friction=0.6)
    return compiled(scene)


def pair_rows(model, q):
    """Rows G (3 x nq) of the pair's relative velocity at its closest points along n, t1, t2 (the documented frame),
    from the model's point velocities."""
    _, s, t, n = model.link_gap(q, 1, 3)
    points = model.contact_points(q)
    d = points[1] - points[0]
    t1 = d - (d @ n) * n
    t1 /= np.linalg.norm(t1)
    axes = np.array([n, t1, np.cross(n, t1)])
    G = np.zeros((3, model.nq))
    for k in range(model.nq):
        e = np.zeros(model.nq)
        e[k] = 1.0
        vel = model.contact_velocities(q, e)
        G[:, k] = axes @ ((1 - s) * vel[0] + s * vel[1] - (1 - t) * vel[2] - t * vel[3])
    return G


def pair_index(model):
    return next(c for c, (_, contact) in enumerate(model.contacts) if getattr(contact, "name", "") == "L1-L3")


def test_a_rough_strike_keeps_momentum_and_the_cone_and_never_gains_energy(chain):
    """Random states where the pair approaches: linear momentum kept and angular momentum turned by (P - Q) x Lambda_T
    (1e-12), T+ <= T-, |L_T| <= c_f L_N,
    xi_N >= 0, and I_f (qd+ - qd-) = G^T (L_N, L_t1, L_t2); both sticking and sliding strikes occur."""
    reference = reference_of(chain.scene)
    c = pair_index(chain)
    rng = np.random.default_rng(17)
    regimes = set()
    for trial in range(80):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-1, 1, 3)])
        q[1] = rng.uniform(-1.2, 1.2)
        qd = rng.standard_normal(chain.nq) * 2.0
        _, s, t, _ = chain.link_gap(q, 1, 3)
        if (s, t) == (1.0, 0.0):                   # n along link 2: a push no motion takes
            continue
        G = pair_rows(chain, q)
        before = G @ qd
        if before[0] >= 0.0:
            continue
        result = chain.impact_friction(q, qd, [c])
        assert result.law == "gdi" and result.residual < 1e-9
        L = np.concatenate([result.impulse, result.impulse_t[0]])
        scale = 1.0 + np.abs(qd).max()
        assert reference.linear_momentum(q, result.qd_plus) == pytest.approx(reference.linear_momentum(q, qd),
                                                                              abs=1e-12 * scale)
        # the tangential impulses act at the axes' closest points P, Q (r_1 + r_3 apart at contact): the pair of
        # impulses +-Lambda there turns the chain by (P - Q) x Lambda_T (the normal one, along P - Q, does not)
        _, s, t, n = chain.link_gap(q, 1, 3)
        points = chain.contact_points(q)
        P, Q = (1 - s) * points[0] + s * points[1], (1 - t) * points[2] + t * points[3]
        d = points[1] - points[0]
        t1 = d - (d @ n) * n
        t1 /= np.linalg.norm(t1)
        Lambda_T = L[1] * t1 + L[2] * np.cross(n, t1)
        turned = reference.angular_momentum(q, result.qd_plus) - reference.angular_momentum(q, qd)
        assert turned == pytest.approx(np.cross(P - Q, Lambda_T), abs=1e-12 * scale)
        T0, T1 = chain.energy(q, qd)[0], chain.energy(q, result.qd_plus)[0]
        assert T1 <= T0 * (1 + 1e-12)
        assert L[0] > 0 and np.linalg.norm(L[1:]) <= 0.6 * L[0] * (1 + 1e-9)
        after = G @ result.qd_plus
        assert after[0] + 0.5 * before[0] >= -1e-9 * np.abs(before).max()
        change = chain.generalized_momentum(q, result.qd_plus - qd)
        assert np.allclose(change, G.T @ L, rtol=0, atol=1e-10 * np.abs(chain.generalized_momentum(q, qd)).max())
        regimes.add("stick" if np.linalg.norm(L[1:]) < 0.6 * L[0] * (1 - 1e-6) else "slip")
    assert regimes == {"stick", "slip"}


def test_a_strike_with_a_rough_floor_contact_is_solved_by_the_same_law(chain):
    """The pair and O_1 on the rough floor struck together (random states where both approach): no energy gain,
    Coulomb's cone at both, the momentum balance with the floor's rows (normal +X2, tangential X1, X3) and the
    pair's frame."""
    c = pair_index(chain)
    floor = next(k for k, (point, contact) in enumerate(chain.contacts) if getattr(contact, "name", "") == "x2_min")
    rng = np.random.default_rng(19)
    solved = 0
    for trial in range(200):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-1, 1, 3)])
        q[1] = rng.uniform(-1.2, 1.2)
        qd = rng.standard_normal(chain.nq) * 2.0
        _, s, t, _ = chain.link_gap(q, 1, 3)
        if (s, t) == (1.0, 0.0):
            continue
        G = pair_rows(chain, q)
        J1 = np.array([chain.contact_velocities(q, e)[0] for e in np.eye(chain.nq)]).T    # O_1's rows, 3 x nq
        if G[0] @ qd >= 0.0 or J1[1] @ qd >= 0.0:
            continue
        result = chain.impact_friction(q, qd, [floor, c])
        assert result.law in ("gdi", "gdi-common-e") and result.residual < 1e-9
        T0, T1 = chain.energy(q, qd)[0], chain.energy(q, result.qd_plus)[0]
        assert T1 <= T0 * (1 + 1e-12)
        (F_floor, F_pair), (Ft_floor, Ft_pair) = result.impulse, result.impulse_t
        assert np.linalg.norm(Ft_floor) <= 0.4 * F_floor * (1 + 1e-9) + 1e-15
        assert np.linalg.norm(Ft_pair) <= 0.6 * F_pair * (1 + 1e-9) + 1e-15
        pushed = (J1.T @ np.array([Ft_floor[0], F_floor, Ft_floor[1]])
                  + G.T @ np.concatenate([[F_pair], Ft_pair]))
        change = chain.generalized_momentum(q, result.qd_plus - qd)
        assert np.allclose(change, pushed, rtol=0, atol=1e-10 * np.abs(chain.generalized_momentum(q, qd)).max())
        solved += 1
    assert solved > 10


def test_without_friction_the_pair_law_is_the_frictionless_one(chain):
    """friction.links = 0 (the same chain otherwise): the frictional law's result on the pair alone is the
    frictionless law's to round-off (1e-13: the two solve the contact's system by separate paths), without
    tangential impulse."""
    smooth = dataclasses.replace(chain.scene, name="smooth_pair", link_friction=0.0)
    assert smooth.link_contacts()[0].friction == 0.0
    c = pair_index(chain)
    rng = np.random.default_rng(23)
    compared = 0
    for trial in range(30):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-1, 1, 3)])
        q[1] = rng.uniform(-1.2, 1.2)
        qd = rng.standard_normal(chain.nq)
        _, s, t, _ = chain.link_gap(q, 1, 3)
        if (s, t) == (1.0, 0.0) or chain.contact_normal(q, c) @ qd >= 0.0:
            continue
        expected, F = chain.impact(q, qd, [c], mode="complementarity")
        result = chain.impact_friction(q, qd, [c], law="frictionless")
        assert np.allclose(result.qd_plus, expected, rtol=0, atol=1e-13 * np.abs(qd).max())
        assert result.impulse[0] == pytest.approx(F[0], rel=1e-13) and not result.impulse_t.any()
        compared += 1
    assert compared > 10


def test_the_pair_frame_rows_biases_match_central_differences_along_a_trajectory(chain):
    """The biases a resting rough pair's held rows take (gac_contact_frame_tangent, the rows J^T n, J^T t1, J^T t2
    and their derivatives; this model has no tangent kernels, so the Jacobians' own change is differenced inside):
    along q(t) = q0 + v t + a t^2 / 2, d/dt (g_k . qd) = g_k . qdd + dg_k[qd] . qd against the fourth-order central
    difference (step 1e-4) to 1e-8, on random states where both closest points lie inside their links (both
    fractions moving), the rows the documented frame's."""
    c = pair_index(chain)
    rng = np.random.default_rng(29)
    checked = 0
    dp = np.zeros(max(len(chain.p), 1))

    def rows(q, dq):
        axes, g, dg = np.zeros(9), np.zeros(3 * chain.nq), np.zeros(3 * chain.nq)
        code = chain.lib.gac_contact_frame_tangent(chain.ffi.addressof(chain.c.model), chain._ptr(q),
                                                   chain._ptr(chain.p), c, chain._ptr(dq), chain._ptr(dp),
                                                   chain._ptr(axes), chain._ptr(g), chain._ptr(dg))
        assert code == chain.lib.GAC_OK, chain.error_message(code)
        return g.reshape(3, chain.nq), dg.reshape(3, chain.nq)

    while checked < 5:
        q0 = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-1, 1, 3)])
        q0[1] = rng.uniform(-1.2, 1.2)
        _, s, t, _ = chain.link_gap(q0, 1, 3)
        if not (0.05 < s < 0.95 and 0.05 < t < 0.95):
            continue
        v, acc = rng.standard_normal(chain.nq), rng.standard_normal(chain.nq)
        g, dg = rows(q0, v)
        assert np.allclose(g, pair_rows(chain, q0), rtol=0, atol=1e-14 * np.abs(g).max())
        exact = g @ acc + dg @ v

        def rates(h):
            return rows(q0 + v * h + 0.5 * acc * h * h, np.zeros(chain.nq))[0] @ (v + acc * h)

        h = 1e-4
        diff = (8.0 * (rates(h) - rates(-h)) - (rates(2 * h) - rates(-2 * h))) / (12.0 * h)
        assert np.abs(diff - exact).max() < 1e-8 * max(1.0, np.abs(exact).max()), (diff, exact)
        checked += 1
