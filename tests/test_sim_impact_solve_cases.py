"""Fuzz study runs that stopped where the impact law was not solved to round-off, and now go on: an elastic corner
struck back and forth for 155 rounds (the rounds' arithmetic, now in long double, had gained 3.6e-10 of T), frictional
rounds that ended within their own tolerance but left a contact approaching beyond what the post-conditions allow (a
wall, and a link pair after a plastic closing round: now closed by plastic normal strikes), and a first frictional
round at round-off speed over dependent rows (a point in a corner, 9 rows for 6 coordinates) that no solve met to
GAC_FRICTION_RESIDUAL_MAX, and an impulse left below zero by round-off.  Each run is rebuilt from its case as the study draws it, and every impact's physics is
checked here from the model's mass matrix and contact Jacobian, independently of the library's own measures: the
kinetic energy does not grow, the impulses push and lie in Coulomb's cone, and no contact is left approaching."""
from __future__ import annotations

import numpy as np
import pytest

from runtime.simulate import simulate
from studies import fuzz
from conftest import wall_friction

EPS = np.finfo(float).eps


def _contact_index(model, contact) -> int:
    """The model's index of an impact's contact: a wall's (point, wall), a link pair's (i, j), an obstacle's."""
    for k, (point, where) in enumerate(model.contacts):
        if contact.kind == "wall" and point == contact.point and getattr(where, "name", None) == contact.wall:
            return k
        if contact.kind == "link" and (getattr(where, "i", None), getattr(where, "j", None)) == tuple(contact.links):
            return k
        if contact.kind == "obstacle" and getattr(where, "obstacle", None) is not None \
                and contact.wall == f"L{where.i}/{where.obstacle.name}":
            return k
    raise AssertionError(f"no contact {contact.label}")


def _normal(model, q, p, c) -> np.ndarray:
    """Contact c's generalised normal: a wall's Jacobian row along its inward normal, else J^T n (link pairs)."""
    point, where = model.contacts[c]
    if c < len(model.layout.contacts) and hasattr(where, "axis"):
        sign = 1.0 if where.name.endswith("min") else -1.0
        return sign * model.contact_jacobian(q, p)[model.contact_rows.index((point, where.axis))]
    return model.contact_normal(q, c, p)


def check_impacts(scene, model, run, result, t_stop: float) -> int:
    """Every impact's physics from the dense M and the contacts' normals; returns how many impacts came after the
    time the run used to stop at."""
    layout, p = model.layout, run.p
    friction = wall_friction(scene, p)
    later = 0
    for impact in result.impacts:
        q, before, after = (layout.reduce(x) for x in (impact.q, impact.qd_before, impact.qd_after))
        M = model.mass_matrix(q, p)
        T0 = 0.5 * before @ M @ before
        # T+ - T- = (qd+ - qd-) M (qd+ + qd-) / 2, and what evaluating it with the dense M resolves
        change, total = after - before, after + before
        dT = 0.5 * change @ M @ total
        noise = 8 * model.nq * EPS * (np.abs(change) @ np.abs(M) @ np.abs(total) + np.abs(before) @ np.abs(M)
                                      @ np.abs(before))
        assert dT <= 10 * impact.roundoff * T0 + noise, (impact.t, dT / T0, impact.roundoff, noise / T0)
        vel = np.abs(model.contact_velocities(q, before, p)).max()
        for contact in impact.contacts:
            assert contact.impulse >= 0.0, (impact.t, contact)
            cf = friction.get(contact.wall, 0.0) if contact.kind == "wall" else 0.0
            assert np.hypot(*contact.impulse_t) <= cf * contact.impulse * (1 + 1e-9) + 1e-300, (impact.t, contact)
            n = _normal(model, q, p, _contact_index(model, contact))
            v_after = float(n @ after)
            resolve = 8 * model.nq * EPS * float(np.abs(n) @ np.abs(after))
            assert v_after >= -(10 * impact.roundoff * vel + resolve + 1e-15), (impact.t, contact.label, v_after)
        later += impact.t > t_stop
    return later


def run_case(case: str, t_end: float | None = None):
    scene, model, run = fuzz.rebuild_case(case)
    result = simulate(model, run.t_end if t_end is None else t_end, p=run.p, q0=run.q0, qd0=run.qd0,
                      max_wall_time=600, **run.options)
    return scene, model, run, result


def test_an_elastic_corner_struck_for_155_rounds_keeps_its_energy():
    """0-28/6 (4 links, frictionless, cond(I_f) 2.6e10): point O2 in the corner x1_max / x2_max / x3_min, struck at
    174 m/s on x3_min (e = 1) with x2_max (e = 1) and x1_max (e = 0) resting, bounces between them for 155 rounds
    with impulses of 2.5e4 N s (W's condition 4e4).  Exact rounds keep T to 1e-15 whatever A's round-off; in double
    each round's solve and update moved it by F eps |A| |F|, a gain of 3.6e-10 of T over the rounds, above the
    stated 1e-10 (GAC_ERR_IMPACT_ACCURACY at t = 0.00298 s)."""
    scene, model, run, result = run_case("0-28/6", 0.01)
    assert result.status == 0, result.message
    assert check_impacts(scene, model, run, result, 0.00298) > 0


def test_a_frictional_round_ended_at_its_tolerance_leaves_no_approach():
    """0-80/3 (2 links, planar, rough walls, RK4): three frictional rounds left O1 on x1_min (e = 0) pushing with
    461 N s yet approaching at 7.95e-10 m/s, within the rounds' tolerance (1e-9 of the velocities the motion can
    have) but just above the approach the post-conditions allow (7.94e-10 m/s; GAC_ERR_IMPACT_ACCURACY at 1.212 s).
    The approach is closed by a plastic normal strike of its own, which takes energy and keeps the cone."""
    scene, model, run, result = run_case("0-80/3", 1.3)
    assert result.status == 0, result.message
    assert check_impacts(scene, model, run, result, 1.212) > 0


def test_a_first_frictional_round_at_round_off_speed_on_dependent_rows_ends_the_rounds():
    """0-48/1 (one free link on rough walls): O2 in the corner x2_min / x3_min and O1 on x3_max, all approaching at
    1e-12 m/s (touching at rest), 9 rows for 6 coordinates (W singular); no solve of the first round met
    GAC_FRICTION_RESIDUAL_MAX (6e-6 left: GAC_ERR_IMPACT_FRICTION at t = 1.462 s, and at 1.488 s once the rounds'
    approach is closed).  Its approach is within 1e-9 of the velocities the motion can have, as a later round's may
    be: the rounds end.  Run past the first stop here; to t_end (thousands of impacts of 1e-12 N s in the corner,
    40 s) with -m slow."""
    scene, model, run, result = run_case("0-48/1", 1.47)
    assert result.status == 0, result.message
    check_impacts(scene, model, run, result, 1.462)


@pytest.mark.slow
def test_a_point_chattering_in_a_rough_corner_reaches_t_end():
    """0-48/1 to t_end: past its second stop (1.488 s), through the chattering in the corner, where the refinement
    of the impulses against the velocities had taken a stuck contact's tangential impulse of 1e-12 N s 8 % out of
    its cone; a refinement step that would do so is not taken."""
    scene, model, run, result = run_case("0-48/1")
    assert result.status == 0 and result.t_final == pytest.approx(run.t_end), result.message
    assert check_impacts(scene, model, run, result, 1.488) > 0
    assert fuzz.check_run(model, run, result, 0.0, fuzz.BUDGET) == []


def test_a_link_pair_left_approaching_by_a_plastic_closing_round_is_closed():
    """0-33/6 (8 links, capsules, a sphere obstacle, rough walls): O1 on x3_max and the link pair L1-L3 strike each
    other in turn for 256 rounds; the plastic 257th that closes them left the pair approaching at 1.5e-4 m/s
    (GAC_ERR_IMPACT_ACCURACY at t = 0.858 s): the closing plastic normal strikes now reach link pairs too.  (The
    trajectory has since moved: such closing rounds now come at 0.785 s and 0.841 s.)"""
    scene, model, run, result = run_case("0-33/6", 0.9)
    assert result.status == 0, result.message
    closing = [i for i in result.impacts if i.plastic and any(c.kind == "link" for c in i.contacts)]
    assert closing
    assert check_impacts(scene, model, run, result, closing[0].t - 1e-9) > 0


def test_an_impact_its_checks_refuse_names_the_check_and_the_dominating_part():
    """0-44/7 (one free link wedged between the rough walls x1_min and x1_max): the frictional law's impulses meet
    neither stick nor slide there, and the impact's measured accuracy (4e3 of T) is refused: the run stops saying which
    check refused it (record.refusal) and what dominates the accuracy (record.roundoff_cause: the contact law's
    residual)."""
    scene, model, run, result = run_case("0-44/7")
    assert result.status != 0 and result.t_final == pytest.approx(0.02609318, abs=1e-6), result.message
    assert "(refused: its measured accuracy is above GAC_IMPACT_ROUNDOFF_MAX; " in result.message
    assert "its measured accuracy: the contact law's residual: " in result.message
