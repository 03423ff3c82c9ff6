"""Many runs of one model (runtime.ensemble), the sweep command, and single-run exports."""
from __future__ import annotations

import csv
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import load_scene
from runtime import load_model, simulate
from runtime.ensemble import simulate_many
from runtime.export import write_csv, write_npz

ROOT = Path(__file__).resolve().parent.parent
RUNS = [{"p": {"e_x2_min": e}, "qd0": {"X1": v}} for e in (0.3, 0.7, 1.0) for v in (-0.5, 0.0, 0.5)]


def serial_rows(model, runs, t_end):
    """The same runs one by one through simulate(), the yardstick of the parallel paths."""
    rows = []
    for run in runs:
        qd0 = np.array(model.scene.qd0)
        qd0[-3] = run["qd0"]["X1"]
        result = simulate(model, t_end, p=run["p"], qd0=qd0, t_eval=[], charts=False)
        rows.append((len(result.impacts), result.energy_final, result.status))
    return rows


def summary(study):
    return [(row["n_impacts"], row["energy_final"], row["status"]) for row in study.rows]


@pytest.fixture(scope="module")
def model():
    return load_model("paper-case1")


@pytest.mark.parametrize("how", [dict(workers=1), dict(workers=2), dict(workers=2, processes=True)])
def test_parallel_runs_equal_serial_runs(model, how):
    study = simulate_many(model, RUNS, 0.8, t_eval=[], **how)
    assert [row["run"] for row in study.rows] == list(range(len(RUNS)))
    assert summary(study) == serial_rows(model, RUNS, 0.8)
    assert study.rows[0]["p.e_x2_min"] == 0.3 and study.rows[0]["qd.X1"] == -0.5


def test_a_dask_cluster_gives_the_serial_results(model):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed (the ensemble extra)")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        study = simulate_many(model, RUNS, 0.8, t_eval=[], client=client, chunk_size=2)
        workers = client.run(lambda: 1)
    assert len(workers) == 2
    assert summary(study) == serial_rows(model, RUNS, 0.8)


def test_the_model_pickles_as_its_scene(model):
    again = pickle.loads(pickle.dumps(model))
    assert again.scene == model.scene and again.options == model.options
    assert np.array_equal(again.forward_dynamics(model.q0, model.qd0), model.forward_dynamics(model.q0, model.qd0))


def test_a_failing_run_is_a_row_not_a_crash(model):
    runs = [{"p": {"e_x2_min": 0.5}}, {"p": {"e_x2_min": 1.5}}, {"q0": {"X2": -3.0}}, {"p": {"nope": 1.0}},
            {"p": {"e_x2_min": 0.5}, "t_end": 0.2}]
    study = simulate_many(model, runs, 0.5, t_eval=[], workers=2)
    status = [row["status"] for row in study.rows]
    assert status == [0, -2, -2, -2, 0]
    assert "restitution must be in [0, 1]" in study.rows[1]["message"]
    assert "outside the wall x2_min" in study.rows[2]["message"]
    assert "p[nope]: no such parameter" in study.rows[3]["message"]
    assert study.rows[4]["t_final"] == 0.2
    with pytest.raises(ValueError, match="runs\\[0\\]: unknown key 'P'; allowed: p, q0, qd0, u, t_end"):
        simulate_many(model, [{"P": {}}], 0.1)
    with pytest.raises(ValueError, match="keep: 'samples' needs t_eval"):
        simulate_many(model, runs, 0.1, keep="samples")


def test_tables_and_arrays_round_trip(model, tmp_path):
    study = simulate_many(model, RUNS[:4], 0.5, keep="samples", t_eval=np.linspace(0, 0.5, 11))
    study.to_csv(tmp_path / "runs.csv")
    study.to_npz(tmp_path / "runs.npz")
    with open(tmp_path / "runs.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert [float(r["energy_final"]) for r in rows] == [r["energy_final"] for r in study.rows]
    data = np.load(tmp_path / "runs.npz")
    assert data["q"].shape == (4, 11, 9) and np.array_equal(data["col_n_impacts"], study.column("n_impacts"))
    single = simulate(model, 0.5, p={"e_x2_min": 0.3}, qd0=np.r_[model.scene.qd0[:-3], -0.5, 0, 0],
                      t_eval=np.linspace(0, 0.5, 11))
    assert np.array_equal(data["q"][0], single.q)


def test_single_run_exports(model, tmp_path):
    result = simulate(model, 1.0, t_eval=np.linspace(0, 1, 21))
    scene = model.scene
    write_csv(result, tmp_path / "run.csv", scene)
    write_npz(result, tmp_path / "run.npz", scene)
    with open(tmp_path / "run.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 21 and float(rows[7]["q.theta_1"]) == result.q[7, 2]
    data = np.load(tmp_path / "run.npz")
    points = data["points"]
    lengths = np.linalg.norm(np.diff(points, axis=1), axis=2)
    assert np.allclose(lengths, [link.length for link in scene.links], atol=1e-12)     # joint points, rigid links
    assert np.array_equal(data["impact_t"], [i.t for i in result.impacts]) and len(data["impact_t"]) >= 3
    assert float(rows[0]["O1.X1"]) == points[0, 0, 0]


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "runtime", *args], cwd=cwd, capture_output=True, text=True)


def test_sweep_command_end_to_end(tmp_path):
    pytest.importorskip("tqdm", reason="tqdm is not installed (the ensemble extra)")
    done = run_cli("sweep", "--scene", "paper-case1", "--vary", "e_x2_min=0.2:1:3", "--vary", "qd.X1=-0.5:0.5:2",
                   "--t-end", "0.6", "--workers", "2", "--out", str(tmp_path / "out"), cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert "6 runs in" in done.stdout
    rows = list(csv.DictReader(open(tmp_path / "out" / "runs.csv")))
    assert np.allclose([(float(r["p.e_x2_min"]), float(r["qd.X1"])) for r in rows],
                       [(e, v) for e in (0.2, 0.6, 1.0) for v in (-0.5, 0.5)], rtol=0, atol=1e-15)
    assert (tmp_path / "out" / "sweep.png").stat().st_size > 1000


@pytest.mark.parametrize("args,message", [
    (["--vary", "e_x2_min=0:1"], "--vary: expected NAME=LO:HI:N"),
    (["--vary", "e_x2_min=0:1:zero"], "--vary e_x2_min: LO and HI must be numbers and N an integer"),
    (["--vary", "colour=0:1:3"], "--vary colour: not a parameter of this model"),
    (["--vary", "q.theta_9=0:1:3"], "--vary q.theta_9: no coordinate 'theta_9'"),
    (["--vary", "e_x2_min=0:1:3", "--vary", "e_x2_min=0:1:3"], "--vary e_x2_min: given twice"),
    (["--vary", "e_x2_min=0:1:3", "--workers", "0"], "--workers: must be in 1..1024"),
    (["--vary", "e_x2_min=0:1:10000", "--vary", "qd.X1=0:1:10000"], "--vary: the grid has 100,000,000 runs"),
])
def test_sweep_command_refuses_bad_arguments(tmp_path, args, message):
    done = run_cli("sweep", "--scene", "paper-case1", *args, "--out", str(tmp_path / "out"), cwd=ROOT)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "out").exists()


def test_simulate_command_writes_exports(tmp_path):
    done = run_cli("simulate", "--scene", "paper-case1", "--t-end", "0.3", "--csv", str(tmp_path / "a.csv"),
                   "--npz", str(tmp_path / "a.npz"), cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "a.csv").read_text().startswith("t,q.theta_-1,q.theta_0")
    assert np.load(tmp_path / "a.npz")["samples"].shape[0] == 301
    load_scene("paper-case1")


def test_sweep_on_a_dask_local_cluster_writes_the_same_table(tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (the ensemble extra)")
    tables = []
    for how in (["--workers", "1"], ["--scheduler", "local", "--workers", "2"]):
        out = tmp_path / how[1]
        done = run_cli("sweep", "--scene", "paper-case1", "--vary", "e_x2_min=0.2:1:4", "--t-end", "0.5", *how,
                       "--out", str(out), cwd=ROOT)
        assert done.returncode == 0, done.stderr
        tables.append((out / "runs.csv").read_text())
    assert tables[0] == tables[1]
