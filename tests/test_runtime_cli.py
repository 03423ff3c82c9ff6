"""python -m runtime simulate: impact table, JSON result, plots, clear errors."""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(*args):
    return subprocess.run([sys.executable, "-m", "runtime", *args], capture_output=True, text=True, cwd=ROOT)


def test_simulate_writes_json_and_plots(tmp_path):
    out = tmp_path / "case2.json"
    result = run("simulate", "--scene", "paper-case2", "--t-end", "0.5", "--json", str(out),
                 "--plot", str(tmp_path / "plots"))
    assert result.returncode == 0, result.stderr
    assert "0.285568" in result.stdout and "O1/x2_min" in result.stdout and "balance residual" in result.stdout
    data = json.loads(out.read_text())
    first = data["impacts"][0]
    assert first["contacts"][0]["point"] == 1 and first["contacts"][0]["wall"] == "x2_min"
    assert first["contacts"][0]["impulse"] > 0
    assert abs(first["t"] - (2 * 0.4 / 9.81) ** 0.5) < 1e-9
    for key in ("t_final", "q_final", "qd_final", "energy_initial", "energy_final", "energy_impact_loss",
                "energy_residual", "energy_scale", "energy_drift", "n_rhs"):
        assert key in data
    assert data["t_final"] == 0.5 and len(data["q_final"]) == 6
    pngs = sorted(p.name for p in (tmp_path / "plots").glob("*.png"))
    assert "paper_case2_impacts.png" in pngs and "paper_case2_angles.png" in pngs and len(pngs) == 8   # X1..X3
    assert "paper_case2_positions_X3.png" in pngs


def test_rk4_needs_dt_and_bad_scene_is_named(tmp_path):
    result = run("simulate", "--scene", "paper-case1", "--method", "rk4")
    assert result.returncode == 2 and "--dt: rk4 needs a step" in result.stderr
    result = run("simulate", "--scene", "no-such-scene")
    assert result.returncode == 2 and "shipped scenes: " in result.stderr and "paper-case1" in result.stderr
    assert "Traceback" not in result.stderr


def test_studies_are_not_runtime_commands():
    """precision, stress and fuzz are studies (python -m studies ...): the old form says so in one line."""
    for study in ("precision", "stress", "fuzz"):
        result = run(study, "--quick")
        assert result.returncode == 2 and result.stdout == ""
        assert result.stderr == f"error: '{study}' is a study: run python -m studies {study} --quick\n"
    result = run("--help")
    assert result.returncode == 0 and "simulate" in result.stdout
    assert not any(study in result.stdout for study in ("precision", "stress", "fuzz"))
