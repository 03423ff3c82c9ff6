"""Studies' reports show what they measured: where two variants of a model are compared (`python -m studies
driven`, `python -m studies specialise`) the ratio comes from one program (or one process) that ran both, batch
by batch, shown as median (min-max) of the batches; a row labelled "one chart" ran one chart."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
RATIO = re.compile(r"^(\d+\.\d+) \((\d+\.\d+)-(\d+\.\d+)\)$")


def study(*args) -> str:
    out = subprocess.run([sys.executable, "-m", "studies", *args], cwd=ROOT, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def table(text: str, first_header: str) -> list[dict]:
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(f"| {first_header} |"))
    headers = [h.strip() for h in lines[start].strip("|").split("|")]
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append(dict(zip(headers, (c.strip() for c in line.strip().strip("|").split("|")))))
    return rows


def check_ratio(cell: str):
    match = RATIO.match(cell)
    assert match, f"expected a ratio as median (min-max) of paired batches, got {cell!r}"
    median, low, high = map(float, match.groups())
    assert 0 < low <= median <= high


@pytest.mark.slow          # builds and times two models in a study's process
def test_driven_study_times_passive_and_driven_side_by_side():
    text = study("driven", "--links", "2", "--repeats", "1", "--runs", "2")
    assert text.startswith("Machine: ")
    (row,) = table(text, "n")
    check_ratio(row["driven / passive"])


@pytest.mark.slow          # builds and times two models in a study's process
def test_specialise_study_times_general_and_specialised_side_by_side():
    text = study("specialise", "--repeat", "1", "--scenes", "paper-case2")
    assert text.startswith("Machine: ")
    rows = table(text, "scene")
    assert [(r["scene"], r["model"]) for r in rows] == [("paper-case2", "general"), ("paper-case2", "specialised")]
    for r in rows:
        if r["model"] == "specialised":
            check_ratio(r["general / specialised per rhs"])
        else:
            assert r["general / specialised per rhs"] == ""


def test_charts_study_one_chart_row_runs_one_chart():
    """The gimbal-lock scene's single chart stops before the lock at t = 0.25 s (simulate would otherwise
    switch charts itself); the chart-switching run gets through it to 0.5 s."""
    from studies.charts_report import lock_table
    text = lock_table(methods=("dop853",), rtols=(1e-10,))
    one, switching = table(text, "method")
    assert one["run"] == "one chart" and switching["run"].startswith("charts")
    assert float(one["reaches t (s)"]) < 0.25 and float(switching["reaches t (s)"]) == 0.5


@pytest.mark.slow          # builds and times two models in a study's process
def test_links_study_times_a_scene_with_and_without_its_link_pairs():
    text = study("links", "--scenes", "capsule-chain", "--links", "0", "--t-end", "1", "--repeats", "2", "--runs", "1")
    assert text.startswith("Machine: ")
    (row,) = table(text, "scene")
    assert row["scene"] == "capsule-chain" and row["link pairs"] == "1" and row["same run"] == "yes"
    check_ratio(row["with / without (time)"])
    assert row["rhs ratio"] == "1.000"
