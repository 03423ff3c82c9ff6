"""How the generator scales with n: stage timings and operation counts, as a Markdown table
(general n + 5 coordinate models of the built-in N-link scene unless --specialise).

    python -m studies scaling --links 1,2,4,8,16,32
"""
from __future__ import annotations

import argparse
import sys
import time

from codegen.pipeline import generate
from codegen.scene import default_scene

from .machine import describe


def measure(n: int, compile_code: bool = True, progress=print, specialise: bool = False) -> dict:
    scene = default_scene(n)
    model = generate(scene, progress=lambda m: progress(f"  n={n}: {m}"), specialise=specialise)
    row = {"n": n, **model.timings}
    if compile_code:
        from runtime.compile import compile_model
        start = time.perf_counter()
        # a fresh build every time (the nonce defeats the cache) so the compile time is real
        compile_model(model.name, model.header, model.source, model.cdef,
                      flags=("-O2", f"-DSCALING_NONCE={time.time_ns()}"))
        row["compile"] = time.perf_counter() - start
    ops = {f.name: f.ops for f in model.functions}
    row["ops_M"] = ops["mass_matrix"]
    row["ops_R"] = ops["bias"]
    row["ops_MR"] = ops["mass_matrix"] + ops["bias"]
    row["ops_fd"] = ops["forward_dynamics"]
    row["c_lines"] = len(model.source.splitlines())
    return row


def markdown(rows) -> str:
    lines = ["| n | derive s | CSE s | render s | compile s | I_f + R ops (add/mul/div/calls) "
             "| forward dynamics ops (add/mul/div/calls) | lines of C |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        mr, fd = r["ops_MR"], r["ops_fd"]
        lines.append(f"| {r['n']} | {r['derive']:.2f} | {r['cse']:.2f} | {r['render']:.2f} | "
                     f"{r.get('compile', float('nan')):.2f} | {mr.total:,} ({mr.add}/{mr.mul}/{mr.div}/{mr.calls}) | "
                     f"{fd.total:,} ({fd.add}/{fd.mul}/{fd.div}/{fd.calls}) | {r['c_lines']:,} |")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies scaling", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--links", default="1,2,4,8,16,32", help="comma-separated n values")
    parser.add_argument("--no-compile", action="store_true", help="skip the (fresh) cffi compile")
    parser.add_argument("--specialise", action="store_true",
                        help="measure the scene-specialised (planar, n + 2 coordinates) models instead of the "
                             "general n + 5 coordinate ones")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        ns = [int(x) for x in args.links.split(",")]
    except ValueError:
        print(f"error: --links: expected comma-separated integers, got {args.links!r}", file=sys.stderr)
        return 2
    rows = []
    for n in ns:
        print(f"n = {n} ...", file=sys.stderr, flush=True)
        rows.append(measure(n, not args.no_compile, progress=lambda m: print(m, file=sys.stderr, flush=True),
                            specialise=args.specialise))
    print(f"Machine: {describe()}")
    print(markdown(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
