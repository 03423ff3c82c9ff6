"""Coulomb friction at the impacts of a link on a fixed obstacle (the frictional impact law's rows of a contact with
no Jacobian row, gac_friction_system): a free rod striking a rough ball, against an independent numpy implementation
of the law for one contact (its 3 x 3 contact-space inverse inertia W built here from the model's mass matrix and
point velocities along the documented frame n, t1 = the rod's axis off n, t2 = n x t1; stick where -W^-1 q lies in
the cone, else slide, the direction found by a sweep of the tangent plane), in the stick and the slip regime; the
kinetic energy never grows on random states, coefficients and restitutions; c_f = 0 gives the frictionless law
exactly; a run keeps the momentum balance along all three directions; a rod landing on the rough ball off centre is
held there by its friction (on a smooth ball it slides off); and sensitivities stop at such an impact."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import simulate

BALL = (0.0, 0.0, 0.0)
TIGHT = dict(rtol=1e-12, atol=1e-14)


@pytest.fixture(scope="module")
def model(compiled):
    """A free rod of 1.2 m (capsule radius 0.02 m, a rigid body in 3D) and a rough ball of radius 0.3 m at the
    origin (friction_ball a runtime parameter), under gravity."""
    ball = Obstacle.sphere("ball", BALL, 0.3, friction=0.5)
    scene = Scene(name="rough_ball", links=(LineLink(1.2, 1.5, (2e-3, 3e-3, 4e-3), 0.02),), gravity=9.81,
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.3, -0.4, 0.8, 0.1), obstacles=(ball,))
    return compiled(scene, tangent=True)


def frame(model, q, p=None):
    """The contact frame of the rod on the ball as documented (n from the ball to the rod's closest point, t1 the
    rod's axis with its part along n removed, t2 = n x t1) and the rows G (3 x nq) of the closest point's velocity
    along n, t1, t2, from the model's point velocities column by column."""
    _, s, _, n = model.obstacle_gap(q, 1, "ball", p)
    points = model.contact_points(q, p)
    d = points[1] - points[0]
    t1 = d - (d @ n) * n
    t1 /= np.linalg.norm(t1)
    axes = np.array([n, t1, np.cross(n, t1)])
    G = np.zeros((3, model.nq))
    for k in range(model.nq):
        e = np.zeros(model.nq)
        e[k] = 1.0
        vel = model.contact_velocities(q, e, p)
        G[:, k] = axes @ ((1 - s) * vel[0] + s * vel[1])
    return axes, G


def gdi_one_contact(W, gamma, c_f, e):
    """The impulse (normal, t1, t2) of one contact by the law: xi = W L + (1 + e) gamma, 0 <= L_N _|_ xi_N >= 0,
    L_T = -c_f L_N xi_T / |xi_T| where it slides, |L_T| <= c_f L_N where it sticks.  Independent of the library:
    stick if -W^-1 q is in the cone, else the slide directions d of the tangent plane where xi_T is along d (a sweep
    of 20000 angles, each sign change bisected), L_N > 0, the one nearest q_T's direction."""
    q = (1.0 + e) * np.asarray(gamma, float)
    if q[0] >= 0.0:
        return np.zeros(3), "separate"
    stick = -np.linalg.solve(W, q)
    if stick[0] > 0 and np.linalg.norm(stick[1:]) <= c_f * stick[0]:
        return stick, "stick"

    def slide(phi):
        d = np.array([math.cos(phi), math.sin(phi)])
        L = np.concatenate([[1.0], -c_f * d])
        L_N = -q[0] / (W[0] @ L)
        xi_T = W[1:] @ (L_N * L) + q[1:]
        return L_N * L, xi_T[0] * d[1] - xi_T[1] * d[0], xi_T @ d

    phis = np.linspace(-math.pi, math.pi, 20001)
    values = [slide(phi)[1] for phi in phis]
    best, best_score = None, -np.inf
    for k in range(len(phis) - 1):
        if values[k] == 0.0 or values[k] * values[k + 1] < 0.0:
            lo, hi = phis[k], phis[k + 1]
            for _ in range(100):
                mid = 0.5 * (lo + hi)
                if (slide(mid)[1] > 0) == (slide(lo)[1] > 0):
                    lo = mid
                else:
                    hi = mid
            L, _, along = slide(0.5 * (lo + hi))
            score = -(L[1:] @ q[1:])
            if L[0] > 0 and along >= 0 and score > best_score:
                best, best_score = L, score
    assert best is not None, "no sliding solution"
    return best, "slip"


def random_state(model, rng):
    """A random configuration of the rod near the ball (its closest point inside it or at an end) and velocities."""
    q = np.concatenate([rng.uniform(-1.2, 1.2, 3), rng.uniform(-0.9, 0.9, 3)])
    return q, rng.normal(size=model.nq) * 2.0


def test_the_law_matches_an_independent_one_contact_solution_in_stick_and_slip(model):
    """Random states, c_f and e: the normal and tangential impulses (the latter along t1, t2) and the velocities
    after against gdi_one_contact on W = G I_f^-1 G^T, qd+ = qd + I_f^-1 G^T L; both regimes are met."""
    rng = np.random.default_rng(41)
    regimes = set()
    names = model.parameter_names
    for trial in range(60):
        q, qd = random_state(model, rng)
        c_f, e = rng.uniform(0.05, 1.5), rng.uniform(0.0, 1.0)
        p = model.parameters({"friction_ball": c_f, "e_ball": e})
        axes, G = frame(model, q, p)
        gamma = G @ qd
        if gamma[0] >= -1e-3:
            continue
        M = model.mass_matrix(q, p)
        W = G @ np.linalg.solve(M, G.T)
        L, regime = gdi_one_contact(W, gamma, c_f, e)
        regimes.add(regime)
        result = model.impact_friction(q, qd, [0], p)
        assert result.law == "gdi" and result.residual < 1e-10
        scale = np.abs(L).max()
        assert result.impulse[0] == pytest.approx(L[0], rel=1e-8)
        assert np.allclose(result.impulse_t[0], L[1:], rtol=0, atol=1e-8 * scale)
        expected = qd + np.linalg.solve(M, G.T @ L)
        assert np.allclose(result.qd_plus, expected, rtol=0, atol=1e-8 * np.abs(qd).max())
        assert names.index("friction_ball") == names.index("center_x_ball") - 1      # then the geometry
    assert regimes == {"stick", "slip"}


def test_the_energy_never_grows_and_the_cone_holds(model):
    """Random states, c_f in [0, 3] and e in [0, 1] (300 draws): T+ <= T-, |L_T| <= c_f L_N, and the normal velocity
    after is at least -e times the one before (xi_N >= 0)."""
    rng = np.random.default_rng(43)
    struck = 0
    for trial in range(300):
        q, qd = random_state(model, rng)
        c_f, e = rng.uniform(0.0, 3.0), rng.uniform(0.0, 1.0)
        p = model.parameters({"friction_ball": c_f, "e_ball": e})
        _, G = frame(model, q, p)
        before = G @ qd
        if before[0] >= 0.0:
            continue
        struck += 1
        result = model.impact_friction(q, qd, [0], p)
        T0, T1 = model.energy(q, qd, p)[0], model.energy(q, result.qd_plus, p)[0]
        assert T1 <= T0 * (1 + 1e-12)
        L_N, L_T = result.impulse[0], result.impulse_t[0]
        assert L_N > 0 and np.linalg.norm(L_T) <= c_f * L_N * (1 + 1e-9)
        after = G @ result.qd_plus
        assert after[0] + e * before[0] >= -1e-9 * np.abs(before).max()
    assert struck > 100


def test_without_friction_the_law_is_the_frictionless_one(model):
    """friction_ball = 0: the frictional law gives what the frictionless law gives (to 1e-14), with no tangential
    impulse; and a whole run is the run of the frictionless law, bit for bit."""
    rng = np.random.default_rng(47)
    compared = 0
    for trial in range(30):
        q, qd = random_state(model, rng)
        p = model.parameters({"friction_ball": 0.0, "e_ball": rng.uniform(0, 1)})
        if model.contact_normal(q, 0, p) @ qd >= 0.0:
            continue
        expected, F = model.impact(q, qd, [0], p, mode="complementarity")
        result = model.impact_friction(q, qd, [0], p)
        assert np.allclose(result.qd_plus, expected, rtol=0, atol=1e-14 * np.abs(qd).max())
        assert result.impulse[0] == pytest.approx(F[0], rel=1e-14) and not result.impulse_t.any()
        compared += 1
    assert compared > 10
    q0, qd0 = strike_start()
    p = model.parameters({"friction_ball": 0.0, "e_ball": 0.6})
    a = simulate(model, 0.6, p=p, q0=q0, qd0=qd0, **TIGHT)
    b = simulate(model, 0.6, p=p, q0=q0, qd0=qd0, impact_law="frictionless", **TIGHT)
    assert a.success and b.success and len(a.impacts) >= 1
    assert np.array_equal(a.q, b.q) and np.array_equal(a.qd, b.qd)


def strike_start():
    """The rod flying at the ball obliquely and spinning: it strikes it inside its length."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + 0.3, -0.4, 0.8, 0.1])
    qd0 = np.array([0.0, 0.0, 1.5, 1.2, -2.0, -0.3])
    return q0, qd0


def test_a_run_striking_the_rough_ball_balances_momentum_along_n_t1_t2(model):
    """The rod strikes the rough ball (c_f = 0.5, e = 0.6): the record's law is the frictional one, its tangential
    impulse is not 0, the momentum balance I_f (qd+ - qd-) = G^T (L_N, L_t1, L_t2) holds with the frame's rows, and
    the energy falls."""
    q0, qd0 = strike_start()
    p = model.parameters({"e_ball": 0.6})
    r = simulate(model, 0.6, p=p, q0=q0, qd0=qd0, **TIGHT)
    assert r.success, r.message
    assert len(r.impacts) >= 1
    impact = r.impacts[0]
    assert impact.law == "gdi" and [c.label for c in impact.contacts] == ["L1/ball"]
    c = impact.contacts[0]
    assert np.linalg.norm(c.impulse_t) > 1e-3 * c.impulse
    q, qd_m, qd_p = (model.layout.reduce(x) for x in (impact.q, impact.qd_before, impact.qd_after))
    _, G = frame(model, q, p)
    change = model.generalized_momentum(q, qd_p - qd_m, p)
    pushed = G.T @ np.concatenate([[c.impulse], c.impulse_t])
    assert np.allclose(change, pushed, rtol=0, atol=1e-10 * np.abs(model.generalized_momentum(q, qd_m, p)).max())
    assert impact.energy_after < impact.energy_before


def test_sensitivities_pass_a_rough_strike(model):
    """Sensitivities through the rough ball's impact (the frictional law along the contact frame's rows,
    tests/test_sim_sensitivities_rough_rowless.py): valid through the spinning rod's oblique strike, and the final
    state's against central differences of whole runs."""
    from tests.test_sim_sensitivities import central_differences
    q0, qd0 = strike_start()
    p = model.parameters({"e_ball": 0.6})
    directions = ["qd0[X1]", "q0[theta_1]", "friction_ball"]
    r = simulate(model, 0.6, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and len(r.impacts) == 1 and r.impacts[0].law == "gdi"
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    central_differences(model, 0.6, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_a_rod_landing_on_the_rough_ball_rests_on_it_held_by_its_friction(model):
    """The rod dropped flat, its centre over the ball (e_ball = 0): the frictional law's plastic strike, then the
    contact held without sinking into the ball; dropped off centre, it lands and sticks (c_f = 0.5): the stuck point
    holds it, and it rocks on the ball, rolling without slipping, its centre staying within millimetres of where it
    landed, the energy kept; on a smooth ball (friction_ball = 0) nothing holds it tangentially and it slides off."""
    q0 = np.array([-math.pi / 2, 0.0, -math.pi / 2, -0.6, 0.5, 0.0])        # O_1 (-0.6, 0.5, 0), O_2 (0.6, 0.5, 0)
    p = model.parameters({"e_ball": 0.0})
    r = simulate(model, 1.0, p=p, q0=q0, qd0=np.zeros(6), rtol=1e-10, atol=1e-12)
    assert r.success and [i.law for i in r.impacts] == ["gdi"] and r.resting_final == [(1, "L1/ball")]
    assert min(model.contact_gaps(model.layout.reduce(q))[0] for q in r.q) >= -1e-12
    q0[3] += 0.05
    r = simulate(model, 1.0, p=p, q0=q0, qd0=np.zeros(6), rtol=1e-10, atol=1e-12)
    centres = np.array([model.contact_points(model.layout.reduce(q)).mean(axis=0) for q in r.q])
    assert r.success and r.resting_final == [(1, "L1/ball")] and r.n_sticks == 1 and r.n_slips == 0
    assert np.abs(centres[:, 0] - 0.05).max() < 5e-3 and abs(r.energy_drift) < 1e-9
    assert min(model.contact_gaps(model.layout.reduce(q))[0] for q in r.q) >= -1e-9
    smooth = model.parameters({"e_ball": 0.0, "friction_ball": 0.0})
    r = simulate(model, 1.0, p=smooth, q0=q0, qd0=np.zeros(6), rtol=1e-10, atol=1e-12)
    centre = model.contact_points(model.layout.reduce(r.q[-1])).mean(axis=0)
    assert r.success and r.resting_final == [] and centre[0] > 0.3 and centre[1] < 0.0     # slid off, falling
    assert min(model.contact_gaps(model.layout.reduce(q))[0] for q in r.q) >= -1e-9


def test_the_friction_keys_are_checked_and_named():
    """An obstacle's friction is the parameter friction_<name> after the obstacles' e (none where it is 0, so a
    frictionless scene keeps its layout); friction.links is a constant of the link pairs; values outside [0, 1e3]
    or not numbers are refused naming the key."""
    from codegen.errors import SceneError
    from codegen.scene import scene_from_dict
    data = {"name": "keys", "gravity": 0.0, "links": [{"length": 1.0, "mu": 1.0, "radius": 0.02}] * 3,
            "obstacles": [{"name": "ball", "center": [0, 3, 0], "radius": 0.3, "friction": 0.4},
                          {"name": "bar", "kind": "capsule", "a": [0, -3, -1], "b": [0, -3, 1], "radius": 0.1}],
            "friction": {"links": 0.2}}
    scene = scene_from_dict(data)
    assert scene.parameter_names()[-14:-11] == ["e_ball", "e_bar", "friction_ball"]   # then the geometry (4 + 7)
    assert scene.parameter_vector()[-12] == 0.4 and scene.link_friction == 0.2
    # the pair and its 4 end contacts, the ball's 3 links, the bar's 3 links and 4 joint points
    assert [c.friction for c in scene.rowless_contacts()] == [0.2] * 5 + [0.4] * 3 + [0.0] * 7
    for bad, message in ((-1.0, r"obstacles\[1\] \(ball\)\.friction: the Coulomb coefficient must be in \[0, 1000\]"),
                         ("x", r"obstacles\[1\] \(ball\)\.friction: expected a number")):
        with pytest.raises(SceneError, match=message):
            scene_from_dict({**data, "obstacles": [{**data["obstacles"][0], "friction": bad}]})
    with pytest.raises(SceneError, match=r"friction\.links: the Coulomb coefficient must be in \[0, 1000\], got 2000"):
        scene_from_dict({**data, "friction": {"links": 2e3}})
    assert scene_from_dict({**data, "friction": 0.5}).link_friction == 0.0      # a single number: the walls' only
