"""Stress cases for impact accumulation (Zeno behaviour) and resting contact (``CASES``, taken into
studies.stress_cases.CASES; see studies/stress.py).  A chain dropped onto the floor with e = 0 and e = 0.5
must finish within a bounded number of impacts, with T + V never rising over the samples, and end flat on
the floor at rest: every point in resting contact, gaps 0, speeds 0, energy 0 (V = 0 on the floor)."""
from __future__ import annotations

import numpy as np

from .stress import Case, CaseRun, Check

ACCURATE = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}
MAX_IMPACTS = 200         # the cascade must end well before the max_impacts backstop


def energy_monotone(tol: float = 1e-8):
    """T + V on every sample never exceeds the previous sample by more than tol x the energy scale."""
    def check(run: CaseRun):
        rise = float(np.max(np.diff(run.energy), initial=0.0)) / run.energy_scale
        return Check(rise <= tol, f"T + V non-increasing sample to sample (largest rise {rise:.1e}, tol {tol:g})")
    check.__name__ = "energy_monotone"
    return check


def ends_at_rest(speed_tol: float = 1e-6, gap_tol: float = 1e-9):
    def check(run: CaseRun):
        r, model = run.result, run.model
        everyone = sorted((p, "x2_min") for p in range(1, run.scene.n + 2))
        gaps = model.contact_gaps(model.layout.reduce(r.q_final), run.p)
        speed = float(np.abs(r.qd_final).max())
        events = len(r.contact_events)
        return [Check(sorted(r.resting_final) == everyone,
                      f"resting at the end: {sorted(r.resting_final)} ({events} contact events)"),
                Check(speed <= speed_tol and np.abs(gaps).max() <= gap_tol,
                      f"final speeds {speed:.1e} (tol {speed_tol:g}), gaps {np.abs(gaps).max():.1e} m "
                      f"(tol {gap_tol:g})"),
                Check(len(r.impacts) < MAX_IMPACTS, f"{len(r.impacts)} impacts (bound {MAX_IMPACTS})")]
    check.__name__ = "ends_at_rest"
    return check


CASES = tuple(
    Case(name=name, scene="stress-zeno", params={"e_x2_min": e},
         description=f"3-link chain dropped onto the floor, e = {e:g}: impacts accumulate, resting contact",
         simulate={"t_end": 4.0, "max_impacts": MAX_IMPACTS, **ACCURATE},
         checks=(energy_monotone(), ends_at_rest()))
    for name, e in (("zeno-e0", 0.0), ("zeno-e05", 0.5)))
