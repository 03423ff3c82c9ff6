"""python -m runtime simulate: impact table, JSON result, plots, clear errors."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

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
    assert "paper_case2_impacts.png" in pngs and "paper_case2_angles.png" in pngs and len(pngs) == 6


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


# ---------------------------------------------------------------------------
# advice that can be followed: every option a message names exists, with a value that is accepted
# ---------------------------------------------------------------------------
def test_max_impacts_advice_names_the_option_and_raising_it_goes_on(capsys):
    import runtime.cli
    code = runtime.cli.main(["simulate", "--scene", "paper-case1", "--max-impacts", "3"])
    out = capsys.readouterr().out
    assert code == 1 and "the --max-impacts limit of 3 (raise --max-impacts to go on)" in out
    assert "max_impacts" not in out
    code = runtime.cli.main(["simulate", "--scene", "paper-case1", "--max-impacts", "4"])
    assert code == 1 and "limit of 4" in capsys.readouterr().out
    code = runtime.cli.main(["simulate", "--scene", "paper-case1", "--max-impacts", "100"])
    assert code == 0 and "status 0: reached t_end" in capsys.readouterr().out


def test_advice_in_messages_names_cli_options():
    from runtime.cli import in_cli_words
    message = ("mean step 1e-09 s; ... raise max_steps / max_wall_time or loosen rtol/atol; "
               "the max_impacts limit of 5 (raise max_impacts to go on); reduce dt, or use an adaptive method")
    assert in_cli_words(message) == (
        "mean step 1e-09 s; ... raise --max-steps / --max-wall-time or loosen --rtol/--atol; "
        "the --max-impacts limit of 5 (raise --max-impacts to go on); reduce --dt, or use an adaptive method")
    assert in_cli_words("--rtol: must be ...; stop_rtol_x") == "--rtol: must be ...; stop_rtol_x"   # no double


@pytest.mark.parametrize("t_end", [1e9, 12345.678, 1e7 - 0.5, 99999.9, 3.3e8])
def test_suggested_samples_dt_is_accepted(t_end):
    """The spacing the --samples-dt error suggests is itself accepted (it was once rounded below the limit)."""
    import re
    from runtime.cli import build_parser, simulate_arguments_problem
    args = build_parser().parse_args(["simulate", "--t-end", str(t_end)])
    problem = simulate_arguments_problem(args, t_end)
    suggested = float(re.search(r"give --samples-dt >= (\S+) s", problem).group(1))
    args = build_parser().parse_args(["simulate", "--t-end", str(t_end), "--samples-dt", str(suggested)])
    assert simulate_arguments_problem(args, t_end) == ""
    tighter = build_parser().parse_args(["simulate", "--t-end", str(t_end), "--samples-dt", str(suggested * 0.99)])
    assert "--samples-dt" in simulate_arguments_problem(tighter, t_end)          # and it is close to the limit


def test_long_impact_table_is_summarised_unless_all_are_asked_for(capsys):
    import runtime.cli
    argv = ["simulate", "--scene", "paper-case1", "--t-end", "8", "--samples-dt", "0.01"]      # 45 impacts
    assert runtime.cli.main(argv) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line[:3].strip().isdigit()]
    total = int(rows[-1].split()[0])
    assert total > runtime.cli.TABLE_ROWS and len(rows) == runtime.cli.TABLE_ROWS
    assert f"... {total - runtime.cli.TABLE_ROWS} more impacts ..." in out and "--all-impacts" in out
    assert runtime.cli.main([*argv, "--all-impacts"]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line[:3].strip().isdigit()]
    assert [int(r.split()[0]) for r in rows] == list(range(1, total + 1)) and "more impacts" not in out
