"""How building a model scales with n: for the built-in N-link scene, a cold build into an empty cache --
derive, CSE and render (in worker processes from codegen.pipeline.PARALLEL_MIN_LINKS links on), the compile
(several translation units side by side for a long source), their sum -- then the warm load of the cached
model in a fresh process, the lines of C and the operation counts.  Specialised (planar, n + 2 coordinates,
what `python -m codegen --links N` builds) unless --general.

    python -m studies scaling --links 1,2,4,8,16,32,64,128,256
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

WARM_LOAD = """
import sys, time
from codegen.scene import default_scene
from runtime import load_model
scene = default_scene({n})
start = time.perf_counter()
load_model(scene, specialise={specialise})
print(time.perf_counter() - start)
"""


def measure(n: int, progress=print, specialise: bool = True) -> dict:
    """One cold build of the n-link model into a new, empty cache, and its warm load from there."""
    from codegen.cache import generate_cached
    from codegen.options import build_options
    from codegen.scene import default_scene
    scene = default_scene(n)
    with tempfile.TemporaryDirectory(prefix="scaling-") as cache:
        previous = os.environ.get("GIBBS_APPELL_CACHE")
        os.environ["GIBBS_APPELL_CACHE"] = cache
        try:
            from runtime.compile import compile_model
            start = time.perf_counter()
            model = generate_cached(scene, build_options(scene, specialise=specialise), refresh=True,
                                    progress=lambda m: progress(f"  n={n}: {m}"))
            generated = time.perf_counter() - start
            compile_model(model.name, model.header, model.source, model.cdef)
            total = time.perf_counter() - start
            warm = subprocess.run([sys.executable, "-c", WARM_LOAD.format(n=n, specialise=specialise)],
                                  capture_output=True, text=True, check=True)
        finally:
            if previous is None:
                os.environ.pop("GIBBS_APPELL_CACHE", None)
            else:
                os.environ["GIBBS_APPELL_CACHE"] = previous
    ops = {f.name: f.ops for f in model.functions}
    return {"n": n, **model.timings, "generate": generated, "compile": total - generated, "total": total,
            "warm_ms": float(warm.stdout.split()[-1]) * 1e3, "ops_fd": ops["forward_dynamics"],
            "c_lines": len(model.source.splitlines()), "nq": model.layout.nq,
            "parallel": "parallel_wall" in model.timings}


def markdown(rows) -> str:
    lines = ["| n | coordinates | derive s | CSE s | render s | generate (wall) s | compile s | cold total s "
             "| warm load ms | lines of C | forward dynamics ops |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        star = "*" if r["parallel"] else ""
        lines.append(f"| {r['n']} | {r['nq']} | {r['derive']:.2f}{star} | {r['cse']:.2f}{star} | {r['render']:.2f}{star} "
                     f"| {r['generate']:.2f} | {r['compile']:.2f} | {r['total']:.2f} | {r['warm_ms']:.1f} "
                     f"| {r['c_lines']:,} | {r['ops_fd'].total:,} |")
    if any(r["parallel"] for r in rows):
        lines.append("\n\\* summed over the worker processes (they run side by side: the wall time is the "
                     "generate column).")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies scaling", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--links", default="1,2,4,8,16,32,64", help="comma-separated n values")
    parser.add_argument("--general", action="store_true",
                        help="measure the general (n + 5 coordinate) models instead of the specialised ones")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .cli import parse_links
    try:
        ns = parse_links(args.links)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    from .machine import describe
    from .toolchain import compiler_version
    rows = []
    for n in ns:
        print(f"n = {n} ...", file=sys.stderr, flush=True)
        rows.append(measure(n, progress=lambda m: print(m, file=sys.stderr, flush=True),
                            specialise=not args.general))
    print(f"Machine: {describe(compiler_version())}")
    print(markdown(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
