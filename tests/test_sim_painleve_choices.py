"""Runs of the fuzz study that stopped in the Painleve paradox (GAC_ERR_FRICTION) and now go on: a slow resting
point whose slip direction has no consistent normal force takes another one or none (the paradox at zero speed, where
the direction is free), a contact an impact lifts is not held where the other resting contacts have no consistent
forces, and a step whose dense output passes where they have none is rejected and shrunk onto the jam like a stage
there.  Each run is rebuilt from its case as the study does, and its physics is checked here independently: the
kinetic energy from the model's mass matrix never grows at an impact, the impulses push and lie in Coulomb's cone,
friction takes energy, no point sinks into a wall, and the energy balance closes."""
from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from studies import fuzz
from runtime.simulate import simulate
from conftest import wall_friction


def rebuild(case: str):
    """The scene, model and run of a fuzz case 'SEED-STRUCTURE/RUN' (no obstacles in these structures), as the study
    draws them."""
    seed, index, _ = map(int, re.fullmatch(r"(\d+)-(\d+)/(\d+)", case).groups())
    scene, model, run = fuzz.rebuild_case(case)
    assert not fuzz.has_obstacle_runs(seed, index) or isinstance(scene, fuzz.Chains)
    return scene, model, run


def kinetic(model, q, qd, p) -> tuple[float, float]:
    """T = qd' M qd / 2 from the model's mass matrix, and what its evaluation is known to: the terms' magnitude
    |qd|' |M| |qd| / 2 times 1e3 eps (the fuzz chains' M has condition numbers up to 1e14)."""
    M = model.mass_matrix(q, p)
    return 0.5 * float(qd @ M @ qd), 0.5e3 * np.finfo(float).eps * float(np.abs(qd) @ np.abs(M) @ np.abs(qd))


def check_physics(scene, model, run, result):
    layout, p = model.layout, run.p
    friction = wall_friction(scene, p)
    assert result.status == 0 and result.t_final == pytest.approx(run.t_end, abs=1e-12), result.message
    for impact in result.impacts:                       # T from the mass matrix: never more after than before
        q = layout.reduce(impact.q)
        T0, err0 = kinetic(model, q, layout.reduce(impact.qd_before), p)
        T1, err1 = kinetic(model, q, layout.reduce(impact.qd_after), p)
        assert T1 <= T0 * (1 + 10 * impact.roundoff) + err0 + err1 + 1e-300, (impact.t, T0, T1, err0)
        for c in impact.contacts:                       # pushing, inside the cone
            assert c.impulse >= 0.0
            cf = friction.get(c.wall, 0.0)
            assert np.hypot(*c.impulse_t) <= cf * c.impulse * (1 + 1e-9) + 1e-300, (impact.t, c)
    assert result.loss_friction >= -1e-9 * result.energy_scale
    assert abs(result.energy_drift) <= 1e-5 * result.energy_scale
    deepest = min(float(model.contact_gaps(layout.reduce(q), p).min()) for q in result.q)
    assert deepest > -1e-6 * max(1.0, run.extent)
    assert fuzz.check_run(model, run, result, 0.0, fuzz.BUDGET) == []


def run_case(case: str):
    scene, model, run = rebuild(case)
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, max_wall_time=600,
                      t_eval=np.linspace(0.0, run.t_end, 201), **run.options)
    return scene, model, run, result


@pytest.mark.parametrize("case", ["0-4/0", "0-4/1", "0-4/8"])
def test_a_slow_point_takes_a_slip_direction_with_consistent_forces(case):
    """A 4-link chain on rough walls (one compiled structure, three runs): a point that lands or stops on a wall
    where it cannot stick slid on, at zero speed, along the direction its stuck solve would slip in, where its sliding
    system is no P-matrix; the tangential impact there has nothing to stop (before: GAC_ERR_FRICTION at t = 1.29,
    0.10 and 1.77 s).  It now takes a direction with consistent forces, or none (the friction grows with the speed
    from 0); the choices are counted and the message says so."""
    scene, model, run, result = run_case(case)
    check_physics(scene, model, run, result)
    assert result.n_painleve_choices > 0
    assert "Painleve choice(s)" in result.message


def test_a_lifted_contact_is_released_where_the_others_have_no_consistent_forces():
    """One free link on rough walls (0-48/7): an impact lifts a resting point while the others slide in the
    paradox, so its acceleration with them held does not exist (before: GAC_ERR_FRICTION at t = 0.0596 s, from the
    impact's choice of the resting set).  It is released, the loop resolves the others after the impact, and the run
    goes on.  (Checked to 0.09 s: at 0.0995 s the drawn run follows the paradox's edge and stops saying so,
    GAC_PAINLEVE_STALL, where the same run with qd0 moved by 1e-11 m/s reaches the draw's 2 s.)"""
    scene, model, run = rebuild("0-48/7")
    run = dataclasses.replace(run, t_end=0.09)
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, t_eval=np.linspace(0.0, run.t_end, 201),
                      **run.options)
    check_physics(scene, model, run, result)
    assert result.n_painleve_choices > 0


def test_results_without_the_paradox_count_no_choices():
    """A run that never meets the paradox says nothing of it."""
    scene, model, run = rebuild("0-4/2")
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, **run.options)
    assert result.n_painleve_choices == 0 and "Painleve" not in result.message


def test_a_step_whose_dense_output_passes_the_jam_is_shrunk_onto_it():
    """A 6-link chain on rough walls (0-61/5): a step's stages hold the resting forces but its dense output, where the
    events are looked for, passes a state that has none (before: GAC_ERR_FRICTION at t = 1.42 s, from the event
    search).  The step is rejected and shrunk like one whose stage fails there, and the run goes on (here to 1.5 s:
    after the chain's points leave the walls at 1.4234 s its free flight takes 560,000 steps to the draw's 2 s)."""
    scene, model, run = rebuild("0-61/5")
    run = dataclasses.replace(run, t_end=1.5)
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, max_wall_time=600,
                      t_eval=np.linspace(0.0, run.t_end, 201), **run.options)
    check_physics(scene, model, run, result)
    assert any(e.kind == "release" and e.t > 1.4232 for e in result.contact_events)


def test_one_contact_whose_law_has_no_tangential_impact_takes_the_cones_most_dissipative_impulse():
    """A 7-link chain (0-88/1): one point slides on a rough wall (3D) into a state without consistent forces where
    the frictional law (GDI, e = 0) has no non-trivial solution (before: GAC_ERR_FRICTION at t = 0.0304 s).  The
    impulse of Coulomb's cone that takes the most kinetic energy stops or turns the slip there, and the run reaches
    its end with the physics intact.  (The trajectory has since moved: the tangential impact comes at 0.0004 s, and at
    0.0761 s the run meets a state whose tangential impact has no solution either, where it stops saying so; checked
    to 0.07 s.)"""
    scene, model, run = rebuild("0-88/1")
    run = dataclasses.replace(run, t_end=0.07)
    result = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, max_wall_time=600,
                      t_eval=np.linspace(0.0, run.t_end, 201), **run.options)
    check_physics(scene, model, run, result)
    assert result.n_tangential_impacts >= 1
    assert any(i.law == "gdi-tangential" and i.energy_after < i.energy_before for i in result.impacts)


def _wall_frame(wall: str) -> tuple[np.ndarray, np.ndarray]:
    """A wall's inward normal and its two tangential axes (ascending), e.g. x1_min: +e1, (e2, e3)."""
    axis, side = int(wall[1]) - 1, wall[3:]
    normal = np.eye(3)[axis] * (1.0 if side == "min" else -1.0)
    return normal, np.eye(3)[[k for k in range(3) if k != axis]]


def test_tangential_impacts_in_the_paradox_take_the_cones_most_dissipative_impulses():
    """A 4-link chain (0-19/1): points sliding on rough walls reach states without consistent sliding forces (the
    Painleve paradox), where the loop takes a tangential impact (GDI, e = 0: before, GAC_ERR_FRICTION at t = 0.0635 s,
    where one point struck a rough wall while another slid on the floor and no subset of them could leave their walls
    consistently: there the impulses in the two cones that take the most kinetic energy were taken instead).  The run
    reaches its end with the physics intact, and each tangential impact's impulses are the cones' most dissipative,
    checked from the velocities after by the conditions of the convex problem min f(Lambda) = T+ - T- over the cones:
    each contact's velocity after lies in the dual cone (gamma_N >= c_f |gamma_T|: none approaches) and is orthogonal
    to its impulse.  (The run's trajectory has since moved: the strike and the slide now come 5e-7 s apart, and its
    tangential impacts have one contact each, two of them.)"""
    scene, model, run, result = run_case("0-19/1")
    check_physics(scene, model, run, result)
    friction = wall_friction(scene, run.p)
    tangential = [i for i in result.impacts if i.law == "gdi-tangential"]
    assert len(tangential) >= 2 and result.n_tangential_impacts == len(tangential)
    for impact in tangential:
        q, qd = model.layout.reduce(impact.q), model.layout.reduce(impact.qd_after)
        velocities = model.contact_velocities(q, qd, run.p).reshape(-1, 3)
        for c in impact.contacts:
            normal, tangents = _wall_frame(c.wall)
            v = velocities[c.point - 1]
            gamma_n, gamma_t = float(v @ normal), tangents @ v
            scale = np.linalg.norm(v) + 1e-3 * scene.friction_velocity
            assert gamma_n >= friction[c.wall] * np.linalg.norm(gamma_t) - 1e-6 * scale, (c, gamma_n, gamma_t)
            impulse = np.array([c.impulse, *c.impulse_t])
            assert np.linalg.norm(impulse[1:]) > 0.0                   # friction took part
            assert abs(impulse @ np.array([gamma_n, *gamma_t])) <= 1e-6 * np.linalg.norm(impulse) * scale, c
