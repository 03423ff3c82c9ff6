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
    for key in ("t_final", "q_final", "qd_final", "energy_initial", "energy_final", "loss_impacts",
                "energy_residual", "energy_scale", "energy_drift", "n_rhs", "n_sticks", "n_slips",
                "n_tangential_impacts"):
        assert key in data
    assert first["law"] in ("frictionless", "gdi") and first["contacts"][0]["impulse_t"] == [0.0, 0.0]
    assert 0 < first["roundoff"] < 1e-6 and first["residual"] >= 0.0
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


# ---------------------------------------------------------------------------
# the runtime runs what the generator makes: the built-in chains and URDF files
# ---------------------------------------------------------------------------
def test_simulate_runs_the_built_in_chain_of_codegen_links(capsys, monkeypatch):
    """--links N is python -m codegen --links N's scene (chain4 is the paper's case study 1: the same impacts
    as the shipped paper-case1 scene, whose model differs only by its name)."""
    import runtime.cli
    from codegen.scene import default_scene
    seen = []
    real = runtime.cli.load_model
    monkeypatch.setattr(runtime.cli, "load_model", lambda scene, **k: seen.append(scene) or real(scene, **k))
    assert runtime.cli.main(["simulate", "--links", "4"]) == 0
    chain = capsys.readouterr().out
    assert seen == [default_scene(4)] and "scene chain4: n = 4, t_end = 1.5 s" in chain
    assert runtime.cli.main(["simulate", "--scene", "paper-case1"]) == 0
    case1 = capsys.readouterr().out
    table = lambda out: [line for line in out.splitlines() if line[:3].strip().isdigit()]  # noqa: E731
    assert len(table(chain)) == 7 and table(chain) == table(case1)


@pytest.mark.parametrize("links,message", [(0, "--links: must be in 1..1024, got 0"),
                                           (1025, "--links: must be in 1..1024, got 1025")])
def test_simulate_links_out_of_range(capsys, links, message):
    import runtime.cli
    assert runtime.cli.main(["simulate", "--links", str(links)]) == 2
    assert message in capsys.readouterr().err


def test_simulate_runs_a_urdf_file_in_a_default_box(tmp_path, capsys, monkeypatch):
    """The README's two commands: a shipped scene's chain written as URDF, then run in a default box (the same file
    name as there, so the suite builds that model once)."""
    import numpy as np
    import codegen.cli
    import runtime.cli
    from codegen.scene import URDF_BOX_MARGIN, contact_points, load_scene
    monkeypatch.chdir(tmp_path)
    assert codegen.cli.main(["--scene", "urdf-arm", "--urdf", "arm.urdf"]) == 0
    urdf = tmp_path / "arm.urdf"
    scene = load_scene(urdf)
    shipped = load_scene("urdf-arm")
    assert scene.name == "arm" and scene.joints == shipped.joints and len(scene.links) == len(shipped.links)
    for mine, theirs in zip(scene.links, shipped.links):     # the URDF's decimal text: to round-off
        assert mine.kind == theirs.kind
        assert np.allclose(np.hstack([mine.length, mine.mass, mine.com, np.ravel(mine.inertia)]),
                           np.hstack([theirs.length, theirs.mass, theirs.com, np.ravel(theirs.inertia)]),
                           rtol=1e-14, atol=1e-15)
    # the box holds the chain in any orientation about its centre: every point within reach + margin of it
    points = contact_points(scene, np.array(scene.q0))
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    half = [w.position for w in scene.walls if w.name == "x1_max"][0] / 2
    assert np.allclose(centre, half, atol=1e-12) and len(scene.walls) == 6
    assert np.isclose(half, np.linalg.norm(points - centre, axis=1).max() + URDF_BOX_MARGIN)
    assert runtime.cli.main(["simulate", "--scene", str(urdf), "--t-end", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "default box of a URDF file" in out and "status 0: reached t_end" in out
