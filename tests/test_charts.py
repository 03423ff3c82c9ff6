"""Chart switching near the gimbal lock (runtime/charts.py): the state conversion between the two base
charts, the conditioning measure, and the gimbal-lock scene against an independent integration."""

import numpy as np
import pytest

from codegen.scene import load_scene
from runtime import simulate
from runtime.charts import (Chart, ChartError, ChartModels, convert_state,
                            simulate_with_charts)
from studies.reference import integrate_reference

ACCURATE = {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}
LOCK_TIME = 0.25        # the gimbal-lock scene's z_1 is vertical (theta_0 = pi/2) here, by construction


@pytest.fixture(scope="module")
def scene():
    return load_scene("gimbal-lock")


@pytest.fixture(scope="module")
def models(scene):
    return ChartModels(scene)


@pytest.fixture(scope="module")
def through_lock(scene, models):
    """0.6 s of the gimbal-lock scene (no impact yet: the first is at 0.694 s), through the lock."""
    return simulate_with_charts(scene, 0.6, models=models, t_eval=np.linspace(0.0, 0.6, 601), **ACCURATE)


def random_states(rng, count, nq):
    q = rng.uniform(-np.pi, np.pi, size=(count, nq))
    q[:, 1] = rng.uniform(-1.5, 1.5, size=count)
    q[:, -3:] = rng.uniform(0.5, 1.5, size=(count, 3))
    return q, rng.normal(size=(count, nq))


# ---------------------------------------------------------------------------
# the geometry of the charts
# ---------------------------------------------------------------------------
def test_measure_is_det_E_and_cos_theta0(models):
    A, B = models.charts
    rng = np.random.default_rng(1)
    angles = rng.uniform(-np.pi, np.pi, size=(200, 3))
    for chart in (A, B):
        mu = chart.measure(angles[:, 1])
        assert np.allclose(np.abs(np.linalg.det(chart.axes(angles))), mu, atol=1e-14)
        assert np.allclose(chart.measure_of(chart.rotation(angles)), mu, atol=1e-14)
        assert np.allclose(mu, np.abs(np.cos(angles[:, 1])), atol=1e-14)     # phi = pi/2 for these twists
    # B's first axis is perpendicular to A's, so one of the two charts is always well-conditioned
    assert abs(A.first_axis @ B.first_axis) < 1e-15
    R = A.rotation(angles)
    assert np.all(np.maximum(A.measure_of(R), B.measure_of(R)) >= np.sqrt(0.5) - 1e-12)


def test_smallest_eigenvalue_of_If_falls_like_the_measure_squared(scene, models):
    """Why mu is the measure to watch: lambda_min(I_f) of the compiled mass matrix ~ mu^2."""
    model = models.models[0]
    q = np.array(scene.q0)
    ratios = []
    for mu in (1e-1, 1e-2, 1e-3, 1e-4):
        q[1] = np.pi / 2 - np.arcsin(mu)
        assert abs(models.charts[0].measure(q[1]) - mu) < 1e-12
        lam = np.linalg.eigvalsh(model.mass_matrix(q))[0]
        ratios.append(lam / mu ** 2)
    assert max(ratios) / min(ratios) < 1.05, ratios


def test_chart_b_turns_the_first_axis_away_from_z1_at_the_start(scene, models):
    A, B = models.charts
    R0 = A.rotation(np.array(scene.q0[:3]))
    assert B.measure_of(R0) >= np.sqrt(0.5)
    assert np.array_equal(B.T_0, A.T_0) and np.array_equal(B.T_1, A.T_1)        # only T_-1 differs
    assert set(np.unique(B.T_minus1)) <= {-1.0, 0.0, 1.0}                          # a signed permutation


def test_round_trip_on_random_states(scene, models):
    """A -> B -> A is the identity; both states give the same R_1, omega_1, and the same points, point
    velocities and energy through the two compiled models."""
    A, B = models.charts
    model_a, model_b = models.models
    rng = np.random.default_rng(7)
    q, qd = random_states(rng, 100, scene.nq)
    qb, qdb = convert_state(q, qd, A, B)
    qa, qda = convert_state(qb, qdb, B, A, near=q[0, :3])
    for k in range(len(q)):                  # one by one, each from its own angles (the batch is a path)
        qa[k], qda[k] = convert_state(qb[k], qdb[k], B, A, near=q[k, :3])
    assert np.abs(qa - q).max() < 1e-12
    assert np.abs(qda - qd).max() < 1e-11 * np.abs(qd).max()
    assert np.array_equal(qb[:, 3:], q[:, 3:]) and np.array_equal(qdb[:, 3:], qd[:, 3:])
    assert np.abs(B.rotation(qb[:, :3]) - A.rotation(q[:, :3])).max() < 1e-14
    omega_a = np.einsum("nij,nj->ni", A.axes(q[:, :3]), qd[:, :3])
    omega_b = np.einsum("nij,nj->ni", B.axes(qb[:, :3]), qdb[:, :3])
    assert np.abs(omega_a - omega_b).max() < 1e-13 * np.abs(omega_a).max()
    for k in range(len(q)):
        assert np.abs(model_a.contact_points(q[k]) - model_b.contact_points(qb[k])).max() < 1e-13
        va, vb = model_a.contact_velocities(q[k], qd[k]), model_b.contact_velocities(qb[k], qdb[k])
        assert np.abs(va - vb).max() < 1e-12 * (1 + np.abs(va).max())
        Ea, Eb = model_a.energy(q[k], qd[k]), model_b.energy(qb[k], qdb[k])
        assert np.allclose(Ea, Eb, rtol=1e-12, atol=1e-12)


def test_conversion_is_continuous_through_the_lock(models):
    """theta_0 passing through pi/2 with theta_-1, theta_1 fixed, seen from chart B and converted back
    in order: the same path (not the other solution, where theta_-1 and theta_1 jump by pi)."""
    A, B = models.charts
    path = np.zeros((351, 3))
    path[:, 0], path[:, 1], path[:, 2] = 0.3, np.linspace(1.4, 1.75, 351), -0.7
    R = A.rotation(path)
    in_b = B.angles_path(R)
    back = A.angles_path(B.rotation(in_b), near=path[0])
    assert np.abs(back - path).max() < 1e-10
    assert np.abs(np.diff(in_b, axis=0)).max() < 0.01                # B's angles are smooth there


def test_extraction_at_the_lock_takes_theta_minus1_from_near(models):
    A = models.charts[0]
    R = A.rotation(np.array([0.3, np.pi / 2, -0.7]))
    angles = A.angles(R, near=np.array([0.5, 1.5, 0.0]))
    assert abs(angles[0] - 0.5) < 1e-12                              # only theta_-1 + theta_1 is defined
    assert np.abs(A.rotation(angles) - R).max() < 1e-14


def test_bad_charts_and_options_are_refused(scene, models):
    twists = list(scene.base_twists)
    twists[1] = np.eye(3)                                            # T_0 = I: axes -1 and 0 parallel
    with pytest.raises(ChartError, match=r"T_0\[2\]\[2\] = 0"):
        Chart.of(twists)
    with pytest.raises(ValueError, match="threshold: need 0 < hard_limit < threshold < switch_back"):
        simulate_with_charts(scene, 0.1, threshold=0.7, models=models)
    with pytest.raises(ValueError, match="monitor_dt"):
        simulate_with_charts(scene, 0.1, monitor_dt=1.0, chunk=0.1, models=models)


# ---------------------------------------------------------------------------
# the gimbal-lock scene
# ---------------------------------------------------------------------------
def test_single_chart_stops_before_the_lock_with_a_clear_message(models):
    """charts=False: the C loop stops at the last step before |cos theta_0| falls below sqrt(16 eps / rtol)
    (6e-3 at rtol 1e-10: about 0.3 degrees from the lock), where results would lose the run's tolerance."""
    run = simulate(models.models[0], 0.6, max_steps=20000, charts=False, **ACCURATE)
    assert run.status == -1 and "gimbal lock" in run.message
    assert 0.0 < LOCK_TIME - run.t_final < 1e-2
    assert abs(np.cos(run.q_final[1])) >= np.sqrt(16 * 2.220446049250313e-16 / ACCURATE["rtol"])


def test_simulate_switches_charts_by_default(models, through_lock):
    """By default a run that reaches the lock is run again with chart switching: it ends at t_end with the
    chart driver's result."""
    run = simulate(models.models[0], 0.6, **ACCURATE)
    assert run.success, run.message
    assert len(run.switches) >= 1 and run.switches[0].source == "A"


def test_charts_pass_the_lock(through_lock, models):
    r = through_lock
    assert r.status == 0 and r.t_final == 0.6, r.message
    assert "1 chart switch" in r.message
    (switch,) = r.switches
    assert (switch.source, switch.target) == ("A", "B") and switch.t < LOCK_TIME
    assert 0.05 < switch.measure_source < 0.3 and switch.measure_target > 0.9
    assert r.measure_a.min() < 1e-9                      # the path really goes through chart A's lock
    assert r.min_measure >= 0.05                         # ... but never that close on the integrated chart
    assert np.array_equal(r.chart, (r.t >= switch.t).astype(int))
    E = r.energies()
    assert np.abs(E - r.energy_initial).max() < 1e-10 * abs(r.energy_initial)


def test_samples_in_chart_a_are_the_integrated_states(through_lock, models):
    """result.q (chart A) gives the same points as the integrated coordinates (q_native on its chart)."""
    r, model_a = through_lock, models.models[0]
    points = r.contact_points()
    for k in range(0, len(r.t), 7):
        assert np.abs(model_a.contact_points(r.q[k]) - points[k]).max() < 1e-12
    far = r.measure_a > 1e-6
    E_a = np.array([sum(model_a.energy(q, qd)) for q, qd in zip(r.q[far], r.qd[far])])
    assert np.abs(E_a - r.energies()[far]).max() < 1e-10 * abs(r.energy_initial)


def test_world_trajectory_agrees_with_an_independent_integration(through_lock, scene):
    r = through_lock
    pick = slice(0, None, 6)
    expected = integrate_reference(scene, r.t[pick])
    error = np.abs(r.contact_points()[pick] - expected).max()
    assert error < 1e-8, error


def test_coarse_monitor_grid_is_refined_for_the_rotation_rate(scene, models):
    """monitor_dt = 0.1 s is far too coarse for a base turning at ~4 rad/s: the grid is refined so that
    mu cannot fall from threshold past hard_limit between two samples, and the switch is a normal one."""
    te = np.linspace(0.0, 0.5, 6)
    r = simulate_with_charts(scene, 0.5, threshold=0.2, hard_limit=0.15, chunk=0.1, monitor_dt=0.1, t_eval=te,
                             models=models, **ACCURATE)
    assert r.status == 0 and [s.reason for s in r.switches] == ["mu_A < threshold"]
    assert 0.15 <= r.switches[0].measure_source < 0.2
    assert np.abs(r.contact_points() - integrate_reference(scene, te)).max() < 1e-8


def test_hard_limit_and_failure_redo_on_the_other_chart(scene, models, monkeypatch):
    """The backstops, with the grid refinement capped at 0.1 s (one sample per chunk): the measure is
    first seen below hard_limit, or the chunk fails at the lock (step budget), and the stretch is redone
    from the last good sample on chart B; the result is still right."""
    import runtime.charts
    monkeypatch.setattr(runtime.charts, "MIN_MONITOR_DT", 0.1)
    te = np.linspace(0.0, 0.5, 6)
    expected = integrate_reference(scene, te)
    coarse = {"chunk": 0.1, "monitor_dt": 0.1, "t_eval": te, "models": models, **ACCURATE}
    hard = simulate_with_charts(scene, 0.5, threshold=0.2, hard_limit=0.15, **coarse)
    failed = simulate_with_charts(scene, 0.5, threshold=0.06, hard_limit=0.05, **coarse)
    assert any("hard_limit" in s.reason for s in hard.switches), hard.switch_table()
    assert any(s.reason.startswith("failed at mu_A") for s in failed.switches), failed.switch_table()
    for r in (hard, failed):
        assert r.status == 0, r.message
        assert np.abs(r.contact_points() - expected).max() < 1e-8


def test_step_budget_far_from_the_lock_retries_with_max_steps(through_lock, scene, models):
    """A chunk that exhausts chunk_steps while its chart is fine is run again with max_steps."""
    r = simulate_with_charts(scene, 0.1, chunk_steps=3, models=models, t_eval=through_lock.t[:101], **ACCURATE)
    assert r.status == 0 and not r.switches
    assert np.abs(r.contact_points() - through_lock.contact_points()[:101]).max() < 1e-9


def test_start_near_the_lock_begins_on_chart_b(through_lock, scene, models):
    k = int(np.searchsorted(through_lock.t, 0.249))
    q0, qd0 = through_lock.q[k], through_lock.qd[k]           # mu_A = 2.5e-3: chart A is poor at the start
    r = simulate_with_charts(scene, 0.05, q0=q0, qd0=qd0, models=models, **ACCURATE)
    assert r.status == 0
    assert r.switches[0].t == 0.0 and r.switches[0].reason.startswith("start")
    assert r.chart[0] == 1
    assert np.abs(r.q[0] - q0).max() < 1e-9                   # reported back in chart A


def test_long_run_with_impacts(scene, models):
    """3 s with 18 elastic impacts and repeated switches: energy conserved, no penetration, every switch
    reported and consistent with the per-sample charts."""
    r = simulate_with_charts(scene, 3.0, models=models, **ACCURATE)
    assert r.status == 0, r.message
    assert len(r.impacts) >= 10
    kinds = [(s.source, s.target) for s in r.switches]
    assert kinds.count(("A", "B")) >= 3 and kinds.count(("B", "A")) >= 3
    assert all(a != b for a, b in zip(kinds, kinds[1:]))                    # they alternate
    assert all(s.measure_target >= 0.6 for s in r.switches)
    assert r.min_measure >= 0.05
    # the chart of every sample follows from the switch times
    expected = np.zeros(len(r.t), dtype=int)
    for s in r.switches:
        expected[r.t >= s.t] = 0 if s.target == "A" else 1
    assert np.array_equal(r.chart, expected)
    E0 = r.energy_initial
    assert np.abs(r.energies() - E0).max() < 1e-9 * abs(E0)
    assert abs(r.energy_drift) < 1e-9
    assert all(abs(i.energy_after - i.energy_before) < 1e-12 * abs(E0) for i in r.impacts)
    assert r.contact_gaps().min() > -1e-9
    assert [i.t for i in r.impacts] == sorted(i.t for i in r.impacts)
    assert set(r.impact_chart) == {0, 1} or len(set(r.impact_chart)) == 1
    data = r.to_json()
    assert len(data["charts"]["switches"]) == len(r.switches)
    assert "A -> B" in r.switch_table()


def test_case2_switches_and_agrees_with_simulate():
    """Case 2 reaches mu_A = 0.17 at 1.4 s, where a single chart is still accurate: the chart-switching run
    switches there and back and finds the same impacts as simulate()."""
    tight = {"method": "dop853", "rtol": 1e-12, "atol": 1e-14}
    plain = simulate("paper-case2", 1.75, **tight)
    charted = simulate_with_charts("paper-case2", 1.75, **tight)
    assert charted.status == 0 and len(charted.switches) == 2, charted.switch_table()
    assert len(charted.impacts) == len(plain.impacts) == 11
    assert max(abs(a.t - b.t) for a, b in zip(charted.impacts, plain.impacts)) < 1e-10
    assert [[(c.point, c.wall) for c in i.contacts] for i in charted.impacts] == \
        [[(c.point, c.wall) for c in i.contacts] for i in plain.impacts]
    assert np.abs(charted.q_final - plain.q_final).max() < 1e-9


def test_command_line_reports_the_switches(capsys, models):
    from runtime.cli import main
    code = main(["simulate", "--scene", "gimbal-lock", "--t-end", "0.4", "--charts"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "chart switches" in out and "A -> B" in out and "1 chart switch(es)" in out
    code = main(["simulate", "--scene", "gimbal-lock", "--t-end", "0.4"])
    out = capsys.readouterr().out
    assert code == 0 and "chart switches" in out and "A -> B" in out
    code = main(["simulate", "--scene", "gimbal-lock", "--t-end", "0.4", "--no-charts"])
    out = capsys.readouterr().out
    assert code == 1 and "gimbal lock" in out and "hint: without --no-charts" in out


def test_resting_contact_survives_the_chunk_restarts():
    """A chain coming to rest on the floor (e = 0.5): the restarted chunks find the resting contacts again,
    the same impacts and contact events as simulate(), no spurious events at the chunk boundaries."""
    scene = load_scene("stress-zeno")
    p = scene.parameter_vector()
    p[scene.parameter_names().index("e_x2_min")] = 0.5
    charts = ChartModels(scene)
    plain = simulate(charts.models[0], 4.0, p=p, **ACCURATE)
    charted = simulate_with_charts(scene, 4.0, p=p, models=charts, **ACCURATE)
    assert charted.status == 0 and not charted.switches
    assert len(charted.impacts) == len(plain.impacts)
    assert [(e.point, e.wall, e.kind) for e in charted.contact_events] == \
        [(e.point, e.wall, e.kind) for e in plain.contact_events]
    assert max(abs(a.t - b.t) for a, b in zip(charted.contact_events, plain.contact_events)) < 1e-8
    assert sorted(charted.persistent_final) == sorted(plain.persistent_final)
    assert charted.contact_gaps(p).min() > -1e-9


def test_overridden_box_and_start_pass_the_lock_as_the_scene_does(scene, models):
    """Walls (p) and start (q0) moved together by 10 m: the same motion, shifted, through the lock. The rerun
    with charts checks the start against the walls of p, not against the scene's own box."""
    shift = 10.0
    q0 = np.array(scene.q0, dtype=float)
    q0[-3:] += shift
    model = models.models[0]
    names = model.scene.parameter_names()
    p = {name: model.p[names.index(name)] + shift for name in names if name.startswith("wall_x")}
    moved = simulate(model, 0.5, p=p, q0=q0, **ACCURATE)
    home = simulate(model, 0.5, **ACCURATE)
    assert moved.status == 0 and home.status == 0, (moved.message, home.message)
    assert len(moved.switches) >= 1 and len(moved.switches) == len(home.switches)
    expected = np.array(home.q_final, dtype=float)
    expected[-3:] += shift
    assert np.allclose(moved.q_final, expected, atol=1e-8)
    assert np.allclose(moved.qd_final, home.qd_final, atol=1e-8)


def test_overridden_start_outside_the_overridden_box_is_refused(scene, models):
    model = models.models[0]
    q0 = np.array(scene.q0, dtype=float)
    q0[-3:] += 10.0                                  # the chain moved, the box not
    with pytest.raises(ValueError, match="q0: contact point O_1 is outside the wall"):
        simulate_with_charts(scene, 0.1, models=models, q0=q0, **ACCURATE)
