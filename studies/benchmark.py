"""Benchmark: the compiled hybrid loop against scipy's solve_ivp on the same compiled right-hand side.

    python -m studies benchmark [--scene paper-case1] [--t-end 1.5] [--repeat 21]

For each method and tolerance both pipelines simulate the scene with every impact; the table gives the median
wall time, the largest impact-time error against a tight reference run (DOPRI5 at rtol = 1e-13,
confirmed by RK4 at a small step), and the ratio.  The scipy baseline uses the same Runge-Kutta pair
(RK45 against DOPRI5, DOP853 against DOP853) with one terminal event per (point, wall) pair, the compiled rhs through cffi, and the compiled impact law.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from codegen.scene import load_scene
from runtime.model import CompiledModel, load_model
from runtime.simulate import simulate

from . import baseline
from .machine import describe
from .timing import time_call
from .toolchain import compiler_version


SCIPY_METHOD = {"dopri5": "RK45", "dop853": "DOP853"}


def scipy_hybrid(model: CompiledModel, t_end: float, rtol: float, atol: float, contact_tol: float = 1e-6,
                 method: str = "RK45"):
    """The outside baseline (studies.baseline): solve_ivp + events, impacts by the compiled Eq. 48.
    Returns the impact times and the number of rhs evaluations."""
    run = baseline.scipy_hybrid(model, t_end, rtol, atol, method=method, contact_tol=contact_tol)
    return run.times, run.n_rhs


def reference_times(model: CompiledModel, t_end: float) -> np.ndarray:
    tight = np.array([i.t for i in simulate(model, t_end, rtol=1e-13, atol=1e-15, t_eval=[]).impacts])
    check = np.array([i.t for i in simulate(model, t_end, method="rk4", dt=2e-5, t_eval=[]).impacts])
    if len(check) != len(tight) or np.abs(check - tight).max() > 1e-9:
        raise RuntimeError("the reference run is not confirmed by RK4 at dt = 2e-5 s")
    return tight


def error(times: np.ndarray, reference: np.ndarray) -> float:
    if len(times) != len(reference):
        return float("inf")
    return float(np.abs(times - reference).max())


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies benchmark", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="paper-case1")
    parser.add_argument("--t-end", type=float, default=1.5)
    parser.add_argument("--repeat", type=int, default=21, help="runs per measurement (median reported)")
    parser.add_argument("--rtols", default="1e-6,1e-8,1e-10,1e-12")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    model = load_model(load_scene(args.scene))
    reference = reference_times(model, args.t_end)
    print(f"Machine: {describe(compiler_version())}")
    print(f"{args.scene}, t_end = {args.t_end} s, {len(reference)} impacts; medians of {args.repeat} runs (ours), "
          f"{max(3, args.repeat // 7)} (scipy)")
    print("| method | rtol (atol = rtol/100) | compiled loop ms | impact-time error s | rhs "
          "| scipy solve_ivp + events ms | error s | rhs | speed-up |")
    print("|---|---|---|---|---|---|---|---|---|")
    for method in ("dopri5", "dop853"):
        for rtol in (float(x) for x in args.rtols.split(",")):
            atol = rtol / 100
            timing = time_call(lambda: simulate(model, args.t_end, method=method, rtol=rtol, atol=atol, t_eval=[]),
                               args.repeat)
            ours, ours_ms = timing.result, timing.median
            timing = time_call(lambda: scipy_hybrid(model, args.t_end, rtol, atol, method=SCIPY_METHOD[method]),
                               max(3, args.repeat // 7))
            (theirs, their_rhs), theirs_ms = timing.result, timing.median
            ours_err = error(np.array([i.t for i in ours.impacts]), reference)
            print(f"| {method} / {SCIPY_METHOD[method]} | {rtol:.0e} | {ours_ms * 1e3:.3f} | {ours_err:.1e} | "
                  f"{ours.n_rhs} | {theirs_ms * 1e3:.1f} | {error(theirs, reference):.1e} | {their_rhs} | "
                  f"{theirs_ms / ours_ms:.0f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
