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


def check_report(out: Path, ns, lagrange_ns):
    text = (out / "ops.md").read_text()
    rows = json.loads((out / "ops.json").read_text())["rows"]
    for name in ("ops_vs_n.png", "rhs_time_vs_n.png", "generation_time_vs_n.png"):
        assert (out / name).read_bytes()[:8] == PNG
    ok = {(r["n"], r["formulation"]): r for r in rows if r["status"] == "ok"}
    assert set(ok) == {(n, "gibbs_appell") for n in ns} | {(n, "lagrange") for n in lagrange_ns}
    for (n, formulation), r in ok.items():
        # the report's counts are the generator's own
        model = codegen.generate(default_scene(n), specialise=False, formulation=formulation)
        counts = {f.name: f.ops.total for f in model.functions}
        for name in ("mass_matrix", "bias", "forward_dynamics"):
            assert r["ops"][name]["total"] == counts[name]
        assert r["ns_per_rhs"] > 0 and r["compile_s"] > 0 and r["c_lines"] == len(model.source.splitlines())
        assert r["raw_ops"]["bias"] > 0
        label = opscount.LABELS[formulation]
        assert f"| {n} | {label} | " in text
    return text, rows


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
