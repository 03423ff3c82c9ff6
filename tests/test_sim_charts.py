"""Chart switching near the gimbal lock, in the C loop (gac_sim.c, gac_chart.c): a free base's model carries a
second base chart (codegen.charts) and the loop integrates on it where chart A's measure is poor.  Checked against
an independent integration (studies.reference, the base orientation as a rotation matrix), against a single-chart
run where one chart still suffices, against the same motion in a turned frame, and through the FMU and the
standalone program."""

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from codegen.charts import Chart, chart_b_scene
from codegen.scene import Joint, load_scene
from codegen.specialise import layout_for
from runtime import load_model, simulate
from studies.reference import integrate_reference

ROOT = Path(__file__).resolve().parents[1]
ACCURATE = {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}
LOCK_TIME = 0.25        # the gimbal-lock scene's z_1 is vertical (theta_0 = pi/2) here, by construction
EPS = 2.220446049250313e-16


@pytest.fixture(scope="module")
def scene():
    return load_scene("gimbal-lock")


@pytest.fixture(scope="module")
def model(scene):
    return load_model(scene)


@pytest.fixture(scope="module")
def through_lock(model):
    """0.6 s of the gimbal-lock scene (no impact yet: the first is at 0.694 s), through the lock."""
    return simulate(model, 0.6, t_eval=np.linspace(0.0, 0.6, 601), **ACCURATE)


def driven_scene(scene, inputs=("theta_2",)):
    """The gimbal-lock chain with a spring and a damper on joint 2 and an input, weak enough that the base still
    turns through chart A's lock (within its floor at rtol 1e-10)."""
    joint = Joint(stiffness=1e-4, rest_angle=0.8, damping=1e-5)
    return dataclasses.replace(scene, name="gimbal_driven", joints=(joint,), inputs=inputs)


def measure_a(scene, q):
    return Chart.of(scene.base_twists).measure(np.asarray(q)[..., 1])


# ---------------------------------------------------------------------------
# the model's second chart
# ---------------------------------------------------------------------------
def test_chart_b_first_axis_is_perpendicular_and_far_from_z1_at_the_start(scene):
    A = Chart.of(scene.base_twists)
    scene_b = chart_b_scene(scene, layout_for(scene))
    B = Chart.of(scene_b.base_twists)
    assert abs(A.first_axis @ B.first_axis) < 1e-15
    assert np.allclose(A.rotation(scene.q0[:3]), B.rotation(scene_b.q0[:3]), atol=1e-14)
    assert B.measure(scene_b.q0[1]) >= np.sqrt(0.5)
    assert scene_b.q0[3:] == scene.q0[3:] and scene_b.qd0[3:] == scene.qd0[3:]


def test_planar_models_and_inputs_on_a_base_angle_get_no_second_chart(scene):
    case1 = load_scene("paper-case1")
    assert chart_b_scene(case1, layout_for(case1)) is None                 # planar: never near the lock
    assert chart_b_scene(case1, layout_for(case1, specialise=False)) is not None
    on_base = driven_scene(scene, inputs=("theta_0",))
    assert chart_b_scene(on_base, layout_for(on_base)) is None


# ---------------------------------------------------------------------------
# through the lock, free flight
# ---------------------------------------------------------------------------
def test_single_chart_stops_before_the_lock_with_a_clear_message(model):
    """charts=False: the C loop stops at the last step before |cos theta_0| falls below sqrt(16 eps / rtol)."""
    run = simulate(model, 0.6, max_steps=20000, charts=False, **ACCURATE)
    assert run.status == -1 and "gimbal lock" in run.message and "no second chart" in run.message
    assert 0.0 < LOCK_TIME - run.t_final < 1e-2
    assert abs(np.cos(run.q_final[1])) >= np.sqrt(16 * EPS / ACCURATE["rtol"])
    assert run.n_chart_switches == 0


def test_a_model_built_with_one_chart_has_no_second_chart_and_stops_at_the_lock(scene, model):
    """chart_b=False (--one-chart): no NAME_b_* kernels and no NAME_model_b; the run stops where charts=False
    stops the full model."""
    one = load_model(scene, chart_b=False)
    assert one.options.chart_b is False and "_model_b" not in one.generated.source
    assert "_model_b" in model.generated.source
    assert "gimbal_lock_b_" not in one.generated.source and "gimbal_lock_b_forward_dynamics(" in model.generated.source
    assert len(one.generated.source) < 0.75 * len(model.generated.source)   # (chart A alone has the tangent kernels)
    run = simulate(one, 0.6, max_steps=20000, **ACCURATE)
    full = simulate(model, 0.6, max_steps=20000, charts=False, **ACCURATE)
    assert run.status == -1 and "gimbal lock" in run.message
    assert run.t_final == full.t_final and np.array_equal(run.q_final, full.q_final)


def test_the_loop_passes_the_lock_on_the_second_chart(through_lock, scene):
    r = through_lock
    assert r.status == 0 and r.t_final == 0.6, r.message
    assert r.n_chart_switches == 1 and "1 chart switch(es)" in r.message
    mu = measure_a(scene, r.q)
    assert mu.min() < 1e-3                               # the path really goes through chart A's lock
    assert r.to_json()["n_chart_switches"] == 1


def test_world_trajectory_agrees_with_an_independent_integration(through_lock, scene, model):
    """The points O_1..O_3 from the samples (chart A's coordinates, whichever chart was integrated) against
    the numpy reference model integrated with the orientation as a rotation matrix (no chart at all)."""
    r = through_lock
    pick = slice(0, None, 6)
    expected = integrate_reference(scene, r.t[pick])
    points = np.array([model.contact_points(q) for q in r.q[pick]])
    assert np.abs(points - expected).max() < 1e-8


@pytest.mark.parametrize("method", [{"method": "rk4", "dt": 1e-4}, {"method": "dopri5", "rtol": 1e-8, "atol": 1e-10}],
                         ids=["rk4", "dopri5"])
def test_other_integrators_pass_the_lock(scene, model, method):
    """RK4 (no step rejection: the switch is made at the start of a step that would pass the lock) and DOPRI5
    at its default tolerance, against the same independent integration."""
    t = np.linspace(0.0, 0.6, 61)
    r = simulate(model, 0.6, t_eval=t, **method)
    assert r.status == 0 and r.n_chart_switches == 1, r.message
    points = np.array([model.contact_points(q) for q in r.q])
    assert np.abs(points - integrate_reference(scene, t)).max() < 1e-8


def test_energy_is_kept_through_the_lock(through_lock, scene, model):
    """Free flight with no damping: T + V constant on every sample where chart A's own rates are well
    conditioned, and at the end (the balance of the run)."""
    r = through_lock
    good = measure_a(scene, r.q) > 0.1
    E = np.array([sum(model.energy(q, qd)) for q, qd in zip(r.q[good], r.qd[good])])
    assert np.abs(E - r.energy_initial).max() < 1e-10 * abs(r.energy_initial)
    assert abs(r.energy_drift) < 1e-10


def test_start_near_the_lock_begins_on_chart_b(through_lock, scene, model):
    k = int(np.searchsorted(through_lock.t, 0.249))
    q0, qd0 = through_lock.q[k], through_lock.qd[k]          # chi_A = 2.5e-3: chart A is poor at the start
    assert measure_a(scene, q0) < 0.01
    r = simulate(model, 0.05, q0=q0, qd0=qd0, t_eval=[0.0, 0.05], **ACCURATE)
    assert r.status == 0 and r.n_chart_switches >= 1, r.message
    assert np.abs(r.q[0] - q0).max() < 1e-9                  # reported back in chart A, the same branch
    assert np.abs(r.qd[0] - qd0).max() < 1e-9 * np.abs(qd0).max()
    ref = simulate(model, 0.299, t_eval=[0.299], **ACCURATE)  # the same motion from the scene's own start
    assert np.abs(model.contact_points(r.q_final) - model.contact_points(ref.q[-1])).max() < 1e-8


def test_bad_threshold_is_refused(model):
    with pytest.raises(ValueError, match=r"chart_switch: must be 0 \(never\) or within \[0.1, 0.35\]"):
        simulate(model, 0.1, charts=0.5)
    r = simulate(model, 0.6, charts=0.2, **ACCURATE)
    assert r.status == 0 and r.t_final == 0.6 and r.n_chart_switches >= 1


# ---------------------------------------------------------------------------
# long runs with impacts
# ---------------------------------------------------------------------------
def test_long_run_with_impacts_keeps_the_energy(model):
    """3 s, 18 elastic impacts, repeated switches each way: energy kept at every impact and over the run, no
    point outside the box at an impact (the impacts' states are in chart A's coordinates)."""
    r = simulate(model, 3.0, **ACCURATE)
    assert r.status == 0 and r.t_final == 3.0, r.message
    assert len(r.impacts) >= 10 and r.n_chart_switches >= 6
    assert f"{r.n_chart_switches} chart switch(es)" in r.message
    E0 = r.energy_initial
    assert abs(r.energy_drift) < 1e-9
    assert all(abs(i.energy_after - i.energy_before) < 1e-12 * abs(E0) for i in r.impacts)
    for i in r.impacts:
        assert model.contact_gaps(i.q).min() > -1e-9
        touching = [c.point for c in i.contacts]
        assert touching


def test_long_run_agrees_with_the_same_motion_in_a_turned_frame(scene, model):
    """The same physical motion parametrised by chart B from the start (the scene with T_-1 turned, its own
    chart A being the other's B): it switches at other times on other kernels, and finds the same impacts
    (times and configurations) to the integration tolerance."""
    turned = dataclasses.replace(chart_b_scene(scene, layout_for(scene)), name="gimbal_turned")
    a = simulate(model, 1.5, t_eval=[], **ACCURATE)
    b = simulate(load_model(turned), 1.5, t_eval=[], **ACCURATE)
    assert a.status == b.status == 0, (a.message, b.message)
    assert len(a.impacts) == len(b.impacts) >= 5
    assert [[(c.point, c.wall) for c in i.contacts] for i in a.impacts] == \
        [[(c.point, c.wall) for c in i.contacts] for i in b.impacts]
    assert max(abs(x.t - y.t) for x, y in zip(a.impacts, b.impacts)) < 1e-8
    turned_model = load_model(turned)
    for x, y in zip(a.impacts, b.impacts):
        assert np.abs(model.contact_points(x.q) - turned_model.contact_points(y.q)).max() < 1e-7


def test_case2_switches_and_agrees_with_a_single_chart():
    """Case 2 reaches chi_A = 0.17 at 1.4 s, where a single chart is still accurate: the run switches there and
    back and finds the same impacts and final state as the single-chart run (no chart B code involved)."""
    tight = {"method": "dop853", "rtol": 1e-12, "atol": 1e-14}
    case2 = load_model("paper-case2")
    plain = simulate(case2, 1.75, charts=False, **tight)
    charted = simulate(case2, 1.75, **tight)
    assert charted.status == 0 and charted.n_chart_switches == 2, charted.message
    assert plain.n_chart_switches == 0
    assert len(charted.impacts) == len(plain.impacts) == 11
    assert max(abs(a.t - b.t) for a, b in zip(charted.impacts, plain.impacts)) < 1e-10
    assert [[(c.point, c.wall) for c in i.contacts] for i in charted.impacts] == \
        [[(c.point, c.wall) for c in i.contacts] for i in plain.impacts]
    assert np.abs(charted.q_final - plain.q_final).max() < 1e-9


def test_resting_contacts_start_on_chart_b_and_carry_over_a_switch(model):
    """Link 1 lying on the floor with its joint axis z_1 vertical: chart A's lock itself (chi_A = 1e-7).  The run
    starts on chart B with O_1 and O_2 resting on the floor (e = 0), link 2 falls and lands, rolling link 1 about
    its own axis until chi_A passes 0.6: back on chart A with the three contacts resting.  No point sinks, the
    energy balance closes, the rests at the start are reported at t = 0 in chart A's coordinates."""
    p = model.parameters({"e_x2_min": 0.0})
    q0 = np.array([0.3, np.pi / 2 - 1e-7, -0.4, 0.5, 1.0, 0.0, 1.0])     # theta_2 = 0.5: O_3 above the floor
    assert model.contact_points(q0)[2, 1] > 0.1 and abs(model.contact_points(q0)[1, 1]) < 1e-6
    qd0 = np.zeros(7)
    qd0[4], qd0[6] = 0.1, 0.05                                             # sliding on the frictionless floor
    r = simulate(model, 1.5, q0=q0, qd0=qd0, p=p, **ACCURATE)
    assert r.status == 0, r.message
    assert r.n_chart_switches >= 2                       # on B from the start, back on A once link 1 rolls
    assert [(e.t, e.kind, e.point) for e in r.contact_events[:2]] == [(0.0, "rest", 1), (0.0, "rest", 2)]
    assert sorted(r.resting_final) == [(1, "x2_min"), (2, "x2_min"), (3, "x2_min")]
    assert np.abs(r.q[0] - q0).max() < 1e-9             # theta_-1, theta_1 alone are conditioned like eps / chi_A
    A = Chart.of(model.scene.base_twists)
    assert np.abs(A.rotation(r.q[0, :3]) - A.rotation(q0[:3])).max() < 1e-14
    assert np.array([model.contact_gaps(q, p) for q in r.q]).min() > -1e-9
    assert abs(r.energy_drift) < 1e-9


# ---------------------------------------------------------------------------
# driven chains
# ---------------------------------------------------------------------------
def test_driven_chain_crosses_the_lock(scene):
    """A spring, a damper and an input on joint 2 (they do not depend on the base chart): the run passes the
    lock (it used to stop there) and the energy balance with the input's work and the damper's loss closes."""
    model = load_model(driven_scene(scene))
    single = simulate(model, 1.0, u=[1e-4], charts=False, **ACCURATE)
    assert single.status == -1 and "gimbal lock" in single.message
    r = simulate(model, 1.0, u=[1e-4], **ACCURATE)
    assert r.status == 0 and r.t_final == 1.0, r.message
    assert r.n_chart_switches >= 1
    assert r.loss_damping > 0.0 and r.work_input != 0.0
    assert abs(r.energy_drift) < 1e-9


def test_input_on_a_base_angle_stops_at_the_lock_and_says_why(scene):
    model = load_model(driven_scene(scene, inputs=("theta_2", "theta_0")))
    r = simulate(model, 0.6, u=[0.0, 0.0], **ACCURATE)
    assert r.status == -1 and "gimbal lock" in r.message and "input" in r.message


# ---------------------------------------------------------------------------
# the other front ends: standalone program and FMU
# ---------------------------------------------------------------------------
@pytest.mark.slow     # the default tier's tools parity test runs the same program through the lock (gimbal-lock row)
def test_standalone_program_passes_the_lock(tmp_path, model):
    subprocess.run([sys.executable, "-m", "codegen", "--scene", "gimbal-lock", "--out", str(tmp_path), "--standalone",
                    "--no-compile"], check=True, cwd=ROOT, capture_output=True)
    subprocess.run(["make", "-s"], cwd=tmp_path, check=True, capture_output=True)
    run = subprocess.run(["./gimbal_lock_example", "3", "dop853", "1e-10"], cwd=tmp_path, capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stderr
    switches = int(re.search(r"# base chart switches (\d+)", run.stdout).group(1))
    python = simulate(model, 3.0, t_eval=[], method="dop853", rtol=1e-10, atol=1e-12)
    assert switches == python.n_chart_switches > 0
    c_times = [float(line.split()[1]) for line in run.stdout.splitlines() if re.match(r"^\s*\d+ \d", line)]
    assert len(c_times) == len(python.impacts)
    assert max(abs(a - b.t) for a, b in zip(c_times, python.impacts)) < 1e-12
    energy = float(re.search(r"final energy (\S+) J", run.stdout).group(1))
    assert energy == pytest.approx(python.energy_final, rel=1e-9)


@pytest.mark.parametrize("driven", [False, True], ids=["gimbal-lock", "driven"])
def test_fmu_passes_the_lock_and_agrees_with_python(tmp_path, scene, driven):
    pytest.importorskip("fmpy", reason="FMPy is not installed: pip install -e '.[fmi]' to run the FMU tests")
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from runtime.fmu import build_fmu
    chosen = driven_scene(scene) if driven else scene
    path = build_fmu(chosen, tmp_path)
    md = read_model_description(str(path))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    q_names = [v.name for v in md.modelVariables if v.name.startswith("q.")]
    qd_names = [v.name for v in md.modelVariables if v.name.startswith("qd.")]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="charts")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([refs["solver.rtol"], refs["solver.atol"]], [1e-11, 1e-13])
    fmu.setInteger([refs["solver.method"]], [2])
    if driven:
        fmu.setReal([refs["u.theta_2"]], [1e-4])
    fmu.exitInitializationMode()
    h, t_end, rows = 0.01, 1.0, []
    for k in range(int(round(t_end / h))):
        fmu.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        rows.append(fmu.getReal([refs[n] for n in q_names + qd_names]))
    time = fmu.getReal([refs["time"]])[0] if "time" in refs else t_end
    fmu.terminate()
    fmu.freeInstance()
    rows = np.array(rows)
    model = load_model(chosen)
    t = h * np.arange(1, len(rows) + 1)
    r = simulate(model, t_end, t_eval=t, method="dop853", rtol=1e-11, atol=1e-13, u=[1e-4] if driven else None)
    assert r.status == 0 and r.n_chart_switches >= 1, r.message
    assert len(rows) == 100 and time == pytest.approx(t_end)
    nq = model.nq
    # near chart A's lock its angles are not unique (two branches, theta_-1 +- theta_1 alone at the lock): the
    # orientation and the angular velocity are what both must agree on; the other coordinates directly
    A = Chart.of(chosen.base_twists)
    assert np.abs(A.rotation(rows[:, :3]) - A.rotation(r.q[:, :3])).max() < 1e-8
    omega = [np.einsum("nij,nj->ni", A.axes(x[:, :3]), v[:, :3]) for x, v in ((rows[:, :nq], rows[:, nq:]), (r.q, r.qd))]
    good = measure_a(chosen, r.q) > 0.05                 # E_A thetadot_A cancels like 1/chi_A near the lock
    assert np.abs(omega[0] - omega[1])[good].max() < 1e-7
    assert np.abs(rows[:, 3:nq] - r.q[:, 3:]).max() < 1e-8
    assert np.abs(rows[:, nq + 3:] - r.qd[:, 3:]).max() < 1e-7
    points = np.array([model.contact_points(q) for q in rows[:, :nq]])
    assert np.abs(points - np.array([model.contact_points(q) for q in r.q])).max() < 1e-8
