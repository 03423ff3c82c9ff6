"""Work-precision study: error against CPU time for every integrator, on one scene with all its impacts.

    python -m studies precision --scene paper-case1 [--t-end T] [--out DIR] [--quick]

Reference: DOP853 (the highest order we have) at rtol = 1e-13, atol = 1e-15.  It is confirmed by two
other methods, DOPRI5 at rtol = 1e-13 and RK4 at the paper's dt = 1e-5 s: both must give the same impact
sequence (contact sets in order), impact times within ``time_tol`` and the same final state within
``state_tol``, or the study stops with an error.  Their largest disagreement is the reference's own
uncertainty; errors below it are not resolved.

Runs: our RK4 over dt, our DOPRI5 and DOP853 over rtol (atol = rtol/100), and scipy's solve_ivp RK45,
DOP853 and Radau (scipy's finite-difference Jacobian) on the same compiled right-hand side
(studies.baseline).  For each run:

* CPU time: ``time.process_time`` of the whole run (integration, events, impacts, Python glue), median
  of repeated runs (as many as fit in ``budget`` seconds, 3 to 21; a run longer than that is timed once);
* impacts: matched with the reference in order and by contact set; the first mismatch ends the match and
  everything after it counts as missed (reference impacts not reproduced) and extra (the run's impacts
  after the mismatch): a diverged sequence is reported, never matched loosely;
* impact-time error: the largest |t - t_ref| over the matched impacts;
* final-state error: max |x - x_ref| over q and qd at t_end (full layout of Eq. 13); after a diverged
  impact sequence it is O(1) (a different trajectory);
* energy drift: the largest |E - E0 - (energy removed by the impacts so far)| / |E0| over the impact
  instants and t_end, i.e. what the flight integration gained or lost;
* rhs evaluations: every call of the compiled right-hand side (scipy's Jacobian differences included).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from codegen.scene import shipped_scene_names
from runtime.model import CompiledModel
from runtime.simulate import simulate

from .baseline import scipy_hybrid
from .machine import describe
from .timing import time_call

REFERENCE = {"method": "dop853", "rtol": 1e-13, "atol": 1e-15}
CONFIRM = (("DOPRI5 rtol = 1e-13", {"method": "dopri5", "rtol": 1e-13, "atol": 1e-15}),
           ("RK4 dt = 1e-5 s", {"method": "rk4", "dt": 1e-5}))
TIME_TOL = 1e-10          # s: confirming runs' impact times must agree to this
STATE_TOL = 1e-7          # max |x - x_ref| at t_end the confirming runs must agree to
PAPER_DT = 1e-5

FULL = {"RK4": (2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 3e-5, 1e-5, 3e-6),
        "DOPRI5": tuple(10.0 ** -k for k in range(4, 13)),
        "DOP853": tuple(10.0 ** -k for k in range(4, 13)),
        "scipy RK45": tuple(10.0 ** -k for k in range(4, 13)),
        "scipy DOP853": tuple(10.0 ** -k for k in range(4, 13)),
        "scipy Radau": tuple(10.0 ** -k for k in range(4, 11))}
QUICK = {"RK4": (1e-3, 5e-4, 1e-5),
         "DOPRI5": (1e-4, 1e-6, 1e-8, 1e-10, 1e-12),
         "DOP853": (1e-4, 1e-6, 1e-8, 1e-10, 1e-12),
         "scipy RK45": (1e-6, 1e-10),
         "scipy DOP853": (1e-6, 1e-10),
         "scipy Radau": (1e-6,)}
FAMILIES = tuple(FULL)
OURS = {"RK4": "rk4", "DOPRI5": "dopri5", "DOP853": "dop853"}


class ReferenceDisagreement(RuntimeError):
    """The confirming runs do not agree with the reference: no error below that level can be measured."""


@dataclass
class Outcome:
    """One run, whatever produced it; states in the full layout of Eq. 13."""

    impacts: list                 # [(t, frozenset{(point, wall)}, E_before, E_after)]
    t_final: float
    x_final: np.ndarray           # [q, qd]
    energy_initial: float
    energy_final: float
    n_rhs: int
    status: int
    message: str


def outcome_of(result) -> Outcome:
    """A runtime.simulate result or a studies.baseline run -> Outcome."""
    impacts = []
    for impact in result.impacts:
        contacts = impact.contacts if isinstance(impact.contacts, frozenset) else \
            frozenset((c.point, c.wall) for c in impact.contacts)
        impacts.append((impact.t, contacts, impact.energy_before, impact.energy_after))
    return Outcome(impacts, result.t_final, np.r_[result.q_final, result.qd_final], result.energy_initial,
                   result.energy_final, result.n_rhs, result.status, result.message)


def energy_drift(outcome: Outcome) -> float:
    """Largest |E - E0 - impact losses so far| / |E0| over the impact instants and the end."""
    E0, lost, worst = outcome.energy_initial, 0.0, 0.0
    for _, _, before, after in outcome.impacts:
        worst = max(worst, abs(before - E0 - lost))
        lost += after - before
    worst = max(worst, abs(outcome.energy_final - E0 - lost))
    return worst / abs(E0) if E0 != 0 else worst


def contact_label(contacts: frozenset) -> str:
    return "+".join(f"O{point}/{wall}" for point, wall in sorted(contacts))


@dataclass
class Errors:
    matched: int                  # impacts matched in order and by contact set
    n_reference: int
    missed: int                   # reference impacts after the first mismatch
    extra: int                    # the run's impacts after the first mismatch
    impact_time_error: float      # s, over the matched impacts (nan if none)
    state_error: float            # max |x - x_ref| at t_end (inf if the run stopped early)
    energy_drift: float
    note: str = ""

    @property
    def diverged(self) -> bool:
        return self.missed > 0 or self.extra > 0


def compare(run: Outcome, reference: Outcome) -> Errors:
    ref, got = reference.impacts, run.impacts
    k = 0
    while k < min(len(ref), len(got)) and ref[k][1] == got[k][1]:
        k += 1
    time_error = max((abs(got[i][0] - ref[i][0]) for i in range(k)), default=float("nan"))
    note = ""
    if k < len(ref) or k < len(got):
        theirs = f"{contact_label(got[k][1])} at {got[k][0]:.6f} s" if k < len(got) else "no impact"
        ours = f"{contact_label(ref[k][1])} at {ref[k][0]:.6f} s" if k < len(ref) else "no impact"
        note = f"diverges at impact {k + 1}: {theirs}, reference {ours}"
    if run.status != 0:
        note = (note + "; " if note else "") + f"stopped: {run.message}"
        state_error = float("inf")
    else:
        state_error = float(np.abs(run.x_final - reference.x_final).max())
    return Errors(k, len(ref), len(ref) - k, len(got) - k, float(time_error), state_error, energy_drift(run), note)


@dataclass
class Row:
    family: str
    setting: str                  # "dt = 1e-05 s" or "rtol = 1e-08"
    value: float                  # dt or rtol
    cpu_s: float
    repeats: int
    n_rhs: int
    errors: Errors


@dataclass
class Reference:
    label: str
    outcome: Outcome
    cpu_s: float
    confirmations: list = field(default_factory=list)     # [(label, Errors, cpu_s)]

    @property
    def time_floor(self) -> float:
        return max((e.impact_time_error for _, e, _ in self.confirmations), default=0.0)

    @property
    def state_floor(self) -> float:
        return max((e.state_error for _, e, _ in self.confirmations), default=0.0)


def cpu_time(run: Callable[[], object], budget: float) -> tuple[object, float, int]:
    """(result of a first run, median CPU seconds, number of timed runs): studies.timing.time_call on
    ``time.process_time``, as many runs as fit in ``budget`` (3 to 21; one when the first run takes it)."""
    timing = time_call(run, budget=budget, clock=time.process_time)
    return timing.result, timing.median, timing.runs


def runner(model: CompiledModel, t_end: float, family: str, value: float) -> Callable[[], Outcome]:
    """A callable doing one run of the study (no samples kept: t_eval = [])."""
    if family == "RK4":
        return lambda: outcome_of(simulate(model, t_end, method="rk4", dt=value, t_eval=[]))
    if family in OURS:
        return lambda: outcome_of(simulate(model, t_end, method=OURS[family], rtol=value, atol=value / 100,
                                           t_eval=[]))
    method = family.split()[1]
    return lambda: outcome_of(scipy_hybrid(model, t_end, value, value / 100, method=method))


def setting(family: str, value: float) -> str:
    return f"dt = {value:.0e} s" if family == "RK4" else f"rtol = {value:.0e}"


def make_reference(model: CompiledModel, t_end: float, time_tol: float = TIME_TOL, state_tol: float = STATE_TOL,
                   progress=lambda message: None) -> Reference:
    """The reference run and its confirmations; raises ReferenceDisagreement beyond the tolerances."""
    outcome, cpu, _ = cpu_time(lambda: outcome_of(simulate(model, t_end, t_eval=[], **REFERENCE)), 0.0)
    if outcome.status != 0:
        raise ReferenceDisagreement(f"the reference run failed: {outcome.message}")
    reference = Reference(f"DOP853 rtol = {REFERENCE['rtol']:.0e}, atol = {REFERENCE['atol']:.0e}", outcome, cpu)
    progress(f"reference {reference.label}: {len(outcome.impacts)} impacts, {cpu * 1e3:.1f} ms")
    problems = []
    for label, options in CONFIRM:
        other, cpu, _ = cpu_time(lambda: outcome_of(simulate(model, t_end, t_eval=[], **options)), 0.0)
        errors = compare(other, outcome)
        reference.confirmations.append((label, errors, cpu))
        progress(f"  confirmed by {label}: impact times within {errors.impact_time_error:.1e} s, "
                 f"final state within {errors.state_error:.1e}")
        if errors.diverged or other.status != 0:
            problems.append(f"{label}: {errors.note}")
        elif not (errors.impact_time_error <= time_tol and errors.state_error <= state_tol):
            problems.append(f"{label}: impact times differ by {errors.impact_time_error:.2e} s (allowed "
                            f"{time_tol:.0e} s), final states by {errors.state_error:.2e} (allowed {state_tol:.0e})")
    if problems:
        raise ReferenceDisagreement("the reference is not confirmed: " + "; ".join(problems))
    return reference


def run_study(model: CompiledModel, t_end: float, quick: bool = False, budget: float | None = None,
              time_tol: float = TIME_TOL, state_tol: float = STATE_TOL,
              progress=lambda message: None) -> tuple[Reference, list[Row]]:
    reference = make_reference(model, t_end, time_tol, state_tol, progress)
    scipy_hybrid(model, min(t_end, 1e-3), 1e-6, 1e-8)     # warm-up: scipy's imports are not timed
    plan = [(family, value) for family, values in (QUICK if quick else FULL).items() for value in values]
    budget = budget if budget is not None else (0.05 if quick else 0.5)
    rows = []
    for k, (family, value) in enumerate(plan, start=1):
        outcome, cpu, repeats = cpu_time(runner(model, t_end, family, value), budget)
        errors = compare(outcome, reference.outcome)
        rows.append(Row(family, setting(family, value), value, cpu, repeats, outcome.n_rhs, errors))
        progress(f"[{k}/{len(plan)}] {family} {setting(family, value)}: {cpu * 1e3:.2f} ms, "
                 f"{errors.matched}/{errors.n_reference} impacts matched, impact-time error "
                 f"{errors.impact_time_error:.1e} s, state error {errors.state_error:.1e}")
    return reference, rows


# -- output -------------------------------------------------------------------------------------------

def machine() -> str:
    import scipy
    return describe(f"numpy {np.__version__}", f"scipy {scipy.__version__}")


def _e(x: float) -> str:
    return "—" if x is None or math.isnan(x) else ("∞" if math.isinf(x) else f"{x:.1e}")


def markdown(scene_name: str, t_end: float, reference: Reference, rows: list[Row]) -> str:
    ref = reference.outcome
    lines = [f"## Work-precision study: {scene_name}, t_end = {t_end:g} s, {len(ref.impacts)} impacts", "",
             f"Reference: {reference.label} ({reference.cpu_s * 1e3:.1f} ms, energy drift "
             f"{energy_drift(ref):.1e}). Confirmed by:", ""]
    for label, errors, cpu in reference.confirmations:
        lines.append(f"* {label}: same {errors.matched} impacts (contact sets in order), impact times within "
                     f"{_e(errors.impact_time_error)} s, final state within {_e(errors.state_error)} "
                     f"({cpu * 1e3:.0f} ms)")
    lines += ["", f"Errors below {_e(reference.time_floor)} s (impact times) and {_e(reference.state_floor)} "
              "(final state) are within the reference's own uncertainty.", "",
              "CPU time: `time.process_time`, median of repeated runs (column *runs*). atol = rtol/100. "
              "Energy drift: largest |E − E0 − impact losses| / |E0| at the impacts and t_end. "
              "Impacts are matched in order by contact set; after the first mismatch the rest of the "
              "reference counts as missed and the rest of the run as extra.", "",
              "| method | setting | CPU ms | runs | rhs evals | impacts matched | missed | extra "
              "| max impact-time error s | final-state error | energy drift | note |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        e = row.errors
        lines.append(f"| {row.family} | {row.setting} | {row.cpu_s * 1e3:.3g} | {row.repeats} | {row.n_rhs} | "
                     f"{e.matched}/{e.n_reference} | {e.missed} | {e.extra} | {_e(e.impact_time_error)} | "
                     f"{_e(e.state_error)} | {_e(e.energy_drift)} | {e.note} |")
    return "\n".join(lines) + "\n"


STYLE = {"RK4": ("tab:red", "s"), "DOPRI5": ("tab:blue", "o"), "DOP853": ("tab:green", "^"),
         "scipy RK45": ("tab:cyan", "o"), "scipy DOP853": ("tab:olive", "^"), "scipy Radau": ("tab:purple", "D")}


def plot(scene_name: str, t_end: float, reference: Reference, rows: list[Row], path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), constrained_layout=True)
    panels = ((axes[0], "impact_time_error", "largest impact-time error (s)", reference.time_floor),
              (axes[1], "state_error", "final-state error max |x − x_ref|", reference.state_floor))
    for ax, attr, ylabel, floor in panels:
        ax.set_xscale("log")
        ax.set_yscale("log")
        for family in FAMILIES:
            mine = [r for r in rows if r.family == family]
            if not mine:
                continue
            colour, marker = STYLE[family]
            fill = "none" if family.startswith("scipy") else colour
            good = [r for r in mine if not r.errors.diverged and r.errors.state_error < math.inf]
            ax.plot([r.cpu_s for r in good], [max(getattr(r.errors, attr), 1e-16) for r in good], "-",
                    color=colour, marker=marker, markerfacecolor=fill, label=family)
            bad = [r for r in mine if r not in good]
            if bad:   # diverged impact sequences: state error as is, impact time pinned at the top
                y = [max(r.errors.state_error, 1e-16) if attr == "state_error" and r.errors.state_error < math.inf
                     else 1.0 for r in bad]
                ax.plot([r.cpu_s for r in bad], y, "x", color=colour, markersize=9, markeredgewidth=2)
            paper = [r for r in mine if family == "RK4" and math.isclose(r.value, PAPER_DT)]
            if paper:
                value = getattr(paper[0].errors, attr)
                ax.annotate("RK4 at the paper's\ndt = 1e-5 s", (paper[0].cpu_s, max(value, 1e-16)),
                            textcoords="offset points", xytext=(-30, 45), fontsize=8, ha="center",
                            arrowprops={"arrowstyle": "->", "color": "tab:red"})
        if floor > 0:
            ax.axhline(floor, color="grey", linestyle=":", linewidth=1)
            ax.annotate("reference uncertainty", (0.01, floor), xycoords=("axes fraction", "data"),
                        textcoords="offset points", xytext=(0, 3), fontsize=8, color="grey")
        if attr == "impact_time_error" and any(r.errors.diverged for r in rows):
            ax.set_ylim(top=100.0)
            ax.annotate("× impact sequence diverged", (0.5, 1.0), xycoords=("axes fraction", "data"),
                        textcoords="offset points", xytext=(0, 9), fontsize=8, ha="center")
        ax.set_xlabel("CPU time per run (s)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(fontsize=8, title="filled: ours (compiled), hollow: scipy;\n× = impact sequence diverged",
                   title_fontsize=7)
    fig.suptitle(f"{scene_name}: error against CPU time, t_end = {t_end:g} s, all impacts")
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def to_json(scene_name: str, t_end: float, reference: Reference, rows: list[Row]) -> dict:
    def clean(x):
        return None if isinstance(x, float) and not math.isfinite(x) else x
    return {"scene": scene_name, "t_end": t_end, "machine": machine(),
            "reference": {"label": reference.label, "cpu_s": reference.cpu_s,
                          "impact_times": [i[0] for i in reference.outcome.impacts],
                          "energy_drift": energy_drift(reference.outcome),
                          "time_floor": reference.time_floor, "state_floor": reference.state_floor,
                          "confirmations": [{"label": label, "cpu_s": cpu,
                                             **{k: clean(v) for k, v in asdict(e).items()}}
                                            for label, e, cpu in reference.confirmations]},
            "rows": [{"family": r.family, "setting": r.setting, "value": r.value, "cpu_s": r.cpu_s,
                      "repeats": r.repeats, "n_rhs": r.n_rhs,
                      **{k: clean(v) for k, v in asdict(r.errors).items()}} for r in rows]}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m studies precision",
        description="Error against CPU time for RK4, DOPRI5, DOP853 and scipy's RK45, DOP853, Radau, against a "
                    "confirmed DOP853 reference (studies/precision.py).",
        epilog=f"Shipped scenes: {', '.join(shipped_scene_names())}.")
    parser.add_argument("--scene", default="paper-case1", help="shipped scene name or .toml/.json file")
    parser.add_argument("--t-end", type=float, default=None,
                        help="end time in s (default: 1.5 for paper-case1, 1.75 for paper-case2, else 1.0)")
    parser.add_argument("--out", default="precision", metavar="DIR",
                        help="folder for precision-SCENE.md/.json/.png (default ./precision)")
    parser.add_argument("--quick", action="store_true", help="a few runs only (for tests)")
    parser.add_argument("--time-tol", type=float, default=TIME_TOL,
                        help=f"s; the confirming runs' impact times must agree with the reference to this "
                             f"(default {TIME_TOL:g})")
    parser.add_argument("--state-tol", type=float, default=STATE_TOL,
                        help=f"the confirming runs' final states (max |x - x_ref|) must agree with the reference "
                             f"to this (default {STATE_TOL:g})")
    return parser


def main(argv=None) -> int:
    """The `python -m studies precision` command."""
    from codegen.outputs import output_dir_problem
    from runtime.compile import BuildError, CacheError, CompilerNotFound
    from runtime.horizon import scene_and_horizon
    from runtime.model import load_model

    args = build_parser().parse_args(argv)

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    missing = [m for m in ("scipy", "matplotlib") if importlib.util.find_spec(m) is None]
    if missing:
        print(f"error: python -m studies precision needs {' and '.join(missing)} (its scipy baseline and its plot), "
              "which the 'study' extra installs: pip install -e \".[study]\"", file=sys.stderr)
        return 2
    loaded = scene_and_horizon(args)
    if loaded is None:
        return 2
    scene, t_end = loaded
    for name, value in (("--t-end", t_end), ("--time-tol", args.time_tol), ("--state-tol", args.state_tol)):
        if not (math.isfinite(value) and value > 0):
            print(f"error: {name}: must be a finite number > 0, got {value}", file=sys.stderr)
            return 2
    out = Path(args.out)
    problem = output_dir_problem("--out", args.out)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    try:
        model = load_model(scene, progress=lambda m: progress(f"  {m}"))
    except (CompilerNotFound, BuildError, CacheError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    start = time.perf_counter()
    try:
        reference, rows = run_study(model, t_end, quick=args.quick, time_tol=args.time_tol,
                                    state_tol=args.state_tol, progress=progress)
    except ReferenceDisagreement as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    text = markdown(scene.name, t_end, reference, rows)
    text += f"\nMachine: {machine()}. Study took {time.perf_counter() - start:.1f} s.\n"
    print(text)
    stem = f"precision-{scene.name.replace('_', '-')}"
    (out / f"{stem}.md").write_text(text)
    (out / f"{stem}.json").write_text(json.dumps(to_json(scene.name, t_end, reference, rows), indent=1))
    plot(scene.name, t_end, reference, rows, out / f"{stem}.png")
    print(f"wrote {out / stem}.md, .json, .png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
