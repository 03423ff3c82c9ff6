"""Forward sensitivities through sliding on a rough wall at rest (gac_sens.c): a rod lying on a rough floor, both its
ends resting from the start, pushed along it at V0; it slides, decelerating by c_f g (the constrained flight with the
sliding friction -c_f lambda_n v_t/|v_t|: lambda_n through B, the direction, c_f), and comes to stick at
t = V0 / (c_f g) (the transition taken as the event |v_t| = friction_velocity, the velocities' projection onto the
stuck rows its map).  Against the closed form x(t) = V0 t - c_f g t^2 / 2 while it slides and x = V0^2 / (2 c_f g)
once stuck, and against central differences (the same contact events across the stencil)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate

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
