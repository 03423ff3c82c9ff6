"""The stress suite: stiff and extreme scenes, each checked against the four requirements of the
hybrid runtime, plus the physical laws that give each scene an independent answer.

    python -m studies stress [--only NAME ...] [--quick] [--list] [--json [FILE]]     (studies/stress_suite.py)

Every case runs ``simulate`` on one scene and must pass the four requirements:

1. **no NaN**: every sample, impact state and the final state are finite;
2. **no penetration** beyond ``Case.pen_tol`` (default ``PEN_TOL`` = 1e-9 m): the compiled
   ``contact_gaps`` kernel is evaluated on every sample and at every impact;
3. **no energy gain** beyond ``Case.energy_tol`` (default ``ENERGY_TOL`` = 1e-8) times the energy
   scale max(max(T + |V|) over the samples, M g L): E(t) - E(0) on every sample and after every impact;
4. **a clear message**: the outcome is the one the case expects (``Expect``): ``ok`` (status 0),
   ``status`` (status -1 whose message matches a pattern) or ``raises`` (a ValueError, e.g. a
   SceneError, whose message matches a pattern).  Anything else -- an unexpected status -1, a
   traceback, a wrong message -- fails.

The cases are plain data: the tuple ``CASES`` of ``studies/stress_cases.py`` (which takes in the cases of
``studies/stress_charts.py`` and ``studies/stress_zeno.py``).  A case::

    from studies.stress import Case, Expect, energy_conserved, converged

    Case(
        name="my-case",                      # unique; --only my-case
        description="what it stresses",
        scene="stress-my-scene",             # shipped scene name / file, a Scene, or a callable -> Scene
        simulate={"t_end": 1.0, "rtol": 1e-10, "atol": 1e-12},   # keyword arguments of simulate()
        params={"e_x2_min": 0.5},            # optional overrides of the parameter vector, by name
        expect=Expect.ok(),                  # or Expect.status("max_impacts limit"), Expect.raises("O_1")
        checks=(energy_conserved(1e-9), converged()),   # extra checks: fn(run) -> Check or [Check]
        slow=False,                          # True: left out of --quick and of the default test run
        known_issue="",                      # a FAIL the runtime has today (the expectation stays the
    )                                        # correct behaviour; tests mark it xfail, strict)

An extra check receives the ``CaseRun`` (scene, model, result, p, samples and energies already
evaluated) and returns ``Check(ok, note)`` objects; the notes are printed under the table.
"""
from __future__ import annotations

import re
import sys
import time
import traceback
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import LineLink, Scene, frames, load_scene

PEN_TOL = 1e-9        # m: allowed penetration (event location is to 1e-13 s on the interpolant)
ENERGY_TOL = 1e-8     # allowed energy gain, relative to max(T + |V|) over the samples
SAMPLES_DT = 1e-3     # s: default spacing of the samples every requirement is checked on
COND_SAMPLES = 100    # I_f condition numbers are evaluated on at most this many samples


# ---------------------------------------------------------------------------
# the cases
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Expect:
    """The expected outcome of a case: kind 'ok', 'status' (status -1) or 'raises', and a regular
    expression the message must match (searched, case-sensitive)."""

    kind: str = "ok"
    pattern: str = ""

    @staticmethod
    def ok() -> "Expect":
        return Expect("ok")

    @staticmethod
    def status(pattern: str) -> "Expect":
        return Expect("status", pattern)

    @staticmethod
    def raises(pattern: str) -> "Expect":
        return Expect("raises", pattern)

    def describe(self) -> str:
        return "status 0" if self.kind == "ok" else f"{self.kind} /{self.pattern}/"


@dataclass(frozen=True)
class Check:
    ok: bool
    note: str


@dataclass
class Case:
    name: str
    description: str
    scene: object                                  # name/path, Scene, or callable returning a Scene
    simulate: dict = field(default_factory=dict)   # keyword arguments of runtime.simulate (t_end, ...)
    params: dict = field(default_factory=dict)     # parameter overrides by name (scene.parameter_names())
    expect: Expect = field(default_factory=Expect.ok)
    checks: tuple = ()                             # fn(CaseRun) -> Check | list[Check]
    slow: bool = False
    specialise: bool = True
    samples_dt: float = SAMPLES_DT
    pen_tol: float = PEN_TOL
    energy_tol: float = ENERGY_TOL
    known_issue: str = ""                          # a FAIL expected today and why; tests mark it xfail(strict)


def check_cases(cases) -> tuple:
    """The cases as a tuple, after checking that every name is unique and every expectation is known."""
    seen = set()
    for case in cases:
        if case.name in seen:
            raise ValueError(f"stress case {case.name!r} appears twice")
        if case.expect.kind not in ("ok", "status", "raises"):
            raise ValueError(f"{case.name}: expect.kind must be 'ok', 'status' or 'raises', got {case.expect.kind!r}")
        seen.add(case.name)
    return tuple(cases)


# ---------------------------------------------------------------------------
# running one case
# ---------------------------------------------------------------------------
@dataclass
class CaseRun:
    """Everything a check needs: the case, its scene and model, the result (None if the run raised)."""

    case: Case
    scene: Scene | None = None
    model: object = None
    p: np.ndarray | None = None
    result: object = None
    error: BaseException | None = None
    seconds_model: float = 0.0
    seconds_run: float = 0.0
    # filled by evaluate(): samples in the model's coordinates and their energies
    q: np.ndarray | None = None
    qd: np.ndarray | None = None
    energy: np.ndarray | None = None
    energy_scale: float = 1.0

    def simulate_again(self, **overrides):
        """The same run with other simulate() options (for convergence checks)."""
        from runtime.simulate import simulate
        kwargs = {**self.case.simulate, "p": self.p, **overrides}
        return simulate(self.model, **kwargs)


@dataclass
class CaseOutcome:
    case: Case
    passed: bool
    reasons: list[str]
    notes: list[str]
    row: dict


def build_scene(case: Case) -> Scene:
    if isinstance(case.scene, Scene):
        return case.scene
    if callable(case.scene):
        return case.scene()
    return load_scene(case.scene)


def parameter_vector(scene: Scene, model, overrides: dict) -> np.ndarray:
    p = np.array(model.p, dtype=float)
    names = scene.parameter_names()
    for name, value in overrides.items():
        if name not in names:
            raise ValueError(f"params.{name}: no such parameter; the scene has {', '.join(names)}")
        p[names.index(name)] = value
    return p


def run_case(case: Case, progress=None) -> CaseOutcome:
    """Build the scene and model, simulate, check the four requirements and the case's own checks."""
    from runtime.model import load_model
    from runtime.simulate import simulate

    run = CaseRun(case)
    started = start = time.perf_counter()
    try:
        run.scene = build_scene(case)
        run.model = load_model(run.scene, specialise=case.specialise, progress=progress)
        run.p = parameter_vector(run.scene, run.model, case.params)
        run.seconds_model = time.perf_counter() - start
        kwargs = dict(case.simulate)
        t_end = kwargs.pop("t_end", 1.0)
        if "t_eval" not in kwargs:
            kwargs["t_eval"] = np.unique(np.r_[np.arange(0.0, t_end, case.samples_dt), t_end])
        start = time.perf_counter()
        run.result = simulate(run.model, t_end, p=run.p, **kwargs)
        run.seconds_run = time.perf_counter() - start
    except ValueError as exc:               # bad input (SceneError is a ValueError): a clear error
        run.error = exc
    except Exception as exc:                # anything else is a failure of requirement 4
        run.error = exc
        traceback.print_exc(file=sys.stderr)
    outcome = evaluate(run)
    outcome.row["seconds"] = round(time.perf_counter() - started, 3)      # model, run and checks
    return outcome


def evaluate(run: CaseRun) -> CaseOutcome:
    case, reasons, notes = run.case, [], []
    row = {"case": case.name, "n": run.scene.n if run.scene else None,
           "method": case.simulate.get("method", "dopri5"), "impacts": None, "t_final": None,
           "t_end": case.simulate.get("t_end", 1.0), "energy_drift": None, "max_gain": None,
           "max_penetration": None, "max_cond_If": None, "status": None, "message": "",
           "seconds_model": round(run.seconds_model, 3), "seconds_run": round(run.seconds_run, 3)}
    # requirement 4: the outcome is the expected one, with a clear message
    expect = case.expect
    if run.error is not None:
        message = f"{type(run.error).__name__}: {run.error}"
        row["status"], row["message"] = "raised", message
        if expect.kind != "raises":
            reasons.append(f"raised {message}")
        elif not isinstance(run.error, ValueError):
            reasons.append(f"expected a ValueError with a clear message, got {message}")
        elif not re.search(expect.pattern, str(run.error)):
            reasons.append(f"message does not match /{expect.pattern}/: {run.error}")
        return _outcome(case, reasons, notes, row)
    result = run.result
    row.update(impacts=len(result.impacts), t_final=result.t_final, status=result.status, message=result.message)
    if expect.kind == "raises":
        reasons.append(f"expected an error /{expect.pattern}/, got status {result.status}: {result.message}")
    elif expect.kind == "ok" and result.status != 0:
        reasons.append(f"status {result.status}: {result.message}")
    elif expect.kind == "status":
        if result.status != -1:
            reasons.append(f"expected status -1 /{expect.pattern}/, got status {result.status}: {result.message}")
        elif not re.search(expect.pattern, result.message):
            reasons.append(f"message does not match /{expect.pattern}/: {result.message}")
    if not isinstance(result.message, str) or not result.message:
        reasons.append("the result has no message")
    # requirements 1-3 on every sample and impact
    _sample_requirements(run, row, reasons)
    for check in case.checks:
        try:
            found = check(run)
        except Exception as exc:                           # a check that cannot run is a failure
            found = Check(False, f"{getattr(check, '__name__', 'check')} raised {type(exc).__name__}: {exc}")
        for item in ([found] if isinstance(found, Check) else found):
            notes.append(("" if item.ok else "FAILED: ") + item.note)
            if not item.ok:
                reasons.append(item.note)
    return _outcome(case, reasons, notes, row)


def _outcome(case, reasons, notes, row) -> CaseOutcome:
    row["result"] = "PASS" if not reasons else "FAIL"
    row["reasons"] = reasons
    row["notes"] = notes
    return CaseOutcome(case, not reasons, reasons, notes, row)


def _sample_requirements(run: CaseRun, row: dict, reasons: list[str]) -> None:
    model, result, p, case = run.model, run.result, run.p, run.case
    layout = model.layout
    arrays = [result.q, result.qd, result.q_final, result.qd_final]
    arrays += [a for i in result.impacts for a in (i.q, i.qd_before, i.qd_after)]
    finite = all(np.all(np.isfinite(a)) for a in arrays) and all(
        np.isfinite([i.t, i.energy_before, i.energy_after]).all() for i in result.impacts)
    if not finite:
        reasons.append("NaN or infinity in the samples, impacts or final state")
        return
    free = list(layout.free)                      # full layout (Eq. 13) -> the model's coordinates
    q, qd = np.asarray(result.q)[:, free], np.asarray(result.qd)[:, free]
    run.q, run.qd = q, qd
    # requirement 2: gaps on every sample and at every impact
    states = list(q) + [layout.reduce(i.q) for i in result.impacts] + [layout.reduce(result.q_final)]
    if len(model.contacts):
        worst = max(-float(model.contact_gaps(s, p).min()) for s in states)
        row["max_penetration"] = max(worst, 0.0) + 0.0
        if worst > case.pen_tol:
            reasons.append(f"penetration {worst:.3g} m > {case.pen_tol:g} m")
    # requirement 3: energy on every sample, and after every impact
    energies = np.array([model.energy(a, b, p) for a, b in zip(q, qd)]) if len(q) else np.zeros((0, 2))
    total = energies.sum(axis=1) if len(q) else np.zeros(0)
    run.energy = total
    E0 = result.energy_initial
    from runtime.simulate import weight_scale
    scale = max([abs(E0), weight_scale(run.scene, p)] + list(np.abs(energies).sum(axis=1)) + [1e-300])
    run.energy_scale = scale
    after = [i.energy_after for i in result.impacts] + [result.energy_final]
    gain = max(list(total - E0) + [E - E0 for E in after] + [0.0])
    row["max_gain"] = gain / scale
    row["energy_drift"] = (result.energy_final - E0) / scale
    if gain > case.energy_tol * scale:
        reasons.append(f"energy gain {gain / scale:.3g} (relative) > {case.energy_tol:g}")
    # conditioning of I_f along the run (a note, not a requirement)
    if len(q):
        picks = q[np.unique(np.linspace(0, len(q) - 1, min(len(q), COND_SAMPLES)).astype(int))]
        row["max_cond_If"] = max(float(np.linalg.cond(model.mass_matrix(s, p))) for s in picks)


# ---------------------------------------------------------------------------
# independent mechanics (numpy, from the scene's own frames: not the generated C)
# ---------------------------------------------------------------------------
@dataclass
class LinkMotion:
    mass: float
    com: np.ndarray           # centre of mass, world frame
    v_com: np.ndarray
    R: np.ndarray             # link frame -> world
    omega: np.ndarray         # angular velocity, world frame
    inertia: np.ndarray       # about the centre of mass, world frame


def link_motion(scene: Scene, q, qd) -> list[LinkMotion]:
    """World-frame motion of every real link from the full-layout state (Eq. 13): omega_i is the sum
    of theta_dot_k z_k for k <= i, and O_{i+1} = O_i + l_i x_i."""
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    n = scene.n
    Rs = frames(scene, q)                       # ^{ref}R_k, k = -1..n at index k + 1
    omega = qd[0] * Rs[0][:, 2] + qd[1] * Rs[1][:, 2]
    O, Od = q[n + 2:n + 5].copy(), qd[n + 2:n + 5].copy()
    out = []
    for i, link in enumerate(scene.links, start=1):
        R = Rs[i + 1]
        omega = omega + qd[i + 1] * R[:, 2]
        if isinstance(link, LineLink):
            m, c = link.mu * link.length, np.array([link.length / 2, 0.0, 0.0])
            t = link.mu * link.length ** 3 / 12
            Ic = np.diag([link.length * link.J[0], t + link.length * link.J[1], t + link.length * link.J[2]])
        else:
            m, c, Ic = link.mass, np.array(link.com), np.array(link.inertia)
        r = R @ c
        out.append(LinkMotion(m, O + r, Od + np.cross(omega, r), R, omega.copy(), R @ Ic @ R.T))
        axis = link.length * R[:, 0]
        O, Od = O + axis, Od + np.cross(omega, axis)
    return out


def momenta(scene: Scene, q, qd) -> tuple[np.ndarray, np.ndarray]:
    """Linear momentum and angular momentum about the origin of the whole chain."""
    P, L = np.zeros(3), np.zeros(3)
    for link in link_motion(scene, q, qd):
        P += link.mass * link.v_com
        L += link.mass * np.cross(link.com, link.v_com) + link.inertia @ link.omega
    return P, L


# ---------------------------------------------------------------------------
# reusable extra checks
# ---------------------------------------------------------------------------
def energy_conserved(tol: float = 1e-8):
    """e = 1 everywhere (or no walls): |E(t) - E(0)| <= tol * scale on every sample and impact."""
    def check(run: CaseRun):
        r = run.result
        values = list(run.energy) + [i.energy_after for i in r.impacts] + [r.energy_final]
        worst = max(abs(E - r.energy_initial) for E in values) / run.energy_scale
        return Check(worst <= tol, f"energy conserved to {worst:.1e} (tol {tol:g})")
    check.__name__ = "energy_conserved"
    return check


def energy_never_rises(tol: float = 1e-9):
    """With e < 1: the energy after an impact never exceeds the energy after the previous one
    (flight conserves it, impacts can only dissipate)."""
    def check(run: CaseRun):
        r = run.result
        levels = [r.energy_initial] + [i.energy_after for i in r.impacts]
        rise = max([b - a for a, b in zip(levels, levels[1:])] + [0.0]) / run.energy_scale
        return Check(rise <= tol, f"energy non-increasing impact to impact (largest rise {rise:.1e})")
    check.__name__ = "energy_never_rises"
    return check


def converged(method: str = "dop853", rtol: float = 1e-12, atol: float = 1e-14, time_tol: float = 1e-7,
              until: float | None = None):
    """Run again with a tighter tolerance (another method by default): the same impacts (points and
    walls) at the same times within time_tol.  ``until`` limits the comparison to the impacts up to that
    time (chaotic scenes amplify any integration error; beyond their horizon sequences part)."""
    def check(run: CaseRun):
        other = run.simulate_again(method=method, rtol=rtol, atol=atol, dt=None)
        return same_impacts(run.result, other, f"{method} rtol {rtol:g}", time_tol, until)
    check.__name__ = "converged"
    return check


def same_motion_with(params: dict, label: str, time_tol: float = 1e-7, until: float | None = None):
    """Run again with other parameters that cannot change the motion of the contact points (e.g. the
    axial inertia of a link that is not spinning about its axis): the same impacts at the same times."""
    def check(run: CaseRun):
        p = run.p.copy()
        names = run.scene.parameter_names()
        for name, value in params.items():
            p[names.index(name)] = value
        other = run.simulate_again(p=p)
        return same_impacts(run.result, other, label, time_tol, until)
    check.__name__ = "same_motion_with"
    return check


def same_impacts(mine, other, label: str, time_tol: float, until: float | None = None) -> Check:
    """Compare two results' impact sequences (contact sets exactly, times within time_tol)."""
    if other.status != mine.status:
        return Check(False, f"{label} ends with status {other.status} ({other.message})")
    horizon = float("inf") if until is None else until
    a_list = [i for i in mine.impacts if i.t <= horizon]
    b_list = [i for i in other.impacts if i.t <= horizon]
    within = "" if until is None else f" up to t = {until:g} s"
    if len(a_list) != len(b_list):
        return Check(False, f"{len(a_list)} impacts{within}, {label} finds {len(b_list)}")
    for k, (a, b) in enumerate(zip(a_list, b_list), start=1):
        if {(c.point, c.wall) for c in a.contacts} != {(c.point, c.wall) for c in b.contacts}:
            return Check(False, f"impact {k} at {a.t:.9g} s: contacts differ from {label}")
    dt = max([abs(a.t - b.t) for a, b in zip(a_list, b_list)] + [0.0])
    return Check(dt <= time_tol, f"{len(a_list)} impacts{within} agree with {label} in contacts and to "
                                 f"{dt:.1e} s in time (tol {time_tol:g})")


# ---------------------------------------------------------------------------
# the table
# ---------------------------------------------------------------------------
COLUMNS = ("case", "n", "method", "impacts", "t_final/t_end", "energy drift", "max gain", "max penetration",
           "max cond(I_f)", "status", "result")


def _fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def table_rows(outcomes: list[CaseOutcome]) -> list[list[str]]:
    rows = []
    for o in outcomes:
        r = o.row
        t = "-" if r["t_final"] is None else f"{r['t_final']:.4g}/{r['t_end']:g}"
        status = "raised" if r["status"] == "raised" else _fmt(r["status"], "d")
        verdict = r["result"] + (" (known issue)" if o.case.known_issue and not o.passed else "")
        verdict += " (known issue no longer seen)" if o.case.known_issue and o.passed else ""
        verdict += "" if o.passed else ": " + "; ".join(o.reasons)
        rows.append([r["case"], _fmt(r["n"], "d"), r["method"], _fmt(r["impacts"], "d"), t,
                     _fmt(r["energy_drift"], ".1e"), _fmt(r["max_gain"], ".1e"), _fmt(r["max_penetration"], ".1e"),
                     _fmt(r["max_cond_If"], ".1e"), status, verdict])
    return rows


def format_table(outcomes: list[CaseOutcome]) -> str:
    """A Markdown table, then the notes and messages of every case."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(cells) + " |" for cells in table_rows(outcomes)]
    lines.append("")
    for o in outcomes:
        lines.append(f"{o.case.name}: {o.case.description}")
        lines.append(f"    expected {o.case.expect.describe()}; got: {o.row['message']}")
        if o.case.known_issue:
            lines.append(f"    known issue: {o.case.known_issue}")
        lines += [f"    - {note}" for note in o.notes]
    return "\n".join(lines)


def tolerances_line() -> str:
    return (f"requirements: no NaN; penetration <= {PEN_TOL:g} m (contact_gaps on every sample and impact); "
            f"energy gain <= {ENERGY_TOL:g} x max(T + |V|, M g L) (every sample and impact); the expected "
            "status/message (cases may set their own tolerances)")
