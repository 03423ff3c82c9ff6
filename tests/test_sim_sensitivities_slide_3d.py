"""Forward sensitivities through sliding over both tangential axes of a rough wall at rest (gac_sens.c): a rod lying on
a rough floor, both ends resting from the start, thrown along the floor obliquely while it spins about the vertical,
so that each end's sliding direction v_t/|v_t| turns as it goes (its derivative (I - phi phi^T) dv_t / |v_t| in the
flight's tangent: dropping it fails every velocity direction, by up to the column's size); and the same rod dropped
almost upright, spinning, onto the floor, where its foot lands stuck and later slips over both axes (the slip
direction's derivative carried into the viscous band, and renewed where a stick test at a step's end gives it
again).  Against central differences of the final state."""
from __future__ import annotations

import math

import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate

from test_sim_sensitivities_rest import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
NAMES = ["q0[theta_0]", "qd0[X1]", "qd0[X3]", "qd0[theta_-1]", "g", "l_1", "friction_x2_min"]


def spinning_rod():
    """A rod (1 m, a small inertia about its own axis) lying along X1 on the floor (c_f = 0.3), moving at (1, 0, 0.5)
    m/s and spinning at 2 rad/s about the vertical."""
    return Scene(name="sens_slide_rod3d", links=(LineLink(1.0, 1.0, (0.01, 0.0, 0.0)),),
                 walls=(Wall("x2_min", 0.0, 0.0, friction=0.3),),
                 q0=(-math.pi / 2, 0.0, math.pi / 2, 0.0, 0.0, 0.0), qd0=(2.0, 0.0, 0.0, 1.0, 0.0, 0.5))


@pytest.fixture(scope="module")
def rod(compiled):
    return compiled(spinning_rod(), tangent=True)


@pytest.mark.parametrize("t_end", [0.2, 0.3])
def test_sliding_over_two_axes_matches_central_differences(rod, t_end):
    r = simulate(rod, t_end, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O2/x2_min", "rest")]
    central_differences(rod, t_end, NAMES, r.sensitivities.matrix, **TIGHT)


def test_a_slip_over_two_axes_matches_central_differences(rod):
    """Dropped 0.15 rad from upright from 0.1 m, moving at (0.05, 0, 0.03) m/s and spinning at 1 rad/s about the
    vertical, onto the floor with c_f = 0.5: it lands stuck at 0.143 s, topples about its foot, which slips at
    0.689 s over both axes and slides on.  At 0.8 s (seen: 2e-7 of the columns' size, the same with steps of 1e-5 and
    1e-6: the slip direction is renewed at each step's end in the viscous band, and those times move with the
    directions, a dependence not carried)."""
    p = rod.p.copy()
    p[rod.parameter_names.index("friction_x2_min")] = 0.5
    q0 = (-math.pi / 2, 0.0, 0.15, 0.0, 0.1, 0.0)
    qd0 = (1.0, 0.0, 0.0, 0.05, 0.0, 0.03)
    names = ["q0[theta_1]", "qd0[X1]", "qd0[X3]", "qd0[theta_-1]", "g", "l_1", "friction_x2_min"]
    r = simulate(rod, 0.8, p=p, q0=q0, qd0=qd0, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O1/x2_min", "rest"), ("O1/x2_min", "stick"),
                                                              ("O1/x2_min", "slip")]
    central_differences(rod, 0.8, names, r.sensitivities.matrix, p=p, q0=q0, qd0=qd0, **TIGHT)
