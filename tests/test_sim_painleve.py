"""The Painleve paradox of sliding friction resolved by a tangential impact ("impact without collision"): Glocker's rod
sliding on a rough floor reaches the dynamic jam, where its normal compliance with sliding passes through 0, and
takes there the frictional impact law's non-trivial solution; a rod started sliding inside the paradox takes it at
the start.  Everything is checked against an independent derivation of the rod's sliding phase (solve_ivp) and a
closed form of the impact law for one contact (the 2x2 contact-space inverse inertia)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from codegen.scene import scene_from_dict
from runtime import simulate
from conftest import quick_model

# Glocker's rod: mass m, half-length s, J = m s^2 / 3 about its centre, g = 10, c_f = 5/3, 31 deg, sliding at 30 m/s
M, S, G_ROD, C_F = 1.0, 1.0, 10.0, 5.0 / 3.0
J_ROD = M * S * S / 3.0
THETA0, V0 = math.radians(31.0), -30.0


def lean_scene(name, length, mass, gravity, c_f, theta, v):
    """A uniform slender rod (length, mass) with its lower end O_1 on a rough floor, leaning at theta from the floor
    towards +X1 (its upper end at +X1), O_1 sliding at v along X1 (v < 0: the lower end leads)."""
    data = {"name": name, "gravity": gravity, "links": [{"length": length, "mu": mass / length, "J": [0.0, 0.0, 0.0]}],
            "walls": {"x2_min": 0.0}, "restitution": 0.0, "friction": c_f,
            "initial": {"q": [-math.pi / 2, 0.0, math.atan2(-math.cos(theta), math.sin(theta)), 0.0, 0.0, 0.0],
                        "qd": [0.0, 0.0, 0.0, v, 0.0, 0.0]}}
    return scene_from_dict(data)


# The rod's own mechanics, written out here.  Centre c, angle theta from the floor, O_1 = c + r with
# r = -s (cos theta, sin theta).  A force P at O_1: m c'' = P + m g, J theta'' = r x P.  O_1's velocity is
# c' + theta' (-r_y, r_x), so the contact-space inverse inertia of the (normal X2, tangential X1) directions is
#     W = [[1/m + r_x^2/J, -r_x r_y/J], [-r_x r_y/J, 1/m + r_y^2/J]].
# Sliding with O_1 moving towards -X1 (the lower end leading): P = (c_f lambda, lambda), and O_1 held on the floor,
# y_c - s sin(theta) = 0, twice differentiated, gives B lambda = g - s sin(theta) theta'^2 with
#     B = 1/m + s^2/J (cos^2 theta - c_f sin theta cos theta) = W_NN + c_f W_NT    (the compliance with sliding),
# which for J = m s^2/3 and c_f = 5/3 vanishes where tan^2 theta - 5 tan theta + 4 = 0: at 45 deg (and 75.96 deg).

def compliance(theta, m=M, s=S, J=J_ROD, c_f=C_F):
    return 1 / m + s * s / J * (math.cos(theta) ** 2 - c_f * math.sin(theta) * math.cos(theta))


def contact_inverse_inertia(theta, m, s, J):
    rx, ry = -s * math.cos(theta), -s * math.sin(theta)
    return np.array([[1 / m + rx * rx / J, -rx * ry / J], [-rx * ry / J, 1 / m + ry * ry / J]]), np.array([rx, ry])


def sliding(t, y):
    """The sliding phase: y = (theta, theta', x_c, x_c')."""
    theta, w = y[0], y[1]
    lam = (G_ROD - S * math.sin(theta) * w * w) / compliance(theta)
    return [w, lam * S * (C_F * math.sin(theta) - math.cos(theta)) / J_ROD, y[3], C_F * lam / M]


def jam(t, y):
    return compliance(y[0]) - 1e-9          # B within 1e-9 of 0: some 1e-10 s before the jam (B' ~ 11 / s there)


jam.terminal = True


def sliding_reference():
    y0 = [THETA0, 0.0, S * math.cos(THETA0), V0]
    return solve_ivp(sliding, (0.0, 2.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, events=jam, dense_output=True)


def rod_state(q, qd):
    """(theta, theta', O_1's velocity (X1, X2), the centre's velocity) from the full layout of Eq. 13."""
    theta, w = q[2] + math.pi / 2, qd[2]
    v1 = np.array([qd[3], qd[4]])
    r = np.array([-S * math.cos(theta), -S * math.sin(theta)])
    return theta, w, v1, v1 - w * np.array([-r[1], r[0]])


@pytest.fixture(scope="module")
def glocker():
    return quick_model(lean_scene("glocker_rod", 2 * S, M, G_ROD, C_F, THETA0, V0))


def test_the_rod_leans_as_derived(glocker):
    """The scene's rod is the derivation's: O_2 = O_1 + 2 s (cos theta, sin theta), and its compliance with sliding
    starts positive (no paradox at 31 deg) and changes sign at 45 deg."""
    points = glocker.contact_points(glocker.q0)
    assert np.allclose(points[1] - points[0], [2 * S * math.cos(THETA0), 2 * S * math.sin(THETA0), 0.0], atol=1e-14)
    assert compliance(THETA0) > 0.99
    assert compliance(math.radians(45.0)) == pytest.approx(0.0, abs=1e-14)
    assert compliance(math.radians(44.9)) > 0 > compliance(math.radians(45.1))


@pytest.mark.parametrize("method, rtol, atol", [("dopri5", 1e-10, 1e-12), ("dop853", 1e-12, 1e-12)])
def test_glockers_rod_jams_and_takes_a_tangential_impact(glocker, method, rtol, atol):
    ref = sliding_reference()
    assert ref.status == 1                                  # the jam event, before anything else
    t_jam, (theta_jam, w_jam, xc_jam, vc_jam) = ref.t_events[0][0], ref.y_events[0][0]
    lam0 = G_ROD / compliance(THETA0)
    lam_jam = (G_ROD - S * math.sin(theta_jam) * w_jam ** 2) / compliance(theta_jam)
    # the jam: B -> 0 while sliding, the normal force growing without bound, its numerator vanishing with B
    assert theta_jam == pytest.approx(math.pi / 4, abs=1e-9)
    assert lam_jam > 1e3 * lam0 and abs(G_ROD - S * math.sin(theta_jam) * w_jam ** 2) < 1e-3 * G_ROD
    assert vc_jam + S * math.sin(theta_jam) * w_jam < -9.0                 # still sliding fast

    t = np.array([0.4, 0.8])
    result = simulate(glocker, 1.0, method, t_eval=t, rtol=rtol, atol=atol)
    assert result.success, result.message
    for k, tk in enumerate(t):                             # the sliding phase as derived
        theta, w, _, _ = rod_state(result.q[k], result.qd[k])
        ref_theta, ref_w, ref_xc, _ = ref.sol(tk)
        assert theta == pytest.approx(ref_theta, abs=1e-7) and w == pytest.approx(ref_w, abs=1e-6)
        assert result.q[k][3] + S * math.cos(theta) == pytest.approx(ref_xc, abs=1e-7)

    # one impact, the tangential one, at the jam
    assert result.n_tangential_impacts == 1 and len(result.impacts) == 1
    impact = result.impacts[0]
    assert impact.law == "gdi-tangential" and "tangential impact" in result.message
    assert impact.t == pytest.approx(t_jam, abs=1e-6)
    theta, w, v1, vc = rod_state(impact.q, impact.qd_before)
    assert theta == pytest.approx(math.pi / 4, abs=1e-6) and theta == pytest.approx(theta_jam, abs=1e-6)
    assert abs(v1[1]) < 1e-9 and v1[0] == pytest.approx(vc_jam + S * math.sin(theta_jam) * w_jam, abs=1e-5)

    # the impact law in closed form: the stick impulse L = -W^-1 gamma-, gamma- = (0, v) (normal, tangential)
    W, r = contact_inverse_inertia(theta, M, S, J_ROD)
    gamma = np.array([0.0, v1[0]])
    L = -np.linalg.solve(W, gamma)
    assert L[0] > 0 and abs(L[1]) == pytest.approx(C_F * L[0], rel=1e-6)   # at the jam: on the cone's edge
    (contact,) = impact.contacts
    assert (contact.point, contact.wall) == (1, "x2_min")
    assert contact.impulse == pytest.approx(L[0], rel=1e-6) and contact.impulse_t[0] == pytest.approx(L[1], rel=1e-6)
    P = np.array([L[1], L[0]])                               # (X1, X2)
    vc_plus = vc + P / M
    w_plus = w + (r[0] * P[1] - r[1] * P[0]) / J_ROD
    v1_plus = vc_plus + w_plus * np.array([-r[1], r[0]])
    assert np.abs(v1_plus).max() < 1e-12                     # the closed form sticks O_1
    _, w_after, v1_after, _ = rod_state(impact.q, impact.qd_after)
    assert w_after == pytest.approx(w_plus, rel=1e-6) and np.abs(v1_after).max() < 1e-6
    T_before = 0.5 * M * vc @ vc + 0.5 * J_ROD * w * w
    T_after = 0.5 * M * vc_plus @ vc_plus + 0.5 * J_ROD * w_plus ** 2
    assert T_before - T_after == pytest.approx(-0.5 * L[1] * v1[0], rel=1e-9)   # GDI: T+ - T- = L . (g+ + g-)/2
    assert impact.energy_before - impact.energy_after == pytest.approx(T_before - T_after, rel=1e-6)
    assert impact.energy_after < impact.energy_before                          # no energy gain

    # after: held at the pivot the rod would need a pulling force, m (a_y + g) < 0, so it lifts off there
    theta_dd = -M * G_ROD * S * math.cos(theta) / (J_ROD + M * S * S)
    a_y = theta_dd * S * math.cos(theta) - w_plus ** 2 * S * math.sin(theta)
    assert M * (a_y + G_ROD) < 0
    assert [(e.kind, e.point) for e in result.contact_events] == [("rest", 1), ("release", 1)]
    assert result.contact_events[1].t == impact.t
    assert abs(result.energy_drift) < 1e-6


def stick_or_lift(v):
    """The rod of tests/test_sim_friction.py (1 m, 1 kg, tan theta = 2, c_f = 2): at the start inside the paradox."""
    theta = math.atan(2.0)
    return theta, lean_scene("painleve_start", 1.0, 1.0, 9.81, 2.0, theta, v)


@pytest.mark.parametrize("v, sticks", [(-1.0, True), (-5.0, False)])
def test_a_start_inside_the_paradox_takes_the_tangential_impact_at_once(v, sticks):
    """Started sliding where B < 0 (no consistent normal force), the run takes the tangential impact at t = 0: the
    closed-form stick impulse, inside the cone; slow, the rod then pivots on its stuck end (its pivot force pushes and
    stays in the cone); fast, the pivot would pull and the rod lifts off."""
    theta, scene = stick_or_lift(v)
    m, s, g, c_f = 1.0, 0.5, 9.81, 2.0
    J = m * (2 * s) ** 2 / 12
    assert compliance(theta, m, s, J, c_f) < 0
    result = simulate(quick_model(scene), 0.2, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert result.n_tangential_impacts == 1
    impact = result.impacts[0]
    assert impact.t == 0.0 and impact.law == "gdi-tangential"
    W, r = contact_inverse_inertia(theta, m, s, J)
    L = -np.linalg.solve(W, [0.0, v])
    assert L[0] > 0 and abs(L[1]) < c_f * L[0]
    assert impact.contacts[0].impulse == pytest.approx(L[0], rel=1e-12)
    assert impact.contacts[0].impulse_t[0] == pytest.approx(L[1], rel=1e-12)
    assert impact.energy_before - impact.energy_after == pytest.approx(-0.5 * L[1] * v, rel=1e-9)
    w = (r[0] * L[0] - r[1] * L[1]) / J                      # theta' after (the rod starts at rest but for v)
    theta_dd = -m * g * s * math.cos(theta) / (J + m * s * s)
    a = theta_dd * np.array([-r[1], r[0]]) * -1 - w * w * -r  # the centre's acceleration about the stuck end
    lam_n, lam_t = m * (a[1] + g), m * a[0]
    assert impact.qd_after[2] == pytest.approx(w, rel=1e-9)
    if sticks:
        assert lam_n > 0 and abs(lam_t) < c_f * lam_n
        assert result.n_sticks == 1 and [(e.kind, e.t) for e in result.contact_events] == [("rest", 0.0), ("stick", 0.0)]
    else:
        assert lam_n < 0
        assert [(e.kind, e.t) for e in result.contact_events] == [("rest", 0.0), ("release", 0.0)]


def test_an_indeterminate_start_leaves_the_floor_with_the_least_normal_force():
    """Glocker's rod at 60 deg (B = 1 + 3 (cos^2 - 5/3 sin cos) = -0.415 < 0), its lower end sliding at 3 m/s ahead
    of it and at rest along the normal, the rod turning at theta' = 4 rad/s.  Its end's normal acceleration without a
    force is a_N = -g + s sin(theta) theta'^2 = +3.86 m/s^2 (theta'' = 0 free: gravity acts at the centre), and held
    sliding, B lambda = g - s sin(theta) theta'^2 gives lambda = 9.30 N > 0: the contact problem 0 <= lambda _|_
    a_N >= 0 has two solutions (indeterminacy, not inconsistency).  The run takes the one with the least normal
    force, lambda = 0, from the start (the start's rest rule holds only contacts pressed into their walls): no
    impact, no tangential impact, and the rod flies freely, its end's height y = s sin(theta0) + s cos(theta0)
    theta' t - g t^2 / 2 - s sin(theta0 + theta' t) > 0 in closed form (held with lambda = 9.30 N it would stay 0)."""
    theta, w, v = math.radians(60.0), 4.0, -3.0
    B = compliance(theta)
    a_free = -G_ROD + S * math.sin(theta) * w * w
    lam = (G_ROD - S * math.sin(theta) * w * w) / B
    assert B < 0 and a_free > 0 and lam > 0                   # indeterminate: lift-off and sliding both solve it
    scene = dataclasses.replace(lean_scene("painleve_indeterminate", 2 * S, M, G_ROD, C_F, theta, v),
                                qd0=(0.0, 0.0, w, v, 0.0, 0.0))
    t = np.array([0.01, 0.03, 0.05])
    result = simulate(quick_model(scene), 0.05, t_eval=t, rtol=1e-11, atol=1e-12)
    assert result.success, result.message
    assert result.n_tangential_impacts == 0 and not result.impacts
    assert all(e.kind != "rest" for e in result.contact_events)
    for k, tk in enumerate(t):
        height = S * math.sin(theta) + S * math.cos(theta) * w * tk - 0.5 * G_ROD * tk * tk - S * math.sin(theta + w * tk)
        assert height > 1e-4
        assert result.q[k][4] == pytest.approx(height, abs=1e-9)
