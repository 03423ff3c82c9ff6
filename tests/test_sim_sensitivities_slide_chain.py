"""Forward sensitivities through a point sliding on a rough wall while the chain above it turns (gac_sens.c): a 2-link
chain standing on its foot on a floor with c_f = 0.3, the foot pushed along it at 0.5 m/s, topples while the foot
slides (the normal force, and so the friction, change as it turns: lambda_n through B in the flight's tangent), then
its tip strikes the floor, which lifts the sliding foot off (the field before that impact with the foot sliding).
Against central differences of the final state, before and after that impact; the c_f column is not 0."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate

from test_sim_sensitivities_rest import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
NAMES = ["q0[theta_1]", "q0[theta_2]", "qd0[X1]", "qd0[theta_2]", "g", "l_2", "friction_x2_min"]


def sliding_chain():
    """Two links of 0.6 m, the first 0.3 rad from upright, the second bent back 0.9 rad, the foot O_1 on the rough
    floor (e = 0.5, c_f = 0.3) and moving at 0.5 m/s along it: at rest on the floor from the start and sliding; the
    tip O_3 strikes the floor at t ~ 0.406 s and the foot leaves it."""
    return Scene(name="sens_slide_chain",
                 links=(LineLink(0.6, 1.0, (0.0, 0.0, 0.0)), LineLink(0.6, 1.0, (0.0, 0.0, 0.0))),
                 walls=(Wall("x2_min", 0.0, 0.5, friction=0.3),),
                 q0=(-math.pi / 2, 0.0, 0.3, -0.9, 0.0, 0.0, 0.0), qd0=(0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0))


@pytest.fixture(scope="module")
def chain(compiled):
    return compiled(sliding_chain(), specialise=True, tangent=True)


@pytest.mark.parametrize("t_end", [0.3, 0.45])
def test_a_sliding_foot_under_a_turning_chain_matches_central_differences(chain, t_end):
    """At 0.3 s the foot slides (the chain turning above it); at 0.45 s the tip has struck the floor and lifted it
    off (the impact's field before it with the foot's sliding friction)."""
    r = simulate(chain, t_end, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    events = [(e.label, e.kind) for e in r.contact_events]
    assert events[0] == ("O1/x2_min", "rest")
    if t_end > 0.41:
        assert events[1:] == [("O1/x2_min", "release")]
        assert [c.label for c in r.impacts[-1].contacts] == ["O3/x2_min"]
    else:
        assert events[1:] == [] and not r.impacts
    assert np.abs(r.sensitivities.matrix[:, NAMES.index("friction_x2_min")]).max() > 1.0
    central_differences(chain, t_end, NAMES, r.sensitivities.matrix, **TIGHT)
