"""The FMI 2.0 Co-Simulation FMU (runtime.fmu, runtime/c/fmi2/gac_fmi2.c), run by FMPy as an importer would run
it: the archive and modelDescription.xml pass FMPy's validation; its runs agree with runtime.simulate (an
independent driver of the same physics: dense output sampled within one integration, against steps stopped at
every communication point) and close the energy balance from the FMU's own outputs; inputs, parameters, initial
values, saved states and bad calls behave as gac_fmi2.h says.  The slave also compiles strictly against the
standard's own headers (those FMPy ships)."""
from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy", reason="FMPy is not installed: pip install -e '.[fmi]' to run the FMU tests")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from runtime import load_model, simulate  # noqa: E402
from runtime.fmu import FMI2_DIR, build_fmu  # noqa: E402
from runtime.inputs import InputSchedule  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STRICT = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]


class Slave:
    """An FMU instance driven through FMPy's FMU2Slave, with its variables by name."""

    def __init__(self, path: Path, name: str = "instance", guid: str | None = None):
        self.md = read_model_description(str(path))
        self.unzipped = extract(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.fmu = FMU2Slave(guid=guid or self.md.guid, unzipDirectory=self.unzipped,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)

    def refs(self, names):
        return [self.vars[n].valueReference for n in names]

    def real(self, names):
        return np.array(self.fmu.getReal(self.refs(names)))

    def start(self, values=None, tolerance=None):
        self.fmu.instantiate()
        self.fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in (values or {}).items():
            if self.vars[name].type == "Integer":
                self.fmu.setInteger(self.refs([name]), [int(value)])
            else:
                self.fmu.setReal(self.refs([name]), [float(value)])
        self.fmu.exitInitializationMode()

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture(scope="module")
def case1_fmu(tmp_path_factory):
    return build_fmu("paper-case1", tmp_path_factory.mktemp("fmu"))


@pytest.fixture(scope="module")
def driven_fmu(tmp_path_factory):
    return build_fmu("driven-fold", tmp_path_factory.mktemp("fmu"))


def coordinate_names(slave: Slave, prefix: str) -> list[str]:
    return [v.name for v in slave.md.modelVariables if v.name.startswith(prefix + ".")]


def test_archive_and_model_description_validate(case1_fmu):
    assert validate_fmu(str(case1_fmu)) == []
    with zipfile.ZipFile(case1_fmu) as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "binaries/linux64/paper_case1.so", "sources/gac_fmi2.c",
            "sources/paper_case1.c", "sources/paper_case1_fmi2.c", "sources/gac.h"} <= names
    md = read_model_description(str(case1_fmu))
    assert md.fmiVersion == "2.0" and md.coSimulation.canGetAndSetFMUstate
    assert md.defaultExperiment.stopTime == "1.5"
    model = load_model("paper-case1")
    q_names = [v.name for v in md.modelVariables if v.name.startswith("q.")]
    assert len(q_names) == model.nq
    assert [v.name for v in md.modelVariables if v.name.startswith("p.")] == [f"p.{n}" for n in model.parameter_names]


def test_start_values_are_what_the_slave_holds(case1_fmu):
    """Every parameter's start in modelDescription.xml equals what the instance reports before initialization:
    the scene's parameters and initial state, gac_default_options' solver settings."""
    slave = Slave(case1_fmu)
    slave.fmu.instantiate()
    for v in slave.md.modelVariables:
        if v.causality != "parameter":
            continue
        if v.type == "Integer":
            assert slave.fmu.getInteger([v.valueReference])[0] == int(v.start), v.name
        else:
            assert slave.fmu.getReal([v.valueReference])[0] == float(v.start), v.name
    slave.fmu.freeInstance()


def run_fmu(slave: Slave, t_end: float, h: float, outputs: list[str], controller=None):
    """Step to t_end with communication step h; rows of [t, outputs...] and the inputs set at each step."""
    rows, inputs, t = [np.r_[0.0, slave.real(outputs)]], [], 0.0
    steps = int(round(t_end / h))
    for k in range(steps):
        if controller is not None:
            u = controller(slave)
            slave.fmu.setReal(slave.refs(coordinate_names(slave, "u")), list(u))
            inputs.append((t, u))
        slave.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t = (k + 1) * h
        rows.append(np.r_[t, slave.real(outputs)])
    return np.array(rows), inputs


def test_case1_agrees_with_simulate_and_closes_the_energy_balance(case1_fmu):
    slave = Slave(case1_fmu)
    q, qd = coordinate_names(slave, "q"), coordinate_names(slave, "qd")
    energy = ["energy.kinetic", "energy.potential", "energy.loss_impacts", "energy.loss_damping", "energy.work_input"]
    slave.start({"solver.rtol": 1e-12, "solver.atol": 1e-14, "solver.method": 2})
    rows, _ = run_fmu(slave, 1.5, 0.01, q + qd + energy)
    impacts = slave.fmu.getInteger(slave.refs(["impacts"]))[0]
    slave.close()

    model = load_model("paper-case1")
    result = simulate(model, 1.5, method="dop853", rtol=1e-12, atol=1e-14, t_eval=rows[:, 0])
    assert result.success, result.message
    assert impacts == len(result.impacts) == 7
    nq, free = model.nq, list(model.layout.free)
    assert np.max(np.abs(rows[:, 1:1 + nq] - result.q[:, free])) < 1e-9
    assert np.max(np.abs(rows[:, 1 + nq:1 + 2 * nq] - result.qd[:, free])) < 1e-8
    T, V, loss, damping, work = rows[:, 1 + 2 * nq:].T
    E0 = T[0] + V[0]
    assert np.max(np.abs(T + V + loss + damping - work - E0)) < 1e-9 * abs(E0)
    assert loss[-1] == pytest.approx(sum(i.energy_before - i.energy_after for i in result.impacts), abs=1e-9)


def test_two_chains_name_their_variables_by_chain_and_run_as_simulate(tmp_path):
    """A scene of several chains: each chain's coordinates and own parameters with its prefix (q.c2.theta_1,
    p.c2.l_1, the box's p.g once); one communication step over [0, 1] s gives simulate's impacts, final state and
    energy, and the balance closes."""
    path = build_fmu("two-chains", tmp_path)
    assert validate_fmu(str(path)) == []
    model = load_model("two-chains")
    slave = Slave(path)
    names = model.scene.full_coordinate_names()
    assert coordinate_names(slave, "q") == [f"q.{names[i]}" for i in model.layout.free]
    assert "q.c2.theta_1" in slave.vars and slave.vars["qd.c2.theta_1"].unit == "rad/s"
    assert coordinate_names(slave, "p") == [f"p.{n}" for n in model.parameter_names]
    assert slave.vars["p.c2.l_1"].description == "chain 2, link 1: length (m)" and slave.vars["p.c2.l_1"].unit == "m"
    energy = ["energy.kinetic", "energy.potential", "energy.loss_impacts", "energy.loss_damping", "energy.work_input"]
    q, qd = coordinate_names(slave, "q"), coordinate_names(slave, "qd")
    slave.start({"solver.rtol": 1e-10, "solver.atol": 1e-12})
    rows, _ = run_fmu(slave, 1.0, 1.0, q + qd + energy)
    impacts = slave.fmu.getInteger(slave.refs(["impacts"]))[0]
    slave.close()
    result = simulate(model, 1.0, rtol=1e-10, atol=1e-12)
    assert result.success and impacts == len(result.impacts) == 15, result.message
    free, nq = list(model.layout.free), model.nq
    assert np.abs(rows[-1, 1:1 + nq] - result.q_final[free]).max() < 1e-9
    T, V, loss, damping, work = rows[:, 1 + 2 * nq:].T
    assert T[-1] + V[-1] == pytest.approx(result.energy_final, rel=1e-9)
    assert T[-1] + V[-1] + loss[-1] + damping[-1] - work[-1] == pytest.approx(T[0] + V[0], rel=1e-8)


def test_driven_chain_inputs_held_over_each_step(driven_fmu):
    """A PD torque law closed around the FMU (inputs from its outputs at each communication point, held over
    the step) gives the same run as runtime.simulate with those inputs as a held schedule; the balance with the
    inputs' work and the dampers' dissipation closes from the FMU's outputs."""
    slave = Slave(driven_fmu)
    q = coordinate_names(slave, "q")
    qd = coordinate_names(slave, "qd")
    energy = ["energy.kinetic", "energy.potential", "energy.loss_impacts", "energy.loss_damping", "energy.work_input"]
    actuated = [name[2:] for name in coordinate_names(slave, "u")]
    assert actuated == ["theta_2", "theta_3"]

    def pd(s: Slave):
        angle = s.real([f"q.{c}" for c in actuated])
        rate = s.real([f"qd.{c}" for c in actuated])
        return -3.0 * (angle - np.array([0.5, -0.5])) - 0.4 * rate

    slave.start({"solver.rtol": 1e-11, "solver.atol": 1e-13})
    rows, inputs = run_fmu(slave, 1.2, 0.02, q + qd + energy, controller=pd)
    impacts = slave.fmu.getInteger(slave.refs(["impacts"]))[0]
    slave.close()
    assert impacts > 0

    model = load_model("driven-fold")
    schedule = InputSchedule(times=tuple(t for t, _ in inputs), values=tuple(tuple(u) for _, u in inputs))
    result = simulate(model, 1.2, rtol=1e-11, atol=1e-13, t_eval=rows[:, 0], u=schedule)
    assert result.success, result.message
    assert len(result.impacts) == impacts
    nq, free = model.nq, list(model.layout.free)
    assert np.max(np.abs(rows[:, 1:1 + nq] - result.q[:, free])) < 1e-10
    T, V, loss, damping, work = rows[:, 1 + 2 * nq:].T
    E0 = T[0] + V[0]
    assert abs(work[-1]) > 1.0 and damping[-1] > 1.0 and loss[-1] > 1.0
    assert work[-1] == pytest.approx(result.work_input, abs=1e-9 * abs(E0))
    assert damping[-1] == pytest.approx(result.loss_damping, abs=1e-9 * abs(E0))
    assert np.max(np.abs(T + V + loss + damping - work - E0)) < 1e-9 * abs(E0)


def test_parameters_and_initial_values_are_applied(case1_fmu):
    slave = Slave(case1_fmu)
    q = coordinate_names(slave, "q")
    start = {"p.g": 3.0, "qd0.X1": 0.7, "q0.X2": 0.45, "solver.rtol": 1e-11, "solver.atol": 1e-13}
    slave.start(start)
    rows, _ = run_fmu(slave, 0.4, 0.05, q)
    slave.close()
    model = load_model("paper-case1")
    scene = model.scene
    q0, qd0 = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float)
    names = ["theta_-1", "theta_0"] + [f"theta_{i}" for i in range(1, scene.n + 1)] + ["X1", "X2", "X3"]
    q0[names.index("X2")] = 0.45
    qd0[names.index("X1")] = 0.7
    result = simulate(model, 0.4, rtol=1e-11, atol=1e-13, t_eval=rows[:, 0], p={"g": 3.0}, q0=q0, qd0=qd0)
    assert result.success, result.message
    assert np.max(np.abs(rows[:, 1:] - result.q[:, list(model.layout.free)])) < 1e-8
    assert rows[0, 1 + q.index("q.X2")] == 0.45


def test_saved_state_replays_bit_for_bit(case1_fmu):
    slave = Slave(case1_fmu)
    q = coordinate_names(slave, "q")
    slave.start()
    for k in range(50):
        slave.fmu.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
    saved = slave.fmu.getFMUstate()
    first = []
    for k in range(50, 120):
        slave.fmu.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
        first.append(slave.real(q + ["energy.loss_impacts"]))
    impacts = slave.fmu.getInteger(slave.refs(["impacts"]))[0]
    slave.fmu.setFMUstate(saved)
    assert slave.fmu.getRealStatus(2) == pytest.approx(0.5)           # fmi2LastSuccessfulTime
    again = []
    for k in range(50, 120):
        slave.fmu.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
        again.append(slave.real(q + ["energy.loss_impacts"]))
    assert np.array_equal(np.array(first), np.array(again))
    assert slave.fmu.getInteger(slave.refs(["impacts"]))[0] == impacts
    slave.fmu.freeFMUstate(saved)
    slave.close()


def test_experiment_tolerance_sets_the_solver_unless_given(case1_fmu):
    slave = Slave(case1_fmu)
    slave.start(tolerance=1e-6)
    assert list(slave.real(["solver.rtol", "solver.atol"])) == [1e-6, 1e-8]
    slave.close()
    slave = Slave(case1_fmu)
    slave.start({"solver.rtol": 1e-9}, tolerance=1e-6)
    assert list(slave.real(["solver.rtol", "solver.atol"])) == [1e-9, 1e-8]
    slave.close()


def test_bad_calls_fail_with_a_message(case1_fmu, capsys):
    from fmpy.fmi1 import FMICallException
    with pytest.raises(Exception, match="instantiate"):
        Slave(case1_fmu, guid="{00000000-0000-0000-0000-000000000000}").fmu.instantiate()
    assert "fmuGUID does not match" in capsys.readouterr().out

    slave = Slave(case1_fmu)
    slave.fmu.instantiate()
    slave.fmu.setupExperiment(startTime=0.0)
    slave.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["solver.rtol"]), [-1.0])
    assert "solver.rtol must be in [1e-14, 1)" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["solver.rtol"]), [1e-300])
    assert "solver.rtol must be in [1e-14, 1)" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["solver.atol"]), [0.0])
    assert "solver.atol must be in (0, 1e300)" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["q.X1"]), [1.0])
    assert "q and qd are outputs" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["q0.X2"]), [float("nan")])
    assert "must be finite" in capsys.readouterr().out
    slave.fmu.setReal(slave.refs(["q0.X2"]), [-0.5])                 # the chain's end below the floor
    with pytest.raises(FMICallException):
        slave.fmu.exitInitializationMode()
    out = capsys.readouterr().out
    assert "the simulation cannot start" in out and "beyond its wall" in out
    slave.fmu.freeInstance()

    slave = Slave(case1_fmu)
    slave.start()
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["p.g"]), [1.0])
    assert "fixed after initialization" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.01)
    assert "differs from the FMU's time" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.getReal([10_000])
    assert "no Real variable has value reference 10000" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setInteger(slave.refs(["impacts"]), [3])
    assert "only solver.method" in capsys.readouterr().out
    with pytest.raises(FMICallException):
        slave.fmu.setInteger(slave.refs(["solver.impact_law"]), [0])
    assert "solver.impact_law is fixed after initialization" in capsys.readouterr().out
    slave.close()

    slave = Slave(case1_fmu)
    slave.fmu.instantiate()
    slave.fmu.setupExperiment(startTime=0.0)
    slave.fmu.enterInitializationMode()
    assert slave.fmu.getInteger(slave.refs(["solver.impact_law"])) == [1]          # GAC_IMPACT_LAW_GDI
    with pytest.raises(FMICallException):
        slave.fmu.setInteger(slave.refs(["solver.impact_law"]), [7])
    assert "solver.impact_law must be 0 (frictionless), 1 (GDI) or 2" in capsys.readouterr().out
    slave.fmu.setInteger(slave.refs(["solver.impact_law"]), [2])
    assert slave.fmu.getInteger(slave.refs(["solver.stick"])) == [1]
    with pytest.raises(FMICallException):
        slave.fmu.setInteger(slave.refs(["solver.stick"]), [2])
    assert "solver.stick must be 1 (stick as a constraint) or 0" in capsys.readouterr().out
    slave.fmu.setInteger(slave.refs(["solver.stick"]), [0])
    slave.fmu.exitInitializationMode()
    assert slave.fmu.getInteger(slave.refs(["solver.impact_law", "solver.stick"])) == [2, 0]
    with pytest.raises(FMICallException):
        slave.fmu.setInteger(slave.refs(["solver.stick"]), [1])
    assert "solver.stick is fixed after initialization" in capsys.readouterr().out
    slave.close()


def test_baked_parameters_are_not_variables(tmp_path):
    path = build_fmu("paper-case1", tmp_path, name="case1_baked", bake_params=True)
    assert validate_fmu(str(path)) == []
    slave = Slave(path)
    assert not [name for name in slave.vars if name.startswith("p.")]
    slave.start()
    slave.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)
    assert np.all(np.isfinite(slave.real(coordinate_names(slave, "q"))))
    slave.close()


def test_slave_compiles_strictly_against_the_standard_headers(tmp_path):
    """gac_fmi2.c's definitions are checked against the FMI 2.0 prototypes of fmi2Functions.h (FMPy's copy)."""
    headers = Path(fmpy.__file__).parent / "c-code"
    assert (headers / "fmi2Functions.h").exists()
    for extra in (["-DGAC_FMI2_STANDARD_HEADERS", f"-I{headers}"], []):
        done = subprocess.run(["cc", *STRICT, "-O2", *extra, f"-I{ROOT / 'runtime' / 'c'}", f"-I{FMI2_DIR}", "-c",
                               str(FMI2_DIR / "gac_fmi2.c"), "-o", str(tmp_path / "gac_fmi2.o")],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr


def test_command_line(tmp_path):
    done = subprocess.run([sys.executable, "-m", "runtime", "fmu", "--scene", "paper-case1", "--out", str(tmp_path),
                           "--step", "0.01"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "paper_case1.fmu").exists() and "paper_case1.fmu" in done.stdout
    assert read_model_description(str(tmp_path / "paper_case1.fmu")).defaultExperiment.stepSize == "0.01"
    bad = subprocess.run([sys.executable, "-m", "runtime", "fmu", "--scene", "paper-case1", "--out", str(tmp_path),
                          "--step", "-1"], capture_output=True, text=True, cwd=ROOT)
    assert bad.returncode == 2 and "--step: must be a finite time > 0 s, got -1.0" in bad.stderr


def test_an_obstacles_geometry_is_a_parameter_of_the_fmu(tmp_path, capsys):
    """arm-obstacle's ball: its centre and radius are parameters p.center_x_ball ... p.radius_ball with the scene's
    starts (center_z_ball held by the planar model: min = max = its value); the ball moved out of the arm's way
    through them runs as simulate() with the same p, and a radius of 0 is refused, naming it and its range."""
    from fmpy.fmi1 import FMICallException
    path = build_fmu("arm-obstacle", tmp_path)
    slave = Slave(path)
    ball = {name: slave.vars[f"p.{name}"] for name in ("center_x_ball", "center_y_ball", "center_z_ball",
                                                        "radius_ball")}
    assert [float(v.start) for v in ball.values()] == [1.8, 0.95, 0.0, 0.1]
    assert (ball["center_z_ball"].min, ball["center_z_ball"].max) == ("0.0", "0.0")
    q = coordinate_names(slave, "q")
    slave.start({"p.center_y_ball": 3.0, "solver.rtol": 1e-10, "solver.atol": 1e-12})
    rows, _ = run_fmu(slave, 1.0, 0.1, q)
    slave.close()
    model = load_model("arm-obstacle")
    result = simulate(model, 1.0, rtol=1e-10, atol=1e-12, t_eval=rows[:, 0], p={"center_y_ball": 3.0})
    assert result.success and not any(c.wall.endswith("/ball") for i in result.impacts for c in i.contacts)
    assert np.max(np.abs(rows[:, 1:] - result.q[:, list(model.layout.free)])) < 1e-8

    slave = Slave(path)
    slave.fmu.instantiate()
    slave.fmu.setupExperiment(startTime=0.0)
    slave.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        slave.fmu.setReal(slave.refs(["p.radius_ball"]), [0.0])
    assert "p.radius_ball = 0: must be in [1e-09, 1e+09] m (> 0)" in capsys.readouterr().out
    slave.fmu.freeInstance()
