"""Forward sensitivities through a stuck point that takes part in an impact (gac_sens.c): a 2-link chain dropped onto a
rough floor (e = 0.5, c_f = 2) bounces on its foot until the foot lands stuck, topples about it, and its tip strikes
the floor, which lifts the stuck foot off (the field before that impact with the foot held along every axis).
Against central differences of the final state, before and after that impact."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate

from test_sim_sensitivities_rest import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
NAMES = ["q0[theta_1]", "q0[theta_2]", "qd0[X1]", "qd0[theta_2]", "g", "l_2", "e_x2_min", "friction_x2_min"]


def falling_chain():
    """Two links of 0.6 m, the first 0.3 rad from upright, the second bent back 0.9 rad, the foot O_1 5 cm above the
    rough floor and moving at 5 cm/s along it: 7 impacts of the foot (the last a landing, stuck at t ~ 0.305 s), then
    the tip O_3 strikes at t ~ 0.424 s and the foot leaves the floor."""
    return Scene(name="sens_stick_chain",
                 links=(LineLink(0.6, 1.0, (0.0, 0.0, 0.0)), LineLink(0.6, 1.0, (0.0, 0.0, 0.0))),
                 walls=(Wall("x2_min", 0.0, 0.5, friction=2.0),),
                 q0=(-math.pi / 2, 0.0, 0.3, -0.9, 0.0, 0.05, 0.0), qd0=(0.0, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0))


@pytest.fixture(scope="module")
def chain(compiled):
    return compiled(falling_chain(), specialise=True, tangent=True)


@pytest.mark.parametrize("t_end", [0.4, 0.5])
def test_a_stuck_foot_lifted_by_an_impact_matches_central_differences(chain, t_end):
    """At 0.4 s the foot is stuck (the chain toppling about it); at 0.5 s the tip has struck the floor and lifted it
    off: the impact's field before it holds the stuck foot's tangential row (with the normal row alone it fails).
    c_f enters nowhere (every impact on the floor sticks): its column is 0."""
    r = simulate(chain, t_end, sensitivities=NAMES, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    events = [(e.label, e.kind) for e in r.contact_events]
    assert events[:2] == [("O1/x2_min", "rest"), ("O1/x2_min", "stick")]
    if t_end > 0.45:
        assert events[2:] == [("O1/x2_min", "release")]
        assert [c.label for c in r.impacts[-1].contacts] == ["O3/x2_min"]
        assert r.impacts[-1].t == r.contact_events[2].t
    assert np.abs(r.sensitivities.matrix[:, NAMES.index("friction_x2_min")]).max() == 0.0
    central_differences(chain, t_end, NAMES, r.sensitivities.matrix, **TIGHT)


@pytest.mark.parametrize("friction", [1.5, 3.0])
def test_a_chain_toppling_onto_its_second_link_lands_it_flat_and_stuck(compiled, friction):
    """The chain standing on its stuck foot on a plastic rough floor (e = 0) topples: its tip strikes and lifts the
    foot, then link 2 lands flat, both its ends stuck through that impact (its two tangential rows the same row: the
    dependent one dropped, the impulses split another way for the same velocities); against central differences of
    the state at 0.6 s, before the foot comes down again.  (With c_f = 0.6 or 1 the tip, sliding after its strike,
    slows into the viscous band without sticking; the slip direction the stick test gives it at that step's end moves
    its friction by (1 - |v_t| / v_s) c_f lambda at a time the step sets, not an event: the sensitivities then agree
    with central differences to ~1e-4, as across a stick at a step's end.)"""
    scene = Scene(name="sens_topple_flat",
                  links=(LineLink(0.6, 1.0, (0.0, 0.0, 0.0)), LineLink(0.6, 1.0, (0.0, 0.0, 0.0))),
                  walls=(Wall("x2_min", 0.0, 0.0, friction=friction),),
                  q0=(-math.pi / 2, 0.0, 0.3, -0.9, 0.0, 0.0, 0.0), qd0=(0.0,) * 7)
    model = compiled(scene, specialise=True, tangent=True)
    names = ["q0[theta_1]", "q0[theta_2]", "g", "l_2", "friction_x2_min"]
    r = simulate(model, 0.6, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    flat = [i for i in r.impacts if sorted(c.label for c in i.contacts) == ["O2/x2_min", "O3/x2_min"]]
    assert len(flat) == 1 and all(abs(c.impulse_t[0]) < friction * c.impulse for c in flat[0].contacts)
    central_differences(model, 0.6, names, r.sensitivities.matrix, **TIGHT)
