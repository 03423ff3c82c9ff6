"""What a simulated second costs against the chain's length: the built-in n-link scene (dropped in its box:
flight, impacts, resting contact) simulated for --t-end seconds, wall time per simulated second (median of
--repeats runs), with what it is made of -- steps, right-hand sides, impacts, contact events -- and ns per
right-hand side in a C loop; the exponent of a power law fitted for n >= --fit-from, for the whole run and
for the right-hand side alone.

    python -m studies simcost [--links 2,4,8,16,32,64] [--t-end 1.5] [--repeats 5] [--plot docs/simcost.png]
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies simcost", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--links", default="2,4,8,16,32,64", help="chain lengths, comma-separated "
                        "(default 2,4,8,16,32,64)")
    parser.add_argument("--t-end", type=float, default=1.5, help="simulated seconds per run (default 1.5)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per n (default 5)")
    parser.add_argument("--fit-from", type=int, default=8, help="fit the exponent on n >= this (default 8)")
    parser.add_argument("--plot", metavar="PNG", help="also draw the cost against n (log-log) with the fits")
    return parser


def fit_exponent(ns, values) -> float:
    """Least-squares slope of log(value) against log(n)."""
    slope, _ = np.polyfit(np.log(ns), np.log(values), 1)
    return float(slope)


def measure(n: int, t_end: float, repeats: int, progress=print) -> dict:
    from codegen.scene import default_scene
    from runtime import load_model, simulate
    from .timing import time_call, time_rhs
    start = time.perf_counter()
    model = load_model(default_scene(n))
    progress(f"  n = {n}: model ready in {time.perf_counter() - start:.1f} s")
    timing = time_call(lambda: simulate(model, t_end, t_eval=[]), repeats)
    run = timing.result
    if run.status != 0:
        raise RuntimeError(f"n = {n}: the run stopped early: {run.message}")
    rhs_ns = time_rhs(model.generated).median
    return {"n": n, "s_per_s": timing.median / t_end, "spread": timing.spread / t_end, "steps": run.n_steps,
            "rhs": run.n_rhs, "impacts": len(run.impacts), "contact_events": len(run.contact_events),
            "rhs_ns": rhs_ns, "rhs_share": run.n_rhs * rhs_ns * 1e-9 / timing.median}


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .cli import parse_links
    try:
        links = parse_links(args.links, low=2)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if not (args.t_end > 0 and args.repeats >= 1):
        print("error: --t-end must be > 0 and --repeats >= 1", file=sys.stderr)
        return 2
    if args.plot:
        try:
            import matplotlib
        except ImportError:
            print("error: --plot needs matplotlib (the study extra: pip install -e \".[study]\")", file=sys.stderr)
            return 2
    rows = []
    for n in links:
        rows.append(measure(n, args.t_end, args.repeats,
                            progress=lambda m: print(m, file=sys.stderr, flush=True)))
    from .machine import describe
    print(f"Machine: {describe()}")
    print(f"Built-in n-link scene, {args.t_end} s runs (DOPRI5, rtol 1e-8), median of {args.repeats}.\n")
    print("| n | ms per simulated s (spread) | steps | rhs calls | impacts | contact events | ns per rhs "
          "| ns of the run per rhs call | rhs share of the run |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        r["per_call_ns"] = r["s_per_s"] * args.t_end / r["rhs"] * 1e9
        print(f"| {r['n']} | {r['s_per_s'] * 1e3:.3f} ({r['spread'] * 1e3:.3f}) | {r['steps']} | {r['rhs']} | "
              f"{r['impacts']} | {r['contact_events']} | {r['rhs_ns']:.0f} | {r['per_call_ns']:.0f} | "
              f"{r['rhs_share']:.0%} |")
    fit = [r for r in rows if r["n"] >= args.fit_from]
    if len(fit) >= 2:
        ns = [r["n"] for r in fit]
        whole = fit_exponent(ns, [r["s_per_s"] for r in fit])
        rhs = fit_exponent(ns, [r["rhs_ns"] for r in fit])
        calls = fit_exponent(ns, [r["rhs"] for r in fit])
        per_call = fit_exponent(ns, [r["per_call_ns"] for r in fit])
        print(f"\nFitted for n >= {args.fit_from}: time per simulated second ~ n^{whole:.2f} = rhs calls ~ "
              f"n^{calls:.2f} times the run's time per rhs call ~ n^{per_call:.2f}; one rhs alone ~ n^{rhs:.2f}.")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        ns = np.array([r["n"] for r in rows])
        ax.loglog(ns, [r["s_per_s"] * 1e3 for r in rows], "o-", label="whole run, ms per simulated s")
        ax.loglog(ns, [r["rhs"] * r["rhs_ns"] * 1e-6 / args.t_end for r in rows], "s--",
                  label="its right-hand sides alone")
        if len(fit) >= 2:
            ax.set_title(f"n >= {args.fit_from}: run ~ n^{whole:.2f}, rhs ~ n^{rhs:.2f}, calls ~ n^{calls:.2f}",
                         fontsize=9)
        ax.set_xlabel("links n")
        ax.set_ylabel("ms per simulated second")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
