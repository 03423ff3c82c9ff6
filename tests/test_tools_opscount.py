"""`python -m studies ops` and the raw (before CSE) operation count."""
import json
import random
import subprocess
import sys
from pathlib import Path

import pytest
import sympy as sp

import codegen
from codegen.flatten import live_assignments
from codegen.lagrange import build_kernels as lagrange_kernels
from codegen.kernels import build_kernels as gibbs_appell_kernels
from codegen.ops import raw_count_ops
from codegen.scene import MAX_LINKS, default_scene
from codegen.options import build_options
from conftest import random_scene
from studies import opscount
from studies.cli import parse_links

ROOT = Path(__file__).resolve().parent.parent
PNG = b"\x89PNG\r\n\x1a\n"


def test_raw_count_ops_is_sympy_count_ops_on_random_expressions():
    x, y, z = sp.symbols("x y z", real=True)
    rng = random.Random(1)
    atoms = [x, y, z, sp.Integer(2), sp.Rational(-1, 2), sp.Float(0.3), sp.E]

    def expression(depth):
        if depth == 0:
            return rng.choice(atoms)
        a, b = expression(depth - 1), expression(depth - 1)
        return rng.choice([a + b, a - b, a * b, a / b, -a, sp.sin(a), sp.cos(b), sp.exp(a), sp.sqrt(a),
                           a ** rng.choice([2, 3, -1, -2])])
    for _ in range(150):
        e = expression(4)
        assert raw_count_ops([e]) == sp.count_ops(e), e


@pytest.mark.parametrize("build", [gibbs_appell_kernels, lagrange_kernels], ids=["gibbs_appell", "lagrange"])
def test_raw_count_ops_is_sympy_count_ops_on_kernels(build):
    """Shared subexpressions count once per occurrence, as in sympy's tree count."""
    scene = random_scene(1, seed=3, kinds=("rigid",))
    for kernel in build(scene):
        if kernel.name in ("mass_matrix", "bias"):
            expressions = [e for _, e in live_assignments(kernel)] + list(kernel.values)
            assert raw_count_ops(expressions) == sp.count_ops(expressions)


def test_parse_links():
    assert parse_links("1-4") == [1, 2, 3, 4]
    assert parse_links("8,1,2,2") == [1, 2, 8]
    assert parse_links("1-3,16") == [1, 2, 3, 16]
    for bad in ("0-3", "4-2", "a", "1,,2", str(MAX_LINKS + 1)):
        with pytest.raises(ValueError, match="--links"):
            parse_links(bad)


def run_ops(*args):
    return subprocess.run([sys.executable, "-m", "studies", "ops", *args], cwd=ROOT, capture_output=True, text=True)


def test_cli_rejects_bad_input_clearly():
    result = run_ops("--links", "0-3")
    assert result.returncode == 2 and f"--links: every n must be in 1..{MAX_LINKS}" in result.stderr
    result = run_ops("--timeout", "-1")
    assert result.returncode == 2 and "--timeout: must be > 0" in result.stderr


def test_time_limit_is_reported_and_larger_n_skipped():
    messages = []
    rows = opscount.run_all([1, 2], specialise=False, timeout=0.2, lagrange_max=None, say=messages.append)
    assert [(r["n"], r["formulation"], r["status"]) for r in rows] == [
        (1, "gibbs_appell", "timeout"), (1, "lagrange", "timeout"),
        (2, "gibbs_appell", "skipped"), (2, "lagrange", "skipped")]
    text = opscount.markdown(rows)
    assert text.count("timed out (> 0.2 s)") == 2 and text.count("skipped (timed out at n = 1)") == 2


def tables(text: str) -> list[list[dict]]:
    """Every Markdown table of a report as a list of {header: cell} rows."""
    found, block = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            block.append([cell.strip() for cell in line.strip().strip("|").split("|")])
        elif block:
            found.append([dict(zip(block[0], row)) for row in block[2:]])
            block = []
    return found


def ratio_columns(row: dict) -> list[str]:
    return [header for header in row if (" / " in header or "ratio" in header) and "raw" not in header]


def check_shows_only_what_it_measured(text: str, rows: list[dict]):
    """Every table row of the report is about an n of this run, and a ratio appears only in a Lagrange row whose
    Gibbs-Appell partner of the same n was measured (and timed beside it) in this run."""
    measured = {(r["n"], r["formulation"]) for r in rows if r["status"] == "ok"}
    ran = {r["n"] for r in rows}
    for table in tables(text):
        for row in table:
            assert int(row["n"]) in ran, f"a table row about n = {row['n']}, which this run did not measure: {row}"
            for header in ratio_columns(row):
                if row[header]:
                    assert row.get("formulation") == "Lagrange", (header, row)
                    assert (int(row["n"]), "gibbs_appell") in measured and (int(row["n"]), "lagrange") in measured


def check_report(out: Path, ns, lagrange_ns):
    text = (out / "ops.md").read_text()
    rows = json.loads((out / "ops.json").read_text())["rows"]
    for name in ("ops_vs_n.png", "rhs_time_vs_n.png", "generation_time_vs_n.png"):
        assert (out / name).read_bytes()[:8] == PNG
    ok = {(r["n"], r["formulation"]): r for r in rows if r["status"] == "ok"}
    assert set(ok) == {(n, "gibbs_appell") for n in ns} | {(n, "lagrange") for n in lagrange_ns}
    for (n, formulation), r in ok.items():
        # the report's counts are the generator's own
        scene = default_scene(n)
        model = codegen.generate(scene, build_options(scene, specialise=False, formulation=formulation))
        counts = {f.name: f.ops.total for f in model.functions}
        for name in ("mass_matrix", "bias", "forward_dynamics"):
            assert r["ops"][name]["total"] == counts[name]
        assert r["ns_per_rhs"] > 0 and r["compile_s"] > 0 and r["c_lines"] == len(model.source.splitlines())
        assert r["raw_ops"]["bias"] > 0
        label = opscount.LABELS[formulation]
        assert f"| {n} | {label} | " in text
    check_shows_only_what_it_measured(text, rows)
    return text, rows


@pytest.mark.slow          # derives, compiles and times a model in the study's process
def test_cli_one_link_gibbs_appell_only(tmp_path):
    result = run_ops("--links", "1", "--lagrange-max", "0", "--calls", "500", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    text, _ = check_report(tmp_path, [1], [])
    assert "skipped (n > --lagrange-max 0)" in text and "skipped (n > --lagrange-max 0)" in result.stdout
    assert "n=1 gibbs_appell: derive" in result.stderr                  # progress on stderr


@pytest.mark.slow
def test_cli_links_1_2_both_formulations(tmp_path):
    result = run_ops("--links", "1-2", "--calls", "2000", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    text, rows = check_report(tmp_path, [1, 2], [1, 2])
    assert text in result.stdout


def synthetic_row(n, formulation, fd_ops, ns):
    ops = {"add": 1, "mul": 1, "div": 0, "sqrt": 0, "sincos": 0, "other": 0}
    return {"n": n, "formulation": formulation, "status": "ok", "derive_s": 0.1, "cse_s": 0.1,
            "ops": {"mass_matrix": {**ops, "total": 2}, "bias": {**ops, "total": 2},
                    "forward_dynamics": {**ops, "total": fd_ops}},
            "raw_ops": {"mass_matrix": 3, "bias": 3}, "c_lines": 10, "compile_s": 0.5,
            "ns_per_rhs": ns, "ns_per_rhs_min": ns - 1, "ns_per_rhs_max": ns + 1}


def test_report_ratios_are_this_runs_own():
    """Gibbs-Appell alone at n = 4, 8, 16, 32 (where a constant of an earlier measurement could be divided in):
    no ratio; Lagrange beside Gibbs-Appell at n = 3: the operation ratio of the two rows and the time ratio
    measured batch by batch, as given."""
    rows = [synthetic_row(n, "gibbs_appell", 100 * n, 50.0 * n) for n in (4, 8, 16, 32)]
    rows += [synthetic_row(3, "gibbs_appell", 300, 150.0), synthetic_row(3, "lagrange", 2400, 1200.0)]
    rows[-1]["rhs_ratio"] = {"median": 7.5, "min": 7.25, "max": 8.5}
    text = opscount.markdown(rows)
    check_shows_only_what_it_measured(text, rows)
    (table,) = tables(text)
    lagrange = next(row for row in table if row["formulation"] == "Lagrange")
    assert lagrange["ops / Gibbs–Appell"] == "8.00"                       # 2400 / 300
    assert lagrange["time / Gibbs–Appell"] == "7.50 (7.25-8.50)"
    assert "Pinocchio" not in "".join(row["formulation"] for row in table)
    for row in table:
        if row["formulation"] == "Gibbs–Appell":
            assert all(row[h] == "" for h in ratio_columns(row)), row

