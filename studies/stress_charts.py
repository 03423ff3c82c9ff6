"""Stress case "gimbal-lock" (``CASES``, taken into studies.stress_cases.CASES; see studies/stress.py).

The gimbal-lock scene drives theta_0 through pi/2 at t = 0.25 s.  The suite's run is a single-chart
``simulate`` (charts=False): it must stop before the lock with a clear message (status -1, never a silent
loss of accuracy), and the case's check runs ``simulate`` with its default chart switching (the C loop
integrates on the model's second base chart near the lock) on the same scene, which must finish with no NaN,
no penetration, energy conserved (e = 1) and chart switches counted.
"""
from __future__ import annotations

import numpy as np

from codegen.charts import Chart
from runtime.model import load_model
from runtime.simulate import simulate

from .stress import Case, CaseRun, Check, Expect

GIMBAL_T_END = 3.0
GIMBAL_RUN = {"method": "dop853", "rtol": 1e-10, "atol": 1e-12}


def charts_complete(energy_tol: float = 1e-9):
    """The chart-switching run of the case's scene: status 0 to t_end, at least one switch each way, no
    NaN, no penetration, and energy conserved at every impact, at the end and on every sample where chart A is
    well conditioned (chi_A >= 0.1: the samples are in chart A's coordinates, whose rates grow like 1/chi_A)."""
    def check(run: CaseRun):
        case = run.case
        t_end = case.simulate.get("t_end", 1.0)
        model = load_model(run.scene)
        result = simulate(model, t_end, p=run.p, **GIMBAL_RUN)
        checks = [Check(result.status == 0, f"with charts: status {result.status}: {result.message}")]
        checks.append(Check(result.n_chart_switches >= 2, f"{result.n_chart_switches} chart switches"))
        arrays = [result.q, result.qd, result.q_final, result.qd_final]
        checks.append(Check(all(np.isfinite(a).all() for a in arrays), "with charts: no NaN"))
        if len(result.t):
            reduce = model.layout.reduce
            gaps = np.array([model.contact_gaps(reduce(q), run.p) for q in result.q])
            penetration = max(-float(gaps.min()), 0.0)
            checks.append(Check(penetration <= case.pen_tol, f"with charts: penetration {penetration:.1e} m"))
            E0 = result.energy_initial
            good = Chart.of(run.scene.base_twists).measure(result.q[:, 1]) >= 0.1
            samples = [sum(model.energy(reduce(q), reduce(qd), run.p))
                       for q, qd in zip(result.q[good], result.qd[good])]
            values = samples + [i.energy_after for i in result.impacts] + [result.energy_final]
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
                    "switching to a second base chart and back (in the C loop) completes 3 s",
        scene="gimbal-lock",
        simulate={"t_end": GIMBAL_T_END, **GIMBAL_RUN, "max_steps": 20000, "charts": False},
        expect=Expect.status(r"at t = 0\.24\d* s: gimbal lock"),
        checks=(charts_complete(1e-9),),
    ),
)
