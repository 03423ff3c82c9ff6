"""Forward sensitivities through resting on a rough wall while the resting point sticks (gac_sens.c): a rod dropped
almost upright onto a rough floor (e = 0) lands stuck at its foot and topples about it, the foot held along all three
axes (the constrained dynamics' tangent and the projection after each step with the stuck point's tangential rows,
the landing's hold onto them).  Against central differences of the final state and the zero effect of c_f while
stuck; and with less friction the stuck foot slipping (the slip's event time, then sliding), and a landing that
slides on."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene
from codegen.scene import Wall
from runtime import simulate

from test_sim_sensitivities_rest import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
TILT, H0, U0, T = 0.15, 0.1, 0.05, 0.6     # rad from upright, m above the floor, m/s along it, s


def toppling_rod(friction: float = 2.0):
    """A uniform rod (1 m) tilted TILT from upright, its foot O_1 H0 above the rough floor (e = 0), moving at U0 along
    it: the foot lands stuck at t = sqrt(2 H0 / g) and the rod topples about it; with friction 2 the foot stays stuck
    past T (it slips at t ~ 0.71 s with friction 0.5)."""
    return Scene(name="sens_stick_rod", links=(LineLink(1.0, 1.0, (0.0, 0.0, 0.0)),),
                 walls=(Wall("x2_min", 0.0, 0.0, friction=friction),),
                 q0=(-math.pi / 2, 0.0, TILT, 0.0, H0, 0.0), qd0=(0.0, 0.0, 0.0, U0, 0.0, 0.0))


@pytest.fixture(scope="module")
def rod(compiled):
    return compiled(toppling_rod(), specialise=True, tangent=True)


def with_friction(model, friction):
    p = model.p.copy()
    p[model.parameter_names.index("friction_x2_min")] = friction
    return p


NAMES = ["q0[theta_1]", "q0[X2]", "qd0[X1]", "qd0[theta_1]", "g", "l_1", "friction_x2_min"]


def test_a_stuck_landing_matches_central_differences(rod):
    r = simulate(rod, T, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O1/x2_min", "stick")]
    central_differences(rod, T, NAMES, r.sensitivities.matrix, **TIGHT)


def test_the_stuck_foot_holds_its_place(rod):
    """While stuck, c_f has no effect (its column is 0); the foot stays where it landed, X1 = U0 t_land with
    t_land = sqrt(2 H0 / g) (so dX1/dqd0[X1] = t_land, dX1/dg = -U0 t_land / (2 g)), on the floor (dX2 = 0), and
    still (d qd[X1] = d qd[X2] = 0)."""
    r = simulate(rod, T, sensitivities=NAMES, **TIGHT)
    s = r.sensitivities
    assert s.valid, s.message
    t_land = math.sqrt(2 * H0 / 9.81)
    assert r.impacts[0].t == pytest.approx(t_land, rel=1e-10)
    assert np.abs(s.matrix[:, NAMES.index("friction_x2_min")]).max() == 0.0
    x1, x2 = s.rows.index("q[X1]"), s.rows.index("q[X2]")
    assert s.matrix[x1, NAMES.index("qd0[X1]")] == pytest.approx(t_land, rel=1e-8)
    assert s.matrix[x1, NAMES.index("g")] == pytest.approx(-U0 * t_land / (2 * 9.81), rel=1e-8)
    for row in (x2, s.rows.index("qd[X1]"), s.rows.index("qd[X2]")):
        assert np.abs(s.matrix[row]).max() < 1e-9


def test_a_slip_then_sliding_matches_central_differences(rod):
    """With friction 0.5 the stuck foot slips (|lambda_T| reaches c_f lambda_N: the slip's time from that event, the
    field continuous across it) and the rod topples on with its foot sliding: at 0.8 s, before it lies down, the final
    state against central differences (c_f's column is not 0 now), and the slip time's derivative along g against
    central differences of the slip times."""
    p = with_friction(rod, 0.5)
    r = simulate(rod, 0.8, p=p, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O1/x2_min", "stick"),
                                                              ("O1/x2_min", "slip")]
    assert np.abs(r.sensitivities.matrix[:, NAMES.index("friction_x2_min")]).max() > 0.1
    central_differences(rod, 0.8, NAMES, r.sensitivities.matrix, p=p, **TIGHT)
    g, h = rod.parameter_names.index("g"), 1e-6
    slip_times = []
    for sign in (1, -1):
        p1 = p.copy()
        p1[g] += sign * h
        slip_times.append(simulate(rod, 0.8, p=p1, **TIGHT).contact_events[2].t)
    slip = r.contact_events[2]
    assert slip.dt_dp["g"] == pytest.approx((slip_times[0] - slip_times[1]) / (2 * h), rel=1e-5)   # (seen 1e-6)


def test_a_landing_that_slides_on_matches_central_differences(rod):
    """With friction 0.1 and a fast foot the landing slides on (the impact's field after it with the sliding
    friction), and the rod topples with its foot sliding."""
    qd0 = rod.layout.expand(rod.qd0, velocity=True)
    qd0[3] = 1.0
    p = with_friction(rod, 0.1)
    r = simulate(rod, T, p=p, qd0=qd0, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest")]
    central_differences(rod, T, NAMES, r.sensitivities.matrix, p=p, qd0=qd0, **TIGHT)
