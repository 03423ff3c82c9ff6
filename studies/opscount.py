"""Operation counts and timings of the recursive Gibbs-Appell model against a Lagrangian expansion.

    python -m studies ops --links 1-8 [--out DIR] [--specialise] [--timeout S] [--lagrange-max N]

For every n and both formulations (codegen.kernels's Gibbs-Appell kernels, codegen.lagrange's expansion)
it generates the model of the built-in n-link scene (the general n + 5 coordinate model unless
--specialise) and reports: the derivation and CSE times (all kernels of the model), the operation counts
after CSE of I_f (mass_matrix), R (bias) and the forward dynamics (rule in codegen.ops), sympy's raw
``count_ops`` of I_f and R before CSE, the lines of C, the compile time (``cc -std=c99 -O2 -c`` of the
model's .c, studies.toolchain) and the time per right-hand-side evaluation from a C timing loop, both
formulations of one n in one C program, alternating batches (studies.timing.time_rhs_side_by_side; no
Python in the loop), so that the Lagrange / Gibbs-Appell time ratio is measured, batch by batch, in this
run.  Output: a Markdown table on stdout and in DIR/ops.md, the rows as DIR/ops.json, and PNG plots in DIR.
Against Pinocchio's articulated-body algorithm: python -m studies peer (also side by side in one program).

Every (n, formulation) runs in its own process with a time limit (--timeout); a formulation that runs
out of time is reported as such and, being slower still for larger n, not tried again for larger n.
--lagrange-max skips the Lagrangian path beyond some n.  Nothing is dropped silently: the table says so.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from codegen.outputs import output_dir_problem

from .cli import parse_links
from .machine import describe
from .toolchain import compile_c, compiler_version

FORMULATIONS = ("gibbs_appell", "lagrange")
LABELS = {"gibbs_appell": "Gibbs–Appell", "lagrange": "Lagrange"}
START_VARIABLE = "CODEGEN_OPS_T0"


# ---------------------------------------------------------------------------
# one measurement (runs in a child process)
# ---------------------------------------------------------------------------
def measure(n: int, formulation: str, specialise: bool = False, progress=None, keep: Path | None = None) -> dict:
    """Generate, count and compile one model; returns a JSON-able row.  With ``keep`` the model's text is
    written there (``NAME.h``, ``NAME.c``, NAME = ``model_name(n, formulation)``) for the timing, which
    run_all does for both formulations of one n together."""
    from codegen.options import build_options
    from codegen.pipeline import generate, raw_dynamics_ops
    from codegen.scene import default_scene

    say = progress or (lambda message: None)
    scene = default_scene(n)
    options = build_options(scene, specialise=specialise, formulation=formulation, dense=True)
    start = time.perf_counter()
    model = generate(scene, options, name=model_name(n, formulation), progress=say)
    generation = time.perf_counter() - start
    raw = raw_dynamics_ops(scene, options, progress=say)
    ops = {f.name: f.ops for f in model.functions}
    say("compile (cc -std=c99 -O2 -c)")
    compile_seconds = _compile_seconds(model)
    if keep is not None:
        (Path(keep) / f"{model.name}.h").write_text(model.header)
        (Path(keep) / f"{model.name}.c").write_text(model.source)
    return {
        "n": n, "formulation": formulation, "status": "ok", "nq": model.layout.nq, "name": model.name,
        "derive_s": model.timings["derive"], "cse_s": model.timings["cse"], "render_s": model.timings["render"],
        "generation_s": generation,
        "ops": {name: _op_dict(ops[name]) for name in ("mass_matrix", "bias", "forward_dynamics")},
        "raw_ops": raw, "c_lines": len(model.source.splitlines()),
        "compile_s": compile_seconds,
    }


def model_name(n: int, formulation: str) -> str:
    """The C name of one measured model (the two formulations of one n are linked into one timing program)."""
    return f"chain{n}_{formulation}"


def _op_dict(count) -> dict:
    return {"add": count.add, "mul": count.mul, "div": count.div, "sqrt": count.sqrt, "sincos": count.trig,
            "other": count.other_calls, "total": count.total}


def _compile_seconds(model) -> float:
    from runtime.compile import LIBRARY_DIR
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / f"{model.name}.h").write_text(model.header)
        (folder / f"{model.name}.c").write_text(model.source)
        return compile_c([folder / f"{model.name}.c"], folder, flags=("-O2",), include_dirs=[folder, LIBRARY_DIR],
                         link=False)


def run_child(n: int, formulation: str, specialise: bool, timeout: float, say, keep: Path) -> dict:
    """measure() in a child process with a time limit (the model's text written to ``keep``); a row with
    status 'timeout'/'error' otherwise."""
    command = [sys.executable, "-m", "studies.opscount", "--one", str(n), "--formulation", formulation,
               "--keep", str(keep)]
    if specialise:
        command.append("--specialise")
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=None, text=True, env=env,
                             start_new_session=True)
    try:
        out, _ = child.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(child.pid, signal.SIGKILL)                     # the child and the compilers it started
        child.communicate()
        say(f"n={n} {formulation}: timed out after {timeout:g} s")
        return {"n": n, "formulation": formulation, "status": "timeout", "note": f"timed out (> {timeout:g} s)"}
    if child.returncode != 0:
        return {"n": n, "formulation": formulation, "status": "error",
                "note": f"failed (exit {child.returncode}, see stderr)"}
    row = json.loads(out.strip().splitlines()[-1])
    say(f"n={n} {formulation}: done in {time.perf_counter() - start:.1f} s")
    return row


def default_calls(row: dict) -> int:
    """rhs calls per timing batch: about 2e8 operations of the forward dynamics per batch (at most 100,000 calls)."""
    return max(200, min(100000, int(2e8 / max(row["ops"]["forward_dynamics"]["total"], 1))))


def time_side_by_side(rows: list[dict], keep: Path, say, calls: int | None = None) -> None:
    """Time the rhs of every measured model of one n in one C program (alternating batches) and write into
    the rows ns_per_rhs (median, min, max over the batches) and, for Lagrange beside Gibbs-Appell, the time
    ratio batch by batch (``rhs_ratio``: Lagrange / Gibbs-Appell, median, min, max)."""
    from types import SimpleNamespace

    from .timing import BATCHES, ratios, time_rhs_side_by_side
    models = [SimpleNamespace(name=r["name"], header=(keep / f"{r['name']}.h").read_text(),
                              source=(keep / f"{r['name']}.c").read_text()) for r in rows]
    counts = [calls or default_calls(r) for r in rows]
    say(f"n={rows[0]['n']}: time rhs in C, " + " beside ".join(LABELS[r["formulation"]] for r in rows)
        + f" ({' / '.join(map(str, counts))} calls x {BATCHES} batches)")
    timings = time_rhs_side_by_side(models, counts)
    for r, timing, count in zip(rows, timings, counts):
        r.update(ns_per_rhs=timing.median, ns_per_rhs_min=timing.low, ns_per_rhs_max=timing.high,
                 timing_calls=count, timed_with=[x["formulation"] for x in rows])
    by = {r["formulation"]: timing for r, timing in zip(rows, timings)}
    if "gibbs_appell" in by and "lagrange" in by:
        ratio = ratios(by["lagrange"], by["gibbs_appell"])
        lagrange = next(r for r in rows if r["formulation"] == "lagrange")
        lagrange["rhs_ratio"] = {"median": ratio.median, "min": ratio.low, "max": ratio.high}


def run_all(ns, specialise: bool, timeout: float, lagrange_max: int | None, say, calls: int | None = None
            ) -> list[dict]:
    rows = []
    gave_up = {}                                                 # formulation -> n where it timed out
    with tempfile.TemporaryDirectory(prefix="ops-") as tmp:
        keep = Path(tmp)
        for n in ns:
            measured = []
            for formulation in FORMULATIONS:
                if formulation in gave_up:
                    rows.append({"n": n, "formulation": formulation, "status": "skipped",
                                 "note": f"skipped (timed out at n = {gave_up[formulation]})"})
                elif formulation == "lagrange" and lagrange_max is not None and n > lagrange_max:
                    rows.append({"n": n, "formulation": formulation, "status": "skipped",
                                 "note": f"skipped (n > --lagrange-max {lagrange_max})"})
                else:
                    say(f"n={n} {formulation} ...")
                    row = run_child(n, formulation, specialise, timeout, say, keep)
                    if row["status"] == "timeout":
                        gave_up[formulation] = n
                    rows.append(row)
                    if row["status"] == "ok":
                        measured.append(row)
            if measured:
                time_side_by_side(measured, keep, say, calls)
    return rows


# ---------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------
def _ops_cell(o: dict) -> str:
    return f"{o['total']:,} ({o['add']}/{o['mul']}/{o['div']}/{o['sqrt']}/{o['sincos']}/{o['other']})"


def markdown(rows, specialise: bool = False) -> str:
    """The report: every figure in it was measured in this run, and the one time ratio (Lagrange against
    Gibbs-Appell, per rhs) is taken batch by batch from one program that ran both."""
    layout = "specialised (planar, n + 2 coordinates)" if specialise else "general (n + 5 coordinates)"
    lines = [
        f"Built-in n-link scene, {layout}.  Operations after CSE as "
        "total (add/mul/div/sqrt/sincos/other), rule in `codegen/ops.py`; raw = sympy `count_ops` before CSE; "
        "derive and CSE times are for all kernels of the model; compile = `gcc -O2` of the model's .c; "
        "rhs = one `NAME_rhs` call in a C loop, both formulations of one n timed in one program, alternating "
        "batches: median (min-max) of the batches.  The Lagrange rows' ratios are Lagrange / Gibbs–Appell of "
        "the same n: forward dynamics operations, and rhs time batch by batch (median (min-max)).",
        "",
        "| n | formulation | derive s | CSE s | I_f ops | R ops | forward dynamics ops | raw I_f / R "
        "| lines of C | compile s | ns per rhs | ops / Gibbs–Appell | time / Gibbs–Appell |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    ours = {r["n"]: r for r in rows if r["formulation"] == "gibbs_appell" and r["status"] == "ok"}
    for r in rows:
        label = LABELS[r["formulation"]]
        if r["status"] != "ok":
            lines.append(f"| {r['n']} | {label} | {r['note']} |  |  |  |  |  |  |  |  |  |  |")
            continue
        ops, raw = r["ops"], r["raw_ops"]
        ratio_ops = ratio_time = ""
        if r["formulation"] == "lagrange" and r["n"] in ours:
            ratio_ops = f"{ops['forward_dynamics']['total'] / ours[r['n']]['ops']['forward_dynamics']['total']:.2f}"
        if "rhs_ratio" in r:
            q = r["rhs_ratio"]
            ratio_time = f"{q['median']:.2f} ({q['min']:.2f}-{q['max']:.2f})"
        ns = (f"{r['ns_per_rhs']:,.0f} ({r['ns_per_rhs_min']:,.0f}-{r['ns_per_rhs_max']:,.0f})"
              if "ns_per_rhs" in r else "not timed")
        lines.append(
            f"| {r['n']} | {label} | {r['derive_s']:.2f} | {r['cse_s']:.2f} | {_ops_cell(ops['mass_matrix'])} | "
            f"{_ops_cell(ops['bias'])} | {_ops_cell(ops['forward_dynamics'])} | "
            f"{raw['mass_matrix']:,} / {raw['bias']:,} | {r['c_lines']:,} | {r['compile_s']:.2f} | "
            f"{ns} | {ratio_ops} | {ratio_time} |")
    lines += ["", "Against Pinocchio's articulated-body algorithm traced by CasADi: `python -m studies peer` "
              "(both forward dynamics side by side in one C program)."]
    return "\n".join(lines)


def machine() -> str:
    import sympy
    return describe(f"sympy {sympy.__version__}", compiler_version())


def plots(rows, out: Path) -> list[Path]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    ok = {f: [r for r in rows if r["formulation"] == f and r["status"] == "ok"] for f in FORMULATIONS}
    ns = sorted({r["n"] for r in rows})
    style = {"gibbs_appell": "tab:blue", "lagrange": "tab:red"}
    paths = []

    def finish(ax, ylabel, title, path):
        ticks = sorted({int(x) for line in ax.lines for x in line.get_xdata()} | set(ns))
        ax.set_xscale("log", base=2)
        if any(len(line.get_ydata()) for line in ax.lines):
            ax.set_yscale("log")
        else:
            ax.text(0.5, 0.5, "no successful measurement", transform=ax.transAxes, ha="center")
        ax.set_xticks(ticks or [1])
        ax.set_xticklabels([str(n) for n in ticks] or ["1"])
        ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        ax.set_xlabel("links n")
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7)
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120)
        plt.close(ax.figure)
        paths.append(path)

    fig, ax = plt.subplots(figsize=(7, 5))
    for f, rs in ok.items():
        x = [r["n"] for r in rs]
        ax.plot(x, [r["ops"]["forward_dynamics"]["total"] for r in rs], "o-", color=style[f],
                label=f"{LABELS[f]}: forward dynamics (after CSE)")
        ax.plot(x, [r["ops"]["mass_matrix"]["total"] + r["ops"]["bias"]["total"] for r in rs], "s--",
                color=style[f], label=f"{LABELS[f]}: I_f + R (after CSE)")
        ax.plot(x, [r["raw_ops"]["mass_matrix"] + r["raw_ops"]["bias"] for r in rs], "^:", color=style[f],
                label=f"{LABELS[f]}: I_f + R, raw count_ops before CSE")
    finish(ax, "operations", "Operations against n", out / "ops_vs_n.png")

    fig, ax = plt.subplots(figsize=(7, 5))
    for f, rs in ok.items():
        rs = [r for r in rs if "ns_per_rhs" in r]
        ax.plot([r["n"] for r in rs], [r["ns_per_rhs"] / 1e3 for r in rs], "o-", color=style[f],
                label=f"{LABELS[f]}: one rhs (C loop, gcc -O2, both side by side)")
    finish(ax, "µs per call", "Time per right-hand side against n", out / "rhs_time_vs_n.png")

    fig, ax = plt.subplots(figsize=(7, 5))
    for f, rs in ok.items():
        x = [r["n"] for r in rs]
        ax.plot(x, [r["derive_s"] for r in rs], "o-", color=style[f], label=f"{LABELS[f]}: derive")
        ax.plot(x, [r["cse_s"] for r in rs], "s--", color=style[f], label=f"{LABELS[f]}: CSE")
        ax.plot(x, [r["compile_s"] for r in rs], "^:", color=style[f], label=f"{LABELS[f]}: gcc -O2")
    finish(ax, "seconds", "Generation time against n (all kernels)", out / "generation_time_vs_n.png")
    return paths


# ---------------------------------------------------------------------------
# command line
# ---------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies ops", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--links", default="1-8", help="n values: a range 1-8, a list 1,2,4 or both (default 1-8)")
    parser.add_argument("--out", metavar="DIR", help="write ops.md, ops.json and the PNG plots here")
    parser.add_argument("--specialise", action="store_true",
                        help="measure the scene-specialised models (planar: n + 2 coordinates) instead of the "
                             "general n + 5 coordinate ones")
    parser.add_argument("--timeout", type=float, default=1800.0, metavar="S",
                        help="time limit per (n, formulation) in seconds (default 1800); a formulation that "
                             "exceeds it is reported and not tried for larger n")
    parser.add_argument("--lagrange-max", type=int, metavar="N",
                        help="skip the Lagrangian expansion for n > N (reported in the table)")
    parser.add_argument("--calls", type=int, metavar="K",
                        help="rhs calls per timing batch (7 batches, median; default: about 2e8 operations per batch)")
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)            # child process: one measurement
    parser.add_argument("--formulation", choices=FORMULATIONS, help=argparse.SUPPRESS)
    parser.add_argument("--keep", help=argparse.SUPPRESS)                     # child: where the model's text goes
    return parser


def parse_args(argv=None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    os.environ.setdefault(START_VARIABLE, repr(time.time()))     # children time from the parent's start
    t0 = float(os.environ[START_VARIABLE])

    def say(message: str) -> None:
        print(f"[{time.time() - t0:8.1f} s] {message}", file=sys.stderr, flush=True)

    if args.one is not None:                                     # child: one row of JSON on stdout
        row = measure(args.one, args.formulation, args.specialise,
                      progress=lambda m: say(f"n={args.one} {args.formulation}: {m}"),
                      keep=Path(args.keep) if args.keep else None)
        print(json.dumps(row))
        return 0
    try:
        ns = parse_links(args.links)
        if args.timeout <= 0:
            raise ValueError(f"--timeout: must be > 0 seconds, got {args.timeout:g}")
        if args.calls is not None and args.calls < 1:
            raise ValueError(f"--calls: must be >= 1, got {args.calls}")
        if args.lagrange_max is not None and args.lagrange_max < 0:
            raise ValueError(f"--lagrange-max: must be >= 0, got {args.lagrange_max}")
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.out:
        import importlib.util
        problem = output_dir_problem("--out", args.out) or ("" if importlib.util.find_spec("matplotlib") else
                                                            "--out: the plots need matplotlib, which is not installed "
                                                            "(pip install -e \".[study]\")")
        if problem:
            print(f"error: {problem}", file=sys.stderr)
            return 2
    rows = run_all(ns, args.specialise, args.timeout, args.lagrange_max, say, args.calls)
    text = f"Machine: {machine()}.\n\n" + markdown(rows, args.specialise)
    print(text)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "ops.md").write_text(text + "\n")
        (out / "ops.json").write_text(json.dumps({"machine": machine(), "specialise": args.specialise,
                                                  "rows": rows}, indent=1) + "\n")
        written = plots(rows, out)
        say(f"wrote {out / 'ops.md'}, {out / 'ops.json'}, " + ", ".join(str(p) for p in written))
    return 0 if all(r["status"] in ("ok", "skipped", "timeout") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
