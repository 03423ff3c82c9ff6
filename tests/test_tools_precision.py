"""python -m studies precision: the work-precision study (reference, error measures, table, plot)."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from studies.precision import Outcome, compare, energy_drift

ROOT = Path(__file__).resolve().parent.parent
CASE1_FREE_FALL = math.sqrt(2 * 0.3 / 9.81)       # first impact of case 1: O1, O5 fall 0.3 m from rest


def run(*args):
    return subprocess.run([sys.executable, "-m", "studies", "precision", *args], capture_output=True, text=True,
                          cwd=ROOT)


@pytest.fixture(scope="module")
def quick_case1(tmp_path_factory):
    out = tmp_path_factory.mktemp("precision")
    result = run("--scene", "paper-case1", "--quick", "--out", str(out))
    assert result.returncode == 0, result.stderr
    return result, out, json.loads((out / "precision-paper-case1.json").read_text())


def rows(study, family):
    return sorted((r for r in study["rows"] if r["family"] == family), key=lambda r: -r["value"])


def test_quick_study_writes_table_json_and_plot(quick_case1):
    result, out, study = quick_case1
    table = (out / "precision-paper-case1.md").read_text()
    assert table in result.stdout
    assert "| method | setting | CPU ms |" in table and "| RK4 | dt = 1e-05 s |" in table
    for family in ("RK4", "DOPRI5", "DOP853", "scipy RK45", "scipy DOP853", "scipy Radau"):
        assert f"| {family} |" in table
    png = (out / "precision-paper-case1.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    assert "[1/" in result.stderr                              # progress on stderr
    for row in study["rows"]:
        assert row["cpu_s"] > 0 and row["n_rhs"] > 0 and row["repeats"] >= 1


def test_reference_is_confirmed_and_independently_right(quick_case1):
    _, _, study = quick_case1
    reference = study["reference"]
    times = reference["impact_times"]
    assert len(times) == 7
    assert abs(times[0] - CASE1_FREE_FALL) < 1e-12                  # closed form, independent of any integrator
    assert len(reference["confirmations"]) == 2
    for confirmation in reference["confirmations"]:
        assert confirmation["matched"] == 7 and confirmation["missed"] == 0 and confirmation["extra"] == 0
        assert confirmation["impact_time_error"] < 1e-10 and confirmation["state_error"] < 1e-7
    assert reference["energy_drift"] < 1e-12


@pytest.mark.parametrize("family", ["DOPRI5", "DOP853"])
def test_errors_fall_as_the_tolerance_tightens(quick_case1, family):
    _, _, study = quick_case1
    converged = [r for r in rows(study, family) if r["missed"] == 0 and r["extra"] == 0]
    assert [r["value"] for r in converged] == [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]   # every run keeps the 7
    for looser, tighter in zip(converged, converged[1:]):            # each step is 100x tighter
        assert tighter["impact_time_error"] < looser["impact_time_error"]
        assert tighter["state_error"] < looser["state_error"]
        assert tighter["n_rhs"] > looser["n_rhs"]
    assert converged[-1]["impact_time_error"] < 1e-3 * converged[0]["impact_time_error"]
    for row in converged:                                            # the error follows the tolerance
        assert row["impact_time_error"] < 10 * row["value"]


def test_loose_runs_keep_the_symmetric_pairs_and_a_split_is_reported(quick_case1):
    """The simultaneity window follows the tolerance, so DOPRI5 and DOP853 keep case 1's 7 impacts (symmetric
    pairs together) at rtol 1e-4 and 1e-6; scipy's solve_ivp baseline, whose window does not, splits the pair
    at impact 6 at rtol 1e-6, and the study reports where its sequence diverges."""
    _, _, study = quick_case1
    for row in study["rows"]:
        if row["family"] in ("DOPRI5", "DOP853"):
            assert row["matched"] == 7 and row["missed"] == 0 and row["extra"] == 0, row
    split = [r for r in study["rows"] if r["value"] == 1e-6 and r["family"].startswith("scipy RK45")]
    for row in split:
        assert row["matched"] < 7 and row["missed"] == 7 - row["matched"] and row["extra"] > 0
        assert row["note"].startswith(f"diverges at impact {row['matched'] + 1}")
        assert row["state_error"] > 1e-2


def test_rk4_error_falls_as_dt_to_the_fourth(quick_case1):
    _, _, study = quick_case1
    by_dt = {r["value"]: r for r in rows(study, "RK4")}
    coarse, fine = by_dt[1e-3], by_dt[5e-4]
    assert coarse["matched"] == fine["matched"] == 7
    order = math.log2(coarse["impact_time_error"] / fine["impact_time_error"])
    assert 3.0 < order < 5.0, order
    assert fine["n_rhs"] == pytest.approx(2 * coarse["n_rhs"], rel=0.01)      # 4 per step
    paper = by_dt[1e-5]
    assert paper["matched"] == 7 and paper["impact_time_error"] < 1e-10


def test_scipy_baseline_finds_the_same_impacts(quick_case1):
    _, _, study = quick_case1
    for family in ("scipy RK45", "scipy DOP853"):
        tight = [r for r in rows(study, family) if r["value"] == 1e-10][0]
        assert tight["matched"] == 7 and tight["missed"] == tight["extra"] == 0, tight["note"]
        assert tight["impact_time_error"] < 1e-8 and tight["state_error"] < 1e-5
    radau = rows(study, "scipy Radau")[0]
    assert radau["matched"] == 7 and radau["impact_time_error"] < 1e-5


def outcome(impacts, energy_initial=10.0, energy_final=10.0, x_final=(0.0, 0.0), status=0):
    return Outcome([(t, frozenset(c), before, after) for t, c, before, after in impacts], 1.0,
                   np.array(x_final), energy_initial, energy_final, 1, status, "")


def test_compare_matches_in_order_by_contact_set():
    a, b = {(1, "x2_min"), (5, "x2_min")}, {(3, "x2_min")}
    reference = outcome([(0.2, a, 10, 10), (0.5, b, 10, 10), (0.9, a, 10, 10)])
    same = compare(outcome([(0.2 + 1e-9, a, 10, 10), (0.5 - 3e-9, b, 10, 10), (0.9, a, 10, 10)],
                           x_final=(1e-6, -2e-6)), reference)
    assert (same.matched, same.missed, same.extra, same.note) == (3, 0, 0, "")
    assert same.impact_time_error == pytest.approx(3e-9) and same.state_error == pytest.approx(2e-6)
    split = compare(outcome([(0.2, a, 10, 10), (0.5, {(3, "x2_min"), (2, "x2_min")}, 10, 10),
                             (0.6, b, 10, 10), (0.8, a, 10, 10)], x_final=(0.5, 0.0)), reference)
    assert (split.matched, split.missed, split.extra) == (1, 2, 3) and split.diverged
    assert split.note.startswith("diverges at impact 2: O2/x2_min+O3/x2_min at 0.500000 s, reference O3/x2_min")
    assert split.impact_time_error == 0.0
    missed = compare(outcome([(0.2, a, 10, 10)]), reference)
    assert (missed.matched, missed.missed, missed.extra) == (1, 2, 0)
    assert missed.note == "diverges at impact 2: no impact, reference O3/x2_min at 0.500000 s"
    stopped = compare(outcome([(0.2, a, 10, 10)], status=-1), reference)
    assert stopped.state_error == math.inf and "stopped" in stopped.note


def test_energy_drift_leaves_out_what_the_impacts_remove():
    # E0 = 10; the flight gains 1e-3 before the impact, the impact removes 2.001, the flight gains 5e-4 more
    run = outcome([(0.3, {(1, "x2_min")}, 10.001, 8.0)], energy_initial=10.0, energy_final=8.0005)
    assert energy_drift(run) == pytest.approx(1.5e-3 / 10)
    assert energy_drift(outcome([], energy_final=10.0 - 2e-9)) == pytest.approx(2e-10)


def in_process(capsys, *args):
    """The command in this process (faster than a subprocess; an uncaught exception fails the test)."""
    from studies.cli import main
    code = main(["precision", *args])
    return code, capsys.readouterr()


def test_unconfirmed_reference_fails_loudly(tmp_path, capsys):
    code, output = in_process(capsys, "--scene", "paper-case1", "--t-end", "0.5", "--time-tol", "1e-18",
                              "--out", str(tmp_path))
    assert code == 1
    assert "error: the reference is not confirmed: DOPRI5 rtol = 1e-13: impact times differ by" in output.err
    assert list(tmp_path.iterdir()) == []


def test_bad_options_are_named(capsys):
    code, output = in_process(capsys, "--scene", "paper-case1", "--t-end", "-1")
    assert code == 2 and "--t-end: must be a finite number > 0, got -1.0" in output.err
    code, output = in_process(capsys, "--scene", "no-such-scene")
    assert code == 2 and "shipped scenes" in output.err
    code, output = in_process(capsys, "--scene", "paper-case1", "--out", "/dev/null/precision")
    assert code == 2 and "--out: cannot create /dev/null/precision" in output.err


@pytest.mark.slow
def test_full_study_on_case2(tmp_path):
    result = run("--scene", "paper-case2", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    study = json.loads((tmp_path / "precision-paper-case2.json").read_text())
    assert len(study["reference"]["impact_times"]) == 11
    for family in ("DOPRI5", "DOP853", "scipy RK45", "scipy DOP853"):
        tight = [r for r in study["rows"] if r["family"] == family and r["value"] == 1e-12][0]
        assert tight["matched"] == 11 and tight["impact_time_error"] < 1e-9, (family, tight)
    paper = [r for r in study["rows"] if r["family"] == "RK4" and r["value"] == 1e-5][0]
    assert paper["matched"] == 11 and paper["impact_time_error"] < 1e-10
    assert (tmp_path / "precision-paper-case2.png").stat().st_size > 20_000
