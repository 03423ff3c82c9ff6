"""The stress suite (studies/stress.py, studies/stress_cases.py): every fast case passes, the
requirement checks can fail, and python -m studies stress prints the table and sets the exit code."""
import copy
import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from studies import stress, stress_cases
from studies.cli import main as cli_main
from studies.stress import Case, Expect, evaluate, run_case

ROOT = Path(__file__).resolve().parent.parent
CASES = {case.name: case for case in stress_cases.CASES}


def marks(case):
    if case.slow:
        return [pytest.mark.slow]
    if case.known_issue:
        return [pytest.mark.xfail(reason=case.known_issue, strict=True)]
    return []


@pytest.mark.parametrize("case", [pytest.param(case, id=case.name, marks=marks(case)) for case in stress_cases.CASES])
def test_case_passes(case):
    outcome = run_case(case)
    assert outcome.passed, outcome.reasons
    assert outcome.row["result"] == "PASS"


def test_every_kind_of_case_is_in_the_suite():
    names = set(CASES)
    for required in ("mass-ratio-light", "mass-ratio-heavy", "length-ratio-short", "length-ratio-long",
                     "tiny-axial-1e-6", "spin-axial-200", "spin-across-200", "chain-16", "chain-32", "corner",
                     "corner-3d", "flat-drop", "graze", "graze-shallow", "graze-shallow-1e-4-dop853",
                     "graze-shallow-1e-7-dopri5", "graze-miss", "rest-on-floor",
                     "outside-box", "outside-box-q0", "bad-option"):
        assert required in names
    assert CASES["chain-32"].slow
    with pytest.raises(ValueError, match="appears twice"):
        stress.check_cases([*stress_cases.CASES, copy.copy(CASES["corner"])])


def _coarse_case():
    """The graze scene with the floor raised 1 cm, RK4 at dt = 0.1 s (1 rad of the 10 rad/s spin per step):
    the dip is found, but the samples between the step ends come from the cubic Hermite interpolant, whose
    energy rises 2e-5 above the initial one: a genuine FAIL of the energy requirement."""
    return Case(name="coarse-rk4", scene="stress-graze", description="coarse RK4", params={"wall_x2_min": 0.01},
                simulate={"t_end": 0.2, "method": "rk4", "dt": 0.1, "event_samples": 1})


def test_penetration_is_caught():
    """A sample 1 cm below the floor (the event search no longer misses such a dip, so the run is
    doctored): requirement 2 reports it."""
    run = _completed_run("graze-miss")
    gap = run.model.contact_gaps(run.model.layout.reduce(run.result.q[100]), run.p).min()
    run.result.q[100, 4] -= gap + 0.01                 # the rod moved down: its lower point 1 cm inside
    outcome = evaluate(run)
    assert not outcome.passed
    assert any(reason.startswith("penetration 0.0") for reason in outcome.reasons), outcome.reasons
    assert 0.009 < outcome.row["max_penetration"] < 0.011, outcome.row["max_penetration"]


def _completed_run(name):
    """The CaseRun of a case (for doctoring its result and evaluating it again)."""
    from runtime import load_model, simulate
    case = CASES[name]
    run = stress.CaseRun(case, scene=stress.build_scene(case))
    run.model = load_model(run.scene)
    run.p = stress.parameter_vector(run.scene, run.model, case.params)
    kwargs = dict(case.simulate)
    t_end = kwargs.pop("t_end")
    run.result = simulate(run.model, t_end, p=run.p, t_eval=np.linspace(0, t_end, 201), **kwargs)
    assert evaluate(run).passed
    return run


def test_energy_gain_nan_and_impulse_errors_are_caught():
    run = _completed_run("corner")
    run.result.qd[150] *= 1.001                         # a sample with 0.2 % more kinetic energy
    outcome = evaluate(run)
    assert any(r.startswith("energy gain") for r in outcome.reasons), outcome.reasons
    run = _completed_run("corner")
    run.result.q[7, 3] = math.nan
    assert evaluate(run).reasons[:1] == ["NaN or infinity in the samples, impacts or final state"]
    run = _completed_run("corner")
    run.result.impacts[0].contacts[0].impulse *= 1.01  # Newton-Euler no longer balances
    outcome = evaluate(run)
    assert any("impulse-momentum balance" in r for r in outcome.reasons), outcome.reasons


def test_expected_outcomes_are_enforced():
    outcome = run_case(replace(CASES["outside-box"], expect=Expect.ok()))
    assert not outcome.passed and outcome.reasons[0].startswith("raised SceneError: initial.q: contact point O_3")
    outcome = run_case(replace(CASES["corner"], expect=Expect.raises("anything")))
    assert not outcome.passed and "expected an error" in outcome.reasons[0]
    stopped = replace(CASES["flat-drop"], checks=(), simulate={**CASES["flat-drop"].simulate, "max_impacts": 2})
    assert run_case(replace(stopped, expect=Expect.status("max_impacts limit"))).passed
    outcome = run_case(replace(stopped, expect=Expect.status("no such message")))
    assert not outcome.passed and "does not match" in outcome.reasons[0]
    outcome = run_case(replace(stopped, expect=Expect.ok()))
    assert not outcome.passed and outcome.reasons[0].startswith("status -1: stopped after 2 impacts")


def test_cli_table_json_and_exit_codes(monkeypatch, capsys):
    result = subprocess.run([sys.executable, "-m", "studies", "stress", "--only", "corner", "graze-miss", "--json"],
                            capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)
    assert [r["case"] for r in rows] == ["corner", "graze-miss"] and all(r["result"] == "PASS" for r in rows)
    assert rows[0]["impacts"] == 1 and rows[0]["max_penetration"] < 1e-12 and rows[0]["notes"]
    assert "[1/2] corner ..." in result.stderr
    # the table, and exit code 1 when a case fails
    monkeypatch.setattr(stress_cases, "CASES", (CASES["corner"], _coarse_case()))
    assert cli_main(["stress"]) == 1
    out = capsys.readouterr().out
    assert "| case | n | method | impacts | t_final/t_end | energy drift |" in out
    assert "| corner | 1 | dopri5 | 1 | 0.5/0.5 |" in out and "| PASS |" in out
    assert "| coarse-rk4 | 1 | rk4 | 1 |" in out and "FAIL: energy gain" in out and "1 passed, 1 failed" in out
    assert cli_main(["stress", "--only", "corner"]) == 0
    assert cli_main(["stress", "--only", "nope"]) == 2
    assert "unknown case(s) nope" in capsys.readouterr().err


def test_simulate_refuses_impossible_starts_and_parameters():
    from runtime import load_model, simulate
    model = load_model("stress-corner")
    q0 = [-math.pi / 2, 0.0, -math.pi / 4, 0.4, -0.05, 0.0]          # O_1 5 cm below the floor
    with pytest.raises(ValueError, match=r"^q0: contact point O_1 is outside the wall x2_min: X2 = -0.05 m"):
        simulate(model, 0.1, q0=q0)
    with pytest.raises(ValueError, match=r"^qd0: must be finite"):
        simulate(model, 0.1, qd0=[0.0, 0.0, math.nan, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"^p: expected 14 finite values \(g, l_1, mu_1"):
        simulate(model, 0.1, p=model.p[:-1])
    p = model.p.copy()
    p[model.scene.parameter_names().index("e_x2_min")] = 1.5
    with pytest.raises(ValueError, match=r"^p\[e_x2_min\]: restitution must be in \[0, 1\], got 1.5"):
        simulate(model, 0.1, p=p)
    p = model.p.copy()
    p[model.scene.parameter_names().index("wall_x1_min")] = 0.45         # the wall moved past O_1
    with pytest.raises(ValueError, match=r"^initial.q: contact point O_1 is outside the wall x1_min"):
        simulate(model, 0.1, p=p)
