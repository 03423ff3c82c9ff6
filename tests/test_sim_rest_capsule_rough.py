"""A sliding point wedged by a stuck one in the Painleve paradox: the normal force of the sliding point, solved with
the stuck point's tangential rows held, passes through a pole where the held system's Schur complement on the normal
forces stops being a P-matrix.  Taken for a zero, that pole released the point, which landed again picoseconds later
(its free acceleration drives it into its wall), stuck the other one, and so on: a chatter of releases and landings
at 0.1 microsecond intervals that burnt the run's budget.

The case is fuzz run 0-33/4: eight links with capsules on rough walls; from t = 0.24678 s link 5 is wedged between the
two x1 walls (O5 on x1_max stuck, O6 on x1_min sliding slower than friction_velocity). Before the paradox was tested
with stuck points, the run released and landed O5 / O6 56 times in 8e-6 s (O5 37, O6 19) and used its 20 s budget at t
= 0.2468 s. Now no contact is released there; the steps keep meeting the paradox's edge without reaching it (the
motion follows it with unbounded forces), and the run stops with GAC_ERR_PAINLEVE_STALL after some 4,000 steps (its
count of steps rejected at the edge, not a wall-time budget, ends it). The checks on
the way are the study's own (fuzz.check_run, in numpy from the samples: no penetration beyond tolerance, the energy
balance, friction only taking energy)."""
from __future__ import annotations


from runtime.simulate import simulate
from studies import fuzz

WEDGED = 0.24678            # s: link 5 wedged between the x1 walls from here on


def test_a_wedged_sliding_point_is_not_released_at_a_pole_and_the_stall_stops_the_run():
    scene, model, run = fuzz.rebuild_case("0-33/4")
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, max_wall_time=600.0, **run.options)
    assert result.status == -1
    assert "edge of the Painleve paradox" in result.message, result.message
    assert result.t_final > WEDGED
    assert result.n_steps < 20_000, result.n_steps               # stopped by its count, not crawling (no budget)
    late = [e for e in result.contact_events if e.t > WEDGED]
    assert not any(e.kind == "release" for e in late), late      # no release at the pole
    assert fuzz.check_run(model, run, result, 0.0, fuzz.BUDGET) == []
    assert result.loss_friction >= 0.0
    assert abs(result.energy_drift) <= 1e-6 * result.energy_scale

