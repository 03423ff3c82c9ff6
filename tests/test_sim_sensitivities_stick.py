"""Forward sensitivities through resting on a rough wall while the resting point sticks (gac_sens.c): a rod dropped
almost upright onto a rough floor (e = 0) lands stuck at its foot and topples about it, the foot held along all three
axes (the constrained dynamics' tangent and the projection after each step with the stuck point's tangential rows,
the landing's hold onto them).  Against central differences of the final state and the zero effect of c_f while
stuck; and the verdicts where it is not followed: the stuck foot slipping, and a landing that slides on."""
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


def test_a_slip_ends_the_sensitivities(rod):
    """With friction 0.5 the stuck foot slips (|lambda_T| reaches c_f lambda_N): a stick-slip transition, not
    followed; the sensitivities are valid up to it."""
    p = with_friction(rod, 0.5)
    r = simulate(rod, 0.9, p=p, sensitivities=["g"], **TIGHT)
    assert r.success
    slip = [e for e in r.contact_events if e.kind == "slip"]
    assert slip and r.sensitivities.t_event == slip[0].t
    assert r.sensitivity_status.startswith("a stick-slip transition on a rough wall")
    assert "O1/x2_min" in r.sensitivity_message
    assert np.all(np.isnan(r.sensitivities.matrix))
    before = simulate(rod, 0.5 * (T + slip[0].t) - 0.05, p=p, sensitivities=["g"], **TIGHT)
    assert before.sensitivities.valid


def test_a_landing_that_slides_ends_the_sensitivities(rod):
    """With friction 0.1 and a fast foot the landing slides on: sliding friction at rest is not followed."""
    qd0 = rod.layout.expand(rod.qd0, velocity=True)
    qd0[3] = 1.0
    r = simulate(rod, T, p=with_friction(rod, 0.1), qd0=qd0, sensitivities=["g"], **TIGHT)
    assert r.success and [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest")]
    assert r.sensitivity_status.startswith("resting contact sliding on a rough wall")
    assert r.sensitivities.t_event == r.impacts[0].t
