"""A resting contact never pulls: a transition at one instant (a point sticks, a contact lands at zero speed) can leave
another resting contact whose normal force, in the new mode, is negative.  Its event (the force falling from > 0 to
<= 0) then never comes, and a sliding point with a pulling force has its friction push it along: friction gives
energy.  The loop re-checks the resting contacts before any step where one pulls (it is released, a stuck point
beyond its cone slips).

The case is fuzz run 0-48/1: one heavy link (3.4 t, 1.5 m) wedged between the two x3 walls with gravity along -X2,
its upper end stuck on x3_max and its lower end sliding on x3_min.  At t = 0.953617 s its lower end is released,
the upper end slips, the lower end lands again at zero speed and the upper end sticks again: in that mode the
lower end's force is -30 kN, and before the re-check the run integrated it to t = 2 s with friction giving 25 J
(its loss falling at up to 1.3 kW from t = 0.955 s).  Here the friction's loss, integrated by the loop, must never
fall across the transitions and after them, and the energy balance must close."""
from __future__ import annotations

import numpy as np

from runtime.simulate import simulate
from studies import fuzz


def test_a_contact_left_pulling_by_a_transition_is_released():
    scene, model, run = fuzz.rebuild_case("0-48/1")
    losses = []
    for t_end in np.linspace(0.95, 1.02, 29):        # across the transitions at 0.953617 s and after
        result = simulate(model, t_end, p=run.p, q0=run.q0, qd0=run.qd0, **run.options)
        assert result.status == 0, result.message
        losses.append(result.loss_friction)
    tol = 1e-9 * result.energy_scale
    assert abs(result.energy_drift) <= 1e-6 * result.energy_scale
    assert losses[0] > 0.0
    assert np.all(np.diff(losses) >= -tol), np.diff(losses).min()

