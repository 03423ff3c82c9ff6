"""Forward sensitivities through sliding on a rough wall at rest (gac_sens.c): a rod lying on a rough floor, both its
ends resting from the start, pushed along it at V0; it slides, decelerating by c_f g (the constrained flight with the
sliding friction -c_f lambda_n v_t/|v_t|: lambda_n through B, the direction, c_f), and comes to stick at
t = V0 / (c_f g) (the transition taken as the event |v_t| = friction_velocity, the velocities' projection onto the
stuck rows its map).  Against the closed form x(t) = V0 t - c_f g t^2 / 2 while it slides and x = V0^2 / (2 c_f g)
once stuck, and against central differences (the same contact events across the stencil).  At an impact by the
frictional law: the rod dropped flat while moving along its axis, both ends sliding through the impact on the same
tangential row (the law's A singular, its differential not), and stuck at both ends (the same row twice, the
dependent one dropped as the held set drops it), against closed forms; and the shipped incline scene's whole run
(30 impacts) against central differences."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall, load_scene
from runtime import simulate

from test_sim_sensitivities import central_differences as whole_run_differences
from test_sim_sensitivities_rest import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
CF, V0, G = 0.3, 1.0, 9.81
NAMES = ["q0[X1]", "qd0[X1]", "g", "l_1", "friction_x2_min"]


def lying_rod():
    """A uniform rod (1 m) lying along X1 on the floor (c_f = CF, e = 0), moving at V0 along it."""
    return Scene(name="sens_slide_rod", links=(LineLink(1.0, 1.0, (0.0, 0.0, 0.0)),),
                 walls=(Wall("x2_min", 0.0, 0.0, friction=CF),),
                 q0=(-math.pi / 2, 0.0, math.pi / 2, 0.0, 0.0, 0.0), qd0=(0.0, 0.0, 0.0, V0, 0.0, 0.0))


@pytest.fixture(scope="module")
def rod(compiled):
    return compiled(lying_rod(), specialise=True, tangent=True)


def column(run, row, name):
    s = run.sensitivities
    return s.matrix[s.rows.index(row), NAMES.index(name)]


def test_sliding_matches_the_closed_form(rod):
    """While it slides (T = 0.2 s < V0 / (c_f g)): dx/dv0 = T, dx/dc_f = -g T^2/2, dx/dg = -c_f T^2/2, dx/dl = 0;
    the velocity's: 1, -g T, -c_f T, 0.  The c_f column is not 0 now."""
    T = 0.2
    r = simulate(rod, T, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O2/x2_min", "rest")]
    assert rod.layout.reduce(r.q_final)[1] == pytest.approx(V0 * T - CF * G * T * T / 2, rel=1e-12)
    expected = {"q[X1]": {"q0[X1]": 1.0, "qd0[X1]": T, "g": -CF * T * T / 2, "l_1": 0.0,
                          "friction_x2_min": -G * T * T / 2},
                "qd[X1]": {"q0[X1]": 0.0, "qd0[X1]": 1.0, "g": -CF * T, "l_1": 0.0, "friction_x2_min": -G * T}}
    for row, values in expected.items():
        for name, value in values.items():
            assert column(r, row, name) == pytest.approx(value, rel=1e-9, abs=1e-12), (row, name)
    for row in ("q[X2]", "q[theta_1]", "qd[X2]", "qd[theta_1]"):
        assert np.abs(r.sensitivities.matrix[r.sensitivities.rows.index(row)]).max() < 1e-12
    central_differences(rod, T, NAMES, r.sensitivities.matrix, **TIGHT)


def test_coming_to_stick_matches_the_closed_form(rod):
    """Past the stop (t_stop = (V0 - v_s) / (c_f g), v_s = friction_velocity, where it sticks): X1 = (V0^2 - v_s^2) /
    (2 c_f g) to the viscous band's share (below 1e-6 of it), so dX1/dv0 = V0 / (c_f g), dX1/dc_f = -X1 / c_f,
    dX1/dg = -X1 / g, and the velocities' derivatives 0; the stick's dt/dv0 = 1 / (c_f g) (to 1e-4: the step's end
    where it sticks lies a little inside the viscous band).  Taking the stick at the
    step's end as a fixed time (no saltation term) would give dX1/dv0 = t_stop, 1e-3 off.  Central differences of
    the final state with a step of 1e-5 (the stick lands on a step's end, so the differences carry noise of about
    1e-7 / step)."""
    T = 0.5
    r = simulate(rod, T, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O2/x2_min", "rest"),
                                                              ("O1/x2_min", "stick"), ("O2/x2_min", "stick")]
    stick = r.contact_events[2]
    assert stick.t == pytest.approx(V0 / (CF * G), rel=2e-3)
    assert stick.dt_dp["qd0[X1]"] == pytest.approx(1 / (CF * G), rel=1e-4)   # (at the step's end, |v_t| < v_s)
    x_stop = V0 ** 2 / (2 * CF * G)
    assert rod.layout.reduce(r.q_final)[1] == pytest.approx(x_stop, rel=1e-5)
    assert column(r, "q[X1]", "qd0[X1]") == pytest.approx(V0 / (CF * G), rel=1e-6)
    assert column(r, "q[X1]", "friction_x2_min") == pytest.approx(-x_stop / CF, rel=1e-5)
    assert column(r, "q[X1]", "g") == pytest.approx(-x_stop / G, rel=1e-5)
    assert column(r, "q[X1]", "q0[X1]") == pytest.approx(1.0, rel=1e-12)
    for row in ("qd[X1]", "qd[X2]", "qd[theta_1]"):
        assert np.abs(r.sensitivities.matrix[r.sensitivities.rows.index(row)]).max() < 1e-12
    central_differences(rod, T, NAMES, r.sensitivities.matrix, step=1e-5, **TIGHT)


def test_a_rod_landing_flat_and_sliding_at_both_ends_matches_the_closed_form(rod):
    """The rod dropped flat from h = 0.3 m while moving along its axis at 2 m/s onto the floor with e = 0.5: both
    ends strike at once and slide through the impact (each tangential impulse c_f times its normal one), so their
    two tangential rows are the same row (the law's A singular, the cone fixing each tangential impulse); it leaves
    the floor at e v* up and at vx - c_f (1 + e) v* along it (v* = sqrt(2 g h)).  At T = 0.4 s (before it lands
    again): X1 = vx T - c_f (1 + e) v* tau, X2 = e v* tau - g tau^2 / 2 (tau = T - t*, t* = v* / g), so
    dX1/dc_f = -(1 + e) v* tau, dX1/de = -c_f v* tau, dX1/dg = -c_f (1 + e) v* T / (2 g), dX2/de = v* tau and
    dt*/dh = 1 / v*; against central differences too."""
    H, VX, E, T = 0.3, 2.0, 0.5, 0.4
    names = ["q0[X2]", "qd0[X1]", "g", "e_x2_min", "friction_x2_min"]
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, 0.0, H, 0.0])
    qd0 = np.array([0.0, 0.0, 0.0, VX, 0.0, 0.0])
    p = rod.parameters({"e_x2_min": E})
    r = simulate(rod, T, p=p, q0=q0, qd0=qd0, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    (impact,) = r.impacts
    assert sorted(c.label for c in impact.contacts) == ["O1/x2_min", "O2/x2_min"] and impact.law == "gdi"
    for contact in impact.contacts:
        assert contact.impulse_t[0] == pytest.approx(-CF * contact.impulse, rel=1e-9)
    v, t_hit = math.sqrt(2 * G * H), math.sqrt(2 * H / G)
    tau = T - t_hit
    s = r.sensitivities
    expected = {("q[X1]", "friction_x2_min"): -(1 + E) * v * tau, ("q[X1]", "e_x2_min"): -CF * v * tau,
                ("q[X1]", "g"): -CF * (1 + E) * v * T / (2 * G), ("q[X1]", "qd0[X1]"): T,
                ("q[X2]", "e_x2_min"): v * tau, ("qd[X1]", "friction_x2_min"): -(1 + E) * v}
    for (row, name), value in expected.items():
        assert s.matrix[s.rows.index(row), names.index(name)] == pytest.approx(value, rel=1e-8), (row, name)
    assert impact.dt_dp["q0[X2]"] == pytest.approx(1 / v, rel=1e-8)
    whole_run_differences(rod, T, p, q0, qd0, names, s.matrix, **TIGHT)


def test_the_shipped_incline_carries_its_sensitivities_through_its_whole_run(compiled):
    """The shipped `incline` scene (a 3-link chain thrown down a rough incline, e = 0.3, c_f = 0.6): 30 impacts by the
    frictional law in 2 s, link 1 landing flat and sliding at both ends at 0.951 s among them, points coming to rest,
    sliding and leaving; every event differentiated, the final state against central differences."""
    scene = load_scene(Path(__file__).parents[1] / "codegen" / "scenes" / "incline.toml")
    model = compiled(scene, tangent=True)
    names = ["g", "qd0[theta_1]"]
    q0, qd0 = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float)
    r = simulate(model, 2.0, q0=q0, qd0=qd0, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert len(r.impacts) >= 20 and any(e.kind == "release" for e in r.contact_events)
    flat = [i for i in r.impacts if sorted(c.label for c in i.contacts) == ["O1/x2_min", "O2/x2_min"]]
    assert flat and all(abs(c.impulse_t[0]) == pytest.approx(0.6 * c.impulse, rel=1e-9) for c in flat[0].contacts)
    whole_run_differences(model, 2.0, model.p.copy(), q0, qd0, names, r.sensitivities.matrix, **TIGHT)


def test_a_rod_landing_flat_and_stuck_at_both_ends_matches_the_closed_form(rod):
    """The rod dropped flat from h = 0.3 m moving along its axis at 0.2 m/s onto the floor with e = 0.5 and c_f = 3:
    both ends stick through the impact (xi_T = gamma+_T + e gamma-_T = 0 along their one tangential row, the same row
    twice: the law's rows dependent, no slide to fix the split; the rows dependent on the others drop out, the
    impulse split another way for the same velocities), so it leaves at e v* up and at -e vx along it.  At T = 0.4 s:
    X1 = vx t* - e vx tau, so dX1/dvx = t* - e tau and dX1/de = -vx tau - e vx dtau/de (= -vx tau, t* not moving with
    e), X2 = e v* tau - g tau^2 / 2; against central differences too."""
    H, VX, E, T, C_F = 0.3, 0.2, 0.5, 0.4, 3.0
    names = ["q0[X2]", "qd0[X1]", "g", "e_x2_min", "friction_x2_min"]
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, 0.0, H, 0.0])
    qd0 = np.array([0.0, 0.0, 0.0, VX, 0.0, 0.0])
    p = rod.parameters({"e_x2_min": E, "friction_x2_min": C_F})
    r = simulate(rod, T, p=p, q0=q0, qd0=qd0, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    (impact,) = r.impacts
    assert sorted(c.label for c in impact.contacts) == ["O1/x2_min", "O2/x2_min"] and impact.law == "gdi"
    assert sum(c.impulse_t[0] for c in impact.contacts) == pytest.approx(-(1 + E) * VX, rel=1e-9)   # m = 1
    assert all(abs(c.impulse_t[0]) < C_F * c.impulse for c in impact.contacts)
    v, t_hit = math.sqrt(2 * G * H), math.sqrt(2 * H / G)
    tau = T - t_hit
    s = r.sensitivities
    expected = {("q[X1]", "qd0[X1]"): t_hit - E * tau, ("q[X1]", "e_x2_min"): -VX * tau,
                ("q[X1]", "friction_x2_min"): 0.0, ("qd[X1]", "qd0[X1]"): -E, ("q[X2]", "e_x2_min"): v * tau}
    for (row, name), value in expected.items():
        assert s.matrix[s.rows.index(row), names.index(name)] == pytest.approx(value, rel=1e-8, abs=1e-12), (row, name)
    whole_run_differences(rod, T, p, q0, qd0, names, s.matrix, **TIGHT)
