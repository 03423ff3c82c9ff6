"""Stress case "gimbal-lock" (``CASES``, taken into studies.stress_cases.CASES; see studies/stress.py).

The gimbal-lock scene drives theta_0 through pi/2 at t = 0.25 s.  The suite's run is a single-chart
``simulate`` (charts=False): it must stop before the lock with a clear message (status -1, never a silent
loss of accuracy), and the case's check runs ``simulate_with_charts`` (runtime/charts.py) on the same scene,
which must finish with the four requirements evaluated on the integrated coordinates, energy conserved
(e = 1) and every chart switch reported.
"""
from __future__ import annotations

import numpy as np

from runtime.charts import ChartModels, simulate_with_charts

from .stress import Case, CaseRun, Check, Expect

GIMBAL_T_END = 3.0
GIMBAL_RUN = {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}


def charts_complete(energy_tol: float = 1e-9):
    """The chart-switching run of the case's scene: status 0 to t_end, at least one switch each way, no
    NaN, no penetration and energy conserved on every sample (from the coordinates actually integrated)
    and at every impact."""
    def check(run: CaseRun):
        case = run.case
        t_end = case.simulate.get("t_end", 1.0)
        result = simulate_with_charts(run.scene, t_end, p=run.p, models=ChartModels(run.scene), **GIMBAL_RUN)
        checks = [Check(result.status == 0, f"with charts: status {result.status}: {result.message}")]
        kinds = [(s.source, s.target) for s in result.switches]
        checks.append(Check(("A", "B") in kinds and ("B", "A") in kinds,
                            f"{len(result.switches)} chart switches reported (first at t = "
                            f"{result.switches[0].t:.4g} s); integrated chart's mu >= {result.min_measure:.3f}, "
                            f"chart A's mu down to {result.measure_a.min():.1e}" if result.switches else
                            "no chart switch reported"))
        arrays = [result.q_native, result.qd_native, result.q_final, result.qd_final]
        checks.append(Check(all(np.isfinite(a).all() for a in arrays), "with charts: no NaN"))
        if len(result.t):
            penetration = max(-float(result.contact_gaps(run.p).min()), 0.0)
            checks.append(Check(penetration <= case.pen_tol, f"with charts: penetration {penetration:.1e} m"))
            E0 = result.energy_initial
            values = list(result.energies(run.p)) + [i.energy_after for i in result.impacts] + [result.energy_final]
            worst = max(abs(E - E0) for E in values) / abs(E0)
            checks.append(Check(worst <= energy_tol, f"with charts: energy conserved to {worst:.1e} over "
                                                     f"{len(result.impacts)} impacts (tol {energy_tol:g})"))
        return checks
    check.__name__ = "charts_complete"
    return check


CASES = (
    Case(
        name="gimbal-lock",
        description="theta_0 reaches pi/2 at t = 0.25 s: one chart stops before it with a clear message; "
                    "switching to a second base chart and back completes 3 s (runtime/charts.py)",
        scene="gimbal-lock",
        simulate={"t_end": GIMBAL_T_END, **GIMBAL_RUN, "max_steps": 20000, "charts": False},
        expect=Expect.status(r"at t = 0\.24\d* s: gimbal lock"),
        checks=(charts_complete(1e-9),),
    ),
)
