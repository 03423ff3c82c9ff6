"""Figures for docs/simulation.md, "Near gimbal lock: chart switching":  python -m studies charts

1. The gimbal-lock scene over its first 0.5 s (free flight through the lock at t = 0.25 s): one chart
   (``simulate(..., charts=False)``) against chart switching in the C loop (the default), for DOPRI5 and DOP853 at several tolerances: how far each gets, its steps,
   energy drift and largest error of the points O_1..O_3 against an independent integration (the numpy
   reference model with the base orientation as a rotation matrix, scipy DOP853 at rtol = 1e-12;
   studies.reference.integrate_reference, which tests/test_sim_charts.py checks the runtime against too).
2. Long runs with impacts: the gimbal-lock scene for 10 s, case 2 for 20 s, with and without charts.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from codegen.charts import Chart
from codegen.scene import load_scene
from runtime.model import load_model
from runtime.simulate import simulate

from .machine import describe
from .reference import integrate_reference
from .timing import time_call


def _timed(fn, repeat: int = 3):
    """(result, median wall time in s) of ``repeat`` runs after a first one (studies.timing)."""
    timing = time_call(fn, repeat)
    return timing.result, timing.median


def lock_table(max_steps: int = 20000, methods=("dopri5", "dop853"), rtols=(1e-6, 1e-8, 1e-10, 1e-12)) -> str:
    scene = load_scene("gimbal-lock")
    model = load_model(scene)
    t_end = 0.5
    te = np.linspace(0.0, t_end, 101)
    print("independent reference ...", file=sys.stderr, flush=True)
    expected = integrate_reference(scene, te)
    lines = ["| method | rtol | run | reaches t (s) | steps | energy drift | max point error (m) | ms |",
             "|---|---|---|---|---|---|---|---|"]
    for method in methods:
        for rtol in rtols:
            opts = {"method": method, "rtol": rtol, "atol": rtol / 100, "t_eval": te}
            plain, t_plain = _timed(lambda: simulate(model, t_end, max_steps=max_steps, charts=False, **opts), 1)
            charts, t_charts = _timed(lambda: simulate(model, t_end, **opts))
            n = len(plain.t)
            err_plain = np.abs(np.array([model.contact_points(q) for q in plain.q]) - expected[:n]).max()
            err_charts = np.abs(np.array([model.contact_points(q) for q in charts.q]) - expected).max()
            lines.append(f"| {method} | {rtol:g} | one chart | {plain.t_final:.6f} | {plain.n_steps} | "
                         f"{plain.energy_drift:.1e} | {err_plain:.1e} | {t_plain * 1e3:.0f} |")
            lines.append(f"| | | charts ({charts.n_chart_switches} switch) | {charts.t_final:g} | {charts.n_steps} | "
                         f"{charts.energy_drift:.1e} | {err_charts:.1e} | {t_charts * 1e3:.1f} |")
            print(lines[-2] + "\n" + lines[-1], file=sys.stderr, flush=True)
    return "\n".join(lines)


def long_table() -> str:
    lines = ["| scene | t_end (s) | run | status | impacts | switches | min chi_A on samples | energy drift | "
             "steps | ms |", "|---|---|---|---|---|---|---|---|---|---|"]
    opts = {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}
    for name, t_end in (("gimbal-lock", 10.0), ("paper-case2", 20.0)):
        scene = load_scene(name)
        model = load_model(scene)
        A = Chart.of(scene.base_twists)
        plain, t_plain = _timed(lambda: simulate(model, t_end, max_steps=200000, charts=False, **opts))
        charts, t_charts = _timed(lambda: simulate(model, t_end, **opts))
        for label, r, seconds in (("one chart", plain, t_plain), ("charts", charts, t_charts)):
            switches = r.n_chart_switches if label == "charts" else "-"
            mu = A.measure(r.q[:, 1]).min()
            lines.append(f"| {name} | {t_end:g} | {label} | {r.status} (t = {r.t_final:.4g} s) | {len(r.impacts)} | "
                         f"{switches} | {mu:.1e} | {r.energy_drift:.1e} | {r.n_steps} | {seconds * 1e3:.0f} |")
        print("\n".join(lines[-2:]), file=sys.stderr, flush=True)
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(prog="python -m studies charts", description=__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)


def main(argv=None) -> int:
    build_parser().parse_args(argv)
    print(f"Machine: {describe()}")
    print(lock_table())
    print()
    print(long_table())
    return 0


if __name__ == "__main__":
    sys.exit(main())
