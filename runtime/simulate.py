"""The hybrid simulation from Python, in the spirit of scipy.integrate.solve_ivp.

    from runtime import simulate
    result = simulate("paper-case1", t_end=1.5)
    for impact in result.impacts:
        print(impact.t, [(c.point, c.wall) for c in impact.contacts])

Flight segments run in compiled code (``NAME_sim_advance``, the C library in ``runtime/c``) up to the
next impact, which is located, resolved, applied and checked in C (no pulling impulse, no contact still
approaching its wall, no energy gain); the budgets (steps, wall time) and RK4's stability rule are the C loop's
too.  Python validates the arguments, talks to C once per flight segment, and collects and reports the result.
Codes and sizes come from the compiled module (``lib.GAC_...``); GAC_RTOL_MIN, needed before a model is built,
from gac.h's parse (runtime.header).
"""
from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import WALL_NAMES, JointStop, LinkPair, ObstacleContact, Scene, SceneError, parameter_name, \
    split_parameter_name
from codegen.parameters import check_vector, parameter_rules
from codegen.specialise import coordinate_names

from .header import library_constants
from .inputs import Controller, InputSchedule, attach, input_source, pd  # noqa: F401  (Controller, InputSchedule, pd: re-export)
from .model import CHOSEN_LAWS, CompiledModel, load_model
from . import sensitivities as sensitivity

METHODS = ("dopri5", "dop853", "rk4")
RTOL_MIN = float(library_constants()["GAC_RTOL_MIN"])   # the smallest rtol the C loop accepts (gac.h)
DEFAULT_RTOL, DEFAULT_ATOL = 1e-8, 1e-10   # the adaptive methods' tolerances, here, in the CLI and in C
ROUNDOFF_WARN = 1e-6    # an impact whose energy round-off bound exceeds this is named in result.warnings
FRICTION_WARN_STEPS = 10_000   # a run with at least this many steps begun in the regularised friction regime, and
FRICTION_WARN_SHARE = 0.5      # at least this share of its steps, says in result.warnings that friction limits them


@dataclass
class Contact:
    """One contact of an impact: point O_point (1-based, as in the paper) on a wall, or (kind 'stop') joint
    ``point`` on its stop ``wall`` ('theta_2_upper'), and its impulse."""

    point: int
    wall: str
    impulse: float        # N s along the wall's inward normal (>= 0: it pushes); N m s for a stop
    kind: str = "wall"    # 'wall' | 'stop' | 'link' (two capsule links: wall 'L<i>-L<j>', point i, links (i, j))
    #                       | 'obstacle' (link i on a fixed obstacle: wall 'L<i>/<name>', point i, links (i,))
    impulse_t: tuple = (0.0, 0.0)   # N s along the wall's two tangential axes, ascending (X1, X2 for a x3 wall),
                                    # or a link pair's or obstacle's t1, t2 (docs/simulation.md, "Friction at the
                                    # impacts of link pairs and obstacles"): friction at the impact (0 without)
    links: tuple = ()     # 'link': the two links (i, j), 1-based; the impulse pushes them apart along their normal;
    #                       'obstacle': (i,), the impulse pushing link i off the obstacle

    @property
    def label(self) -> str:
        return self.wall if self.kind in ("stop", "link", "obstacle") else f"O{self.point}/{self.wall}"


@dataclass
class Impact:
    t: float
    contacts: list[Contact]
    energy_before: float
    energy_after: float
    complementarity: bool               # not plain Eq. 47: a contact took no impulse, or several rounds
    q: np.ndarray
    qd_before: np.ndarray
    qd_after: np.ndarray
    rounds: int = 1                     # rounds of the impact law (Newton's law with complementarity)
    plastic: bool = False               # the rounds were closed by a plastic round (energy lost, also at e = 1)
    energy_rest: float = 0.0            # J: kinetic energy taken by contacts that landed (come to rest)
    roundoff: float = 1e-10             # the law's relative round-off bound on the energy (grows with cond(I_f))
    law_elastic: bool = False           # the law (each contact's own e, before landings) had only e = 1 contacts
                                        # take impulses, no plastic round: energy_after + energy_rest = energy_before
    law: str = "frictionless"           # the law applied: 'frictionless' (no contact with friction took part), 'gdi',
                                        # 'gdi-common-e' (a round solved with its smallest e), 'newton-coulomb',
                                        # 'gdi-tangential' (a tangential impact: sliding resting contacts in the
                                        # Painleve paradox stopped by an impact without collision)
    residual: float = 0.0               # the frictional law's largest relative violation of its conditions
    roundoff_cause: str = "floor"       # roundoff's largest part: 'floor' (none above 1e-10), 'stored' (the stored
                                        # velocities' energy miss: their rounding to doubles), 'evaluation' (what
                                        # evaluating the momentum balance resolves), 'law' (the contact law's
                                        # residual), 'identity' (evaluating T), 'rounds-energy' (T's change after
                                        # several rounds beyond the law's), 'hold' (holding resting contacts after
                                        # the law), 'link' (a law with link pairs or obstacles)
    dt_dp: dict | None = None           # simulate(sensitivities=...): d t_impact / d(direction) by direction name
                                        # (NaN from the first event not differentiated on)


@dataclass
class ContactEvent:
    """A change of the resting contacts at time t: point O_point (1-based) on a wall became resting ('rest') or was
    released ('release'); or, resting on a wall with Coulomb friction, came to stick ('stick': sliding -> stuck, or
    landed and stuck) or began to slip ('slip': stuck -> sliding, its cone's edge reached or an impact set it
    sliding).  An impact's events carry its time; result.n_sticks and result.n_slips count the 'stick' and 'slip'
    events."""

    t: float
    point: int
    wall: str
    kind: str             # 'rest' | 'release' | 'stick' | 'slip'
    dt_dp: dict | None = None   # simulate(sensitivities=...): d t / d(direction) by direction name (a landing: its
                                # impact's; NaN from the first event not differentiated on)

    @property
    def label(self) -> str:
        return f"O{self.point}/{self.wall}" if self.wall in WALL_NAMES else self.wall   # a stop, pair, obstacle: its own


@dataclass
class SimulationResult:
    """What simulate() returns.  status 0: reached t_end; -1: ended early (see message)."""

    t: np.ndarray                 # sample times (s)
    q: np.ndarray                 # (len(t), nq) configuration samples, layout of Eq. 13
    qd: np.ndarray                # (len(t), nq) velocity samples (pre-impact at an impact time)
    impacts: Impacts              # the Impact records in time order (or only their count: keep_impacts=False)
    t_final: float
    q_final: np.ndarray
    qd_final: np.ndarray
    energy_initial: float
    energy_final: float
    n_steps: int
    n_rejected: int
    n_rhs: int
    status: int
    message: str
    method: str
    options: dict = field(default_factory=dict)
    contact_events: list = field(default_factory=list)   # ContactEvent, in time order
    resting_final: list = field(default_factory=list)     # (point, wall) of the contacts resting at t_final
    warnings: list = field(default_factory=list)          # results of limited accuracy, one sentence each
    energy_scale: float = 1.0     # J: max(T0 + |V0|, M g L, |work_input|, the losses), what energy_drift is measured on
    work_input: float = 0.0       # J: work of the inputs, int u . qd_actuated dt
    loss_damping: float = 0.0     # J: energy the joint dampers took, int C theta_dot^2 dt (>= 0)
    loss_friction: float = 0.0    # J: energy sliding friction took at resting contacts (>= 0)
    u: np.ndarray | None = None        # (len(t), nu) the inputs at the sample times (None: no inputs)
    n_chart_switches: int = 0          # switches between the base charts near the gimbal lock (gac_sim.n_chart_switches)
    n_sticks: int = 0                  # resting points on rough walls that came to stick: the 'stick' events
    n_slips: int = 0                   # stuck points that began to slip: the 'slip' events
    n_tangential_impacts: int = 0      # tangential impacts (law 'gdi-tangential', also in impacts): sliding resting
                                       # contacts with no consistent forces (Painleve paradox, the dynamic jam)
    n_painleve_choices: int = 0        # choices the Painleve paradox left open (gac_sim.n_painleve_choices): a slow
                                       # point's slip direction without consistent forces set aside, resting
                                       # contacts released where they may leave instead (the least normal force)
    sensitivities: "sensitivity.Sensitivities | None" = None   # simulate(sensitivities=...): d x(t_final)/d(direction)

    @property
    def sensitivity_status(self) -> str | None:
        """'valid', or what ended the sensitivities (None: none asked for)."""
        return None if self.sensitivities is None else self.sensitivities.status

    @property
    def sensitivity_message(self) -> str | None:
        """The verdict in a sentence: the event not differentiated, its contact and time (None: none asked for)."""
        return None if self.sensitivities is None else self.sensitivities.message

    @property
    def n_impacts(self) -> int:
        return len(self.impacts)

    @property
    def t_first_impact(self) -> float:
        """s; NaN when there was none."""
        return self.impacts.t_first

    @property
    def success(self) -> bool:
        return self.status == 0

    @property
    def loss_impacts(self) -> float:
        """J: the energy the impacts took, sum of (E before - E after) over the impacts (>= 0; it includes
        what landings on a wall took, Impact.energy_rest)."""
        return self.impacts.energy_loss

    @property
    def energy_residual(self) -> float:
        """J: what the energy balance leaves, E_final - E_initial + loss_impacts + loss_damping +
        loss_friction - work_input (E = T + V, springs' potential included): the integration error of
        the flight phases."""
        return (self.energy_final - self.energy_initial + self.loss_impacts + self.loss_damping
                + self.loss_friction - self.work_input)

    @property
    def energy_drift(self) -> float:
        """energy_residual / energy_scale: the relative error of the energy balance, on a scale that does
        not vanish for a chain at rest (M g L) or whose energy happens to be near 0 (T0 + |V0|)."""
        return self.energy_residual / self.energy_scale

    def energy_summary(self) -> str:
        """One line: initial and final energy, inputs' work, losses in dampers and at impacts, and the residual."""
        driven = (f"work of the inputs {self.work_input:.6g} J, taken by dampers {self.loss_damping:.6g} J, "
                  if self.work_input or self.loss_damping else "")
        if self.loss_friction:
            driven += f"taken by friction {self.loss_friction:.6g} J, "
        return (f"energy: initial {self.energy_initial:.12g} J, final {self.energy_final:.12g} J, {driven}lost at impacts "
                f"{self.loss_impacts:.6g} J; balance residual {self.energy_residual:.3e} J = "
                f"{self.energy_drift:.3e} of {self.energy_scale:.6g} J (max(T0 + |V0|, M g L"
                f"{', |W_in|, D_damp' if driven else ''}))")

    def impact_table(self, limit: int | None = None) -> str:
        """The impacts, one line each; ``limit``: at most this many lines, the first and the last half of
        them around a line saying how many were left out (None: all)."""
        lines = [f"{'#':>3} {'t (s)':>14}  contacts (point/wall: impulse N s)"]
        for k, impact in _shown(self.impacts, limit, "impacts"):
            if impact is None:
                lines.append(k)
                continue
            contacts = ", ".join(f"{c.label}: {c.impulse:.6g}" for c in impact.contacts)
            lines.append(f"{k:>3} {impact.t:14.9f}  {contacts}")
        return "\n".join(lines)

    def contact_event_table(self, limit: int | None = None) -> str:
        """The resting-contact events (rest, release, stick, slip), one line each ('' when there are none);
        ``limit`` as impact_table's."""
        if not self.contact_events:
            return ""
        lines = [f"resting contact: {'t (s)':>14}  point/wall"]
        for _, e in _shown(self.contact_events, limit, "contact events"):
            lines.append(_ if e is None else f"{e.kind:>15} {e.t:14.9f}  {e.label}")
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {
            "impacts": [{"t": i.t, "contacts": [{"point": c.point, "wall": c.wall, "impulse": c.impulse,
                                                 "impulse_t": list(c.impulse_t), "kind": c.kind,
                                                 **({"links": list(c.links)} if c.kind == "link" else {})}
                                                for c in i.contacts],
                         "energy_before": i.energy_before, "energy_after": i.energy_after,
                         "complementarity": i.complementarity, "law": i.law, "residual": i.residual,
                         "roundoff_cause": i.roundoff_cause,
                         "roundoff": i.roundoff} for i in self.impacts],
            "t_final": self.t_final, "q_final": self.q_final.tolist(), "qd_final": self.qd_final.tolist(),
            "energy_initial": self.energy_initial, "energy_final": self.energy_final,
            "loss_impacts": self.loss_impacts, "energy_residual": self.energy_residual,
            "energy_scale": self.energy_scale, "energy_drift": self.energy_drift,
            "work_input": self.work_input, "loss_damping": self.loss_damping,
            "loss_friction": self.loss_friction,
            "n_rhs": self.n_rhs, "n_steps": self.n_steps, "n_rejected": self.n_rejected,
            "n_chart_switches": self.n_chart_switches, "n_sticks": self.n_sticks, "n_slips": self.n_slips,
            "n_tangential_impacts": self.n_tangential_impacts, "n_painleve_choices": self.n_painleve_choices,
            "status": self.status, "message": self.message, "method": self.method, "options": self.options,
            "contact_events": [{"t": e.t, "point": e.point, "wall": e.wall, "kind": e.kind}
                               for e in self.contact_events],
            "resting_final": [{"point": point, "wall": wall} for point, wall in self.resting_final],
            "warnings": list(self.warnings),
        }


def _check(condition: bool, field_name: str, message: str) -> None:
    if not condition:
        raise ValueError(f"{field_name}: {message}")


def _real(value, field_name: str) -> float:
    """A real number argument (NaN and infinities pass here; the range checks refuse them)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{field_name}: expected a number, got {value!r} ({type(value).__name__})")
    return float(value)


def _integer(value, field_name: str, lowest: int, meaning: str) -> int:
    """An integer argument >= lowest."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float, np.floating)) \
            or not np.isfinite(value) or int(value) != value or value < lowest:
        raise ValueError(f"{field_name}: must be an integer >= {lowest} ({meaning}), got {value!r}")
    return int(value)


def _shown(rows: list, limit: int | None, what: str):
    """(number, row) of the rows a table shows: all, or the first and last limit // 2 with ('... N more
    WHAT ...', None) between them."""
    if limit is None or len(rows) <= limit:
        yield from enumerate(rows, start=1)
        return
    head = max(limit // 2, 1)
    tail = max(limit - head, 1)
    yield from enumerate(rows[:head], start=1)
    yield f"    ... {len(rows) - head - tail} more {what} ...", None
    yield from enumerate(rows[len(rows) - tail:], start=len(rows) - tail + 1)


# The options of the C loop (gac_options), set by simulate(**options) under these names.  Their defaults are the C
# library's (gac_default_options) and their ranges its own (gac_check_options): one rule for Python, the standalone
# program and the FMU.  None leaves an option at its default.
LOOP_OPTIONS = {
    "rtol": "relative tolerance of the adaptive methods",
    "atol": "absolute tolerance of the adaptive methods (per coordinate)",
    "dt": "rk4: the step (s); adaptive methods: the first step (None: automatic)",
    "h_max": "the largest step (s; 0: unbounded)",
    "event_samples": "interpolant samples per step searched for wall crossings",
    "event_tol": "time tolerance of event location (s)",
    "contact_tol": "approaching contacts within this gap (m) of their wall join a simultaneous impact",
    "max_steps": "steps allowed between two events (impacts, contact changes; 0: unbounded)",
    "max_impacts": "the run stops after this many impacts (impact accumulation; 0: unbounded)",
    "max_wall_time": "s of wall time the run may take (None: unbounded)",
    "rest_height": "m: a bounce rising less than this ends in resting contact (None: 10 contact_tol; 0: never)",
    "zeno_impacts": "a contact rests after this many impacts at shrinking intervals (0: never)",
    "energy_tol": "the energy balance's allowed residual per energy scale (None: automatic; 0: off)",
    "impact_law": "the impact law at walls with friction: 'gdi' (default; never gains energy), 'newton-coulomb' "
                  "(can gain energy: the run then stops) or 'frictionless' (friction only on resting contacts)",
    "stick": "True (default): a point resting on a rough wall sticks as a constraint until |lambda_T| reaches "
             "c_f lambda_N; False: the regularised friction alone (it creeps below friction_velocity)",
}
def impact_law_code(model: CompiledModel, law) -> int:
    """The library's code of an impact law named by the user ('gdi', 'newton-coulomb', 'frictionless')."""
    _check(law in CHOSEN_LAWS, "impact_law", f"must be one of {CHOSEN_LAWS}, got {law!r}")
    return model.impact_law_code(law)


_INTEGER_OPTIONS = ("event_samples", "max_steps", "max_impacts", "zeno_impacts")


def _loop_options(model: CompiledModel, method: str, given: dict, chart_switch: float):
    """The C options of a run: the library's defaults, ``method``, the given options and simulate(charts=) as
    chart_switch, checked by the library."""
    unknown = sorted(set(given) - set(LOOP_OPTIONS))
    _check(not unknown, unknown[0] if unknown else "", "no such option of simulate(); the loop's options are "
           + ", ".join(LOOP_OPTIONS))
    _check(method in METHODS, "method", f"must be one of {METHODS}, got {method!r}")
    opt = model.c.new("options")
    model.c.default_options(opt)
    opt.method = {"rk4": model.lib.GAC_METHOD_RK4, "dopri5": model.lib.GAC_METHOD_DOPRI5,
                  "dop853": model.lib.GAC_METHOD_DOP853}[method]
    for name, value in given.items():
        if value is None:
            continue
        if name == "impact_law":
            value = impact_law_code(model, value)
        elif name == "stick":
            _check(isinstance(value, (bool, np.bool_)) or value in (0, 1), name,
                   f"must be True or False ({LOOP_OPTIONS[name]}), got {value!r}")
            value = int(bool(value))
        elif name in _INTEGER_OPTIONS:
            whole = not isinstance(value, bool) and isinstance(value, (int, np.integer, float, np.floating)) \
                and np.isfinite(value) and int(value) == value
            _check(whole and abs(value) < 2 ** 31, name, f"must be an integer ({LOOP_OPTIONS[name]}), got {value!r}")
            value = int(value)
        else:
            value = _real(value, name)
        setattr(opt, name, value)
    opt.chart_switch = chart_switch
    given = {**given, "chart_switch": chart_switch}
    field_text = model.ffi.new("const char **")
    if model.lib.gac_check_options(opt, field_text) != model.lib.GAC_OK:
        field_name, rule = model.ffi.string(field_text[0]).decode().split(": ", 1)
        raise ValueError(f"{field_name}: {rule}, got {given.get(field_name)!r}")
    return opt


class Impacts(Sequence):
    """The impacts of a run in time order: their count, the first one's time and the energy they took, always; the
    records themselves (Impact rows) unless the run was told not to keep them (simulate(keep_impacts=False), for
    studies of many runs: then only len(), t_first and energy_loss are there)."""

    def __init__(self, kept: bool = True):
        self.kept = kept
        self._rows: list[Impact] = []
        self.count = 0
        self.t_first = float("nan")    # s; NaN when there was none
        self.energy_loss = 0.0         # J: sum of (energy_before - energy_after)

    @classmethod
    def of(cls, rows: list[Impact]) -> "Impacts":
        """The kept impacts of a list of records (a run assembled from parts)."""
        impacts = cls()
        for row in rows:
            impacts._keep(row)
        return impacts

    def _keep(self, row: Impact) -> None:
        self._count(row.t, row.energy_before - row.energy_after)
        self._rows.append(row)

    def _count(self, t: float, loss: float) -> None:
        if self.count == 0:
            self.t_first = t
        self.count += 1
        self.energy_loss += loss

    def add(self, model: CompiledModel, record) -> None:
        """Count the impact the C loop just applied (its post-conditions were checked there), and keep it."""
        if self.kept:
            self._keep(_read_impact(model, record))
        else:
            self._count(float(record.t), float(record.energy_before) - float(record.energy_after))

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, index):
        if not self.kept:
            raise IndexError(f"impacts: this run kept only their count ({self.count}), first time and energy "
                             "(simulate(keep_impacts=False)); run with keep_impacts=True for the records")
        return self._rows[index]

    def __eq__(self, other) -> bool:
        """Equal to a list or tuple of Impact records (or another Impacts) with the same records."""
        if isinstance(other, (list, tuple, Impacts)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None

    def __repr__(self) -> str:
        return f"Impacts({self.count} impact(s){'' if self.kept else ', records not kept'})"


def simulate(scene: Scene | str | CompiledModel, t_end: float, method: str = "dopri5", t_eval=None, *,
             p=None, q0=None, qd0=None, u=None, progress=None, charts: bool = True, check_start: bool = True,
             keep_impacts: bool = True, sensitivities=None, sensitivities_at_samples: bool = False,
             one_sided: bool = False, **options) -> SimulationResult:
    """Simulate the scene's hybrid dynamics from its initial state over [0, t_end].

    method        'dopri5' (adaptive Dormand-Prince 5(4), rtol/atol), 'dop853' (adaptive 8(5,3)),
                  or 'rk4' (fixed step dt, as the paper)
    t_eval        sample times (ascending, within [0, t_end]); default: every 1 ms and t_end
    p, q0, qd0    override the scene's parameters (a vector in the order of model.parameter_names, or a dict
                  {name: value} of the ones that change) and initial state (q0, qd0 in the full layout of Eq. 13)
    u             the inputs of a driven model (runtime.inputs): None (0), constant values (one per input, in
                  the order of model.input_names), an InputSchedule (values at times, held or linear; evaluated
                  in C, each of its times a step boundary), or a function u(t, q, qd) of the full-layout state,
                  called back from C at every stage (slower: a Python call per stage); Controller(f, jacobian=J)
                  (J(t, q, qd) -> (du/dq, du/dqd), nu x nq_full each) for sensitivities through the feedback, and
                  pd(model, kp, kd, target) a PD controller with its Jacobian
    progress      progress(t, n_steps, n_impacts), called by the C loop every GAC_LOOK_STEPS steps and at every
                  event; returning False stops the run (status -1, "stopped by the progress callback"), as does an
                  exception in it
    charts        near the gimbal lock of the base chart the C loop integrates on the model's second base chart
                  (where chart A's measure falls below 0.3, and back on A above 0.6; gac_options.chart_switch):
                  True (default), or the threshold itself (a number in [0.1, 0.35]); False: never (the run stops
                  with GAC_ERR_GIMBAL_LOCK).  Samples, impacts and the final state are in the scene's coordinates
                  whichever chart was integrated; result.n_chart_switches counts the switches
    check_start   refuse q0/p overrides that put a contact point outside its wall beyond round-off (False:
                  a restart from a state the loop itself produced, with its resting contacts held at
                  their landing gaps)
    keep_impacts  False: count the impacts (len(result.impacts), t_first_impact, loss_impacts) without
                  keeping their records, for studies of many runs
    sensitivities directions to differentiate the run along (runtime.sensitivities): "q0[NAME]", "qd0[NAME]"
                  (a coordinate of Eq. 13's layout by name or index) and parameter names ("e_x2_min", "g");
                  result.sensitivities holds d x(t_final)/d(direction) with named rows and columns, each
                  impact's dt_dp the impact time's derivatives, result.sensitivity_status / _message the verdict
                  (events the C loop does not differentiate make them NaN from there on: docs/simulation.md,
                  "Sensitivities")
    sensitivities_at_samples  True: also d x(t_i)/d(direction) at every sample t_i (result.sensitivities.at_samples,
                  len(t) x 2 nq x k), each formed by one more Runge-Kutta step of the directions from its step's start
                  (costs about one step of the directions per sample)
    one_sided     True: at a mode boundary inside an impact (a contact's impulse ~0 at the law's bound) give the
                  right and left derivatives (result.sensitivities.right / .left, status 'one-sided') instead of
                  ending the sensitivities there; the C loop carries each direction twice (+ and -), so it costs
                  about twice the directions' work; without a boundary the result is as without it
    **options     the C loop's options (LOOP_OPTIONS: rtol, atol, dt, h_max, event_samples, event_tol, contact_tol,
                  max_steps, max_impacts, max_wall_time, rest_height, zeno_impacts, energy_tol), with the C library's
                  defaults
                  and ranges; the budgets stop the run with status -1 and a message that says where the time went
                  energy_tol: the energy balance's allowed residual relative to the run's energy scale: the C loop
                  stops with status -1 ("energy drift") at the first step end where E - E0 - W_inputs + D_dampers +
                  D_friction + impact losses exceeds it (gac.h, "Energy balance"); None: min(0.1, max(1e-8, 1e4 rtol))
                  for dopri5 / dop853, off for rk4; 0: off
    Samples, final state and impact states are returned in the full layout of Eq. 13 whatever the model.
    """
    model = scene if isinstance(scene, CompiledModel) else load_model(scene)
    if sensitivities is not None:
        model.require_tangents("sensitivities")
    ffi, lib, c = model.ffi, model.lib, model.c
    t_end = _real(t_end, "t_end")
    _check(np.isfinite(t_end) and t_end >= 0, "t_end", f"must be a finite time >= 0 s, got {t_end!r}")
    opt = _loop_options(model, method, options, chart_switch=0.3 if charts is True else 0.0 if charts is False
                        else _real(charts, "charts"))

    nq, nx = model.nq, 2 * model.nq
    layout = model.layout
    overridden = p is not None or q0 is not None      # the scene's own values were checked when it was loaded
    if isinstance(p, dict):
        p = model.parameters(p)
    source = input_source(model, u)
    try:
        p = model.p if p is None else np.ascontiguousarray(p, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"p: expected {len(model.p)} numbers ({', '.join(model.scene.parameter_names())}), "
                         f"got {p!r}") from None
    if overridden:
        _check_parameters(model, p)
    q = model.q0 if q0 is None else _reduce(layout, q0, "q0", velocity=False)
    qd = model.qd0 if qd0 is None else _reduce(layout, qd0, "qd0", velocity=True)
    if overridden and check_start:
        _check_inside(model, q, p, "q0" if q0 is not None else "initial.q")
    t_eval = sample_times(t_eval, t_end)

    sim = c.new("sim")
    state = sim.base          # the library's state (gac_sim): t, x, counters; its arrays live in *sim
    code = c.sim_init(sim, 0.0, model._ptr(q), model._ptr(qd), model._ptr(p), opt)
    if code < 0:
        raise ValueError(f"simulate: {model.error_message(code)}")
    keep_alive = attach(model, sim, source)   # noqa: F841  (the schedule or handle the C loop points at)
    sens = sens_work = directions = None
    if sensitivities is not None:
        directions, seed_x, seed_p = sensitivity.directions(model, sensitivities, p)
        seed_x, seed_p = sensitivity.seeds(seed_x, seed_p, bool(one_sided))
        k = len(seed_x)                   # one-sided: each direction twice, +e_j then -e_j
        sens = ffi.new("gac_sens *")
        sens_work = np.zeros(lib.gac_sens_ndouble(ffi.addressof(c.model), k))
        code = lib.gac_sens_attach(ffi.addressof(sim, "base"), sens, k, model._ptr(seed_x), model._ptr(seed_p) if seed_p.size else ffi.NULL,
                                   model._ptr(sens_work))
        if code != lib.GAC_OK:
            raise ValueError(f"sensitivities: {model.error_message(code)}")
        sens.one_sided = 1 if one_sided else 0
    elif sensitivities_at_samples or one_sided:
        raise ValueError(f"{'one_sided' if one_sided else 'sensitivities_at_samples'}: needs sensitivities=[...] "
                         "(the directions)")
    s_eval = None
    if sens is not None and sensitivities_at_samples:     # S at each sample, written by the C loop with x_eval
        s_eval = np.full((len(t_eval), int(sens.k), nx), np.nan)
        sens.S_eval = model._ptr(s_eval)
    watch = _watch(model, sim, opt.max_wall_time, progress)   # noqa: F841  (the clock and progress handles)

    # the loop: one C call per impact or change of the resting contacts, up to t_end or the loop's end
    x_eval = np.zeros((len(t_eval), nx))
    i_eval = ffi.new("int *", 0)
    while i_eval[0] < len(t_eval) and t_eval[i_eval[0]] <= 0.0:      # samples at the start (as sim_init left it)
        row = x_eval[i_eval[0]]          # in chart A's coordinates, whichever base chart the loop starts on
        c.sim_state(sim, ffi.NULL, model._ptr(row[:nq]), model._ptr(row[nq:]))
        if s_eval is not None:                                       # (chart A's too)
            lib.gac_sens_state(ffi.addressof(sim, "base"), model._ptr(s_eval[i_eval[0]]))
        i_eval[0] += 1
    record = c.new("impact_record")
    rec = record.base         # the library's record (gac_impact_record); its arrays live in *record
    t_eval_ptr = ffi.cast("double *", ffi.from_buffer(t_eval))
    x_eval_ptr = ffi.cast("double *", ffi.from_buffer(x_eval))
    T0, V0 = model.energy(q, qd, p)
    impacts = Impacts(kept=keep_impacts)
    contact_events: list[ContactEvent] = []
    segment_t, segment_steps = float(state.t), 0       # the last event: max_steps counts from it
    while True:
        code = c.sim_advance(sim, float(t_end), t_eval_ptr, len(t_eval), i_eval, x_eval_ptr, record)
        if code == lib.GAC_SIM_IMPACT:
            impacts.add(model, rec)
            if sens is not None and keep_impacts:
                impacts[len(impacts) - 1].dt_dp = dict(zip(directions, ffi.unpack(sens.dt_impact, len(directions))))
        if code in (lib.GAC_SIM_IMPACT, lib.GAC_SIM_CONTACT):
            events = _read_contact_events(model, rec)
            if sens is not None and (code == lib.GAC_SIM_IMPACT or rec.nreleased > 0 or rec.nslipped > 0
                                     or rec.nstuck > 0):
                dt_dp = dict(zip(directions, ffi.unpack(sens.dt_impact, len(directions))))
                for event in events:
                    event.dt_dp = dict(dt_dp)
            contact_events += events
            segment_t, segment_steps = float(state.t), int(state.n_steps) + int(state.n_rejected)
            continue
        break
    if source.error is not None:          # the input function (a bad value: GAC_ERR_BAD_INPUT) or its Jacobian
        raise source.error
    # the result, in the full layout of Eq. 13 and chart A's coordinates, whichever base chart was integrated
    x_final = np.zeros(nx)
    c.sim_state(sim, ffi.NULL, model._ptr(x_final[:nq]), model._ptr(x_final[nq:]))
    status, message = (0, "reached t_end") if code == lib.GAC_SIM_END else \
        (-1, _end_message(model, state, code, segment_t, segment_steps, len(impacts), rec, x_stop=x_final))
    if status == 0 and int(state.n_chart_switches):
        message += f"; {int(state.n_chart_switches)} chart switch(es)"
    if int(state.n_tangential_impacts):
        message += (f"; {int(state.n_tangential_impacts)} tangential impact(s): sliding friction in the Painleve "
                    "paradox (the resting contacts' system no P-matrix) stopped by an impact without collision")
    if int(state.n_painleve_choices):
        message += (f"; {int(state.n_painleve_choices)} Painleve choice(s): resting contacts without consistent "
                    "sliding forces where another solution exists (a slow point's slip direction set aside, or "
                    "contacts released that may leave their walls: the least normal force)")
    n = i_eval[0]
    accuracy = impact_warnings(impacts, model, p) if keep_impacts else []
    warnings = model.scene.warnings + accuracy + friction_warnings(model, p, state, method)
    q_samples, qd_samples = layout.expand(x_eval[:n, :nq]), layout.expand(x_eval[:n, nq:], velocity=True)
    u_samples = None
    if model.nu:
        u_samples = np.array([source.value_at(t, qs, qds) for t, qs, qds in zip(t_eval[:n], q_samples, qd_samples)])
        u_samples = u_samples.reshape(n, model.nu)
    return SimulationResult(
        t=t_eval[:n].copy(), q=q_samples, qd=qd_samples, u=u_samples,
        work_input=float(state.work_input), loss_damping=float(state.loss_damping),
        loss_friction=float(state.loss_friction),
        impacts=impacts, t_final=float(state.t), q_final=layout.expand(x_final[:nq]),
        qd_final=layout.expand(x_final[nq:], velocity=True),
        energy_initial=T0 + V0, energy_final=sum(model.energy(x_final[:nq], x_final[nq:], p)),
        n_steps=int(state.n_steps), n_rejected=int(state.n_rejected), n_rhs=int(state.n_rhs), status=status,
        message=message + (f"; {len(accuracy)} impact(s) of limited accuracy (see warnings)" if accuracy else ""),
        method=method, contact_events=contact_events, warnings=warnings,
        energy_scale=max(energy_scale(model.scene, p, T0, V0), abs(float(state.work_input)), float(state.loss_damping),
                         float(state.loss_friction)),
        resting_final=[(model.contacts[state.resting[k]][0], model.contacts[state.resting[k]][1].name)
                          for k in range(state.nresting)],
        options={"t_end": t_end, **{name: _option_value(opt, name) for name in LOOP_OPTIONS},
                 "chart_switch": float(opt.chart_switch)},
        n_chart_switches=int(state.n_chart_switches), n_sticks=int(state.n_sticks), n_slips=int(state.n_slips),
        n_tangential_impacts=int(state.n_tangential_impacts), n_painleve_choices=int(state.n_painleve_choices),
        sensitivities=None if sens is None else sensitivity.read(model, sim, sens, directions, status == 0, message,
                                                                 None if s_eval is None else s_eval[:n]))


def _option_value(opt, name: str):
    """An option as the run used it, None where the C value means 'automatic' or 'unbounded' (dt, rest_height,
    max_wall_time)."""
    value = getattr(opt, name)
    if name in ("dt", "max_wall_time") and value == 0.0 or name in ("rest_height", "energy_tol") and value < 0.0:
        return None
    if name == "stick":
        return bool(value)
    return int(value) if name in _INTEGER_OPTIONS else float(value)


def weight_scale(scene: Scene, p: np.ndarray) -> float:
    """M g L: the work to lift the whole chain by its own length (an energy scale that is not 0 for a
    chain at rest on the floor, where T + V can be exactly 0)."""
    def value(kind, owner=None):
        return p[scene.parameter_index(kind, owner)]
    mass = length = 0.0
    for i, link in enumerate(scene.links, start=1):
        l = value("l", i)
        mass += value("mu", i) * l if link.kind == "line" else value("m", i)
        length += l
    return float(mass * abs(value("g")) * length)


def energy_scale(scene: Scene, p: np.ndarray, T0: float, V0: float) -> float:
    """max(T0 + |V0|, M g L): the scale of a run's energy balance (> 0 unless nothing can move)."""
    return max(T0 + abs(V0), weight_scale(scene, p), 1e-300)


def impact_warnings(impacts: list[Impact], model: CompiledModel | None = None, p=None) -> list[str]:
    """One sentence for each impact whose measured accuracy (record.roundoff, refined after the law) stays above
    ROUNDOFF_WARN, naming its cause (accuracy_cause) when the model and its parameters p are given."""
    flagged = [i for i in impacts if i.roundoff > ROUNDOFF_WARN]
    if model is None:
        return [f"impact at t = {i.t:.9g} s: its energy is accurate only to {i.roundoff:.2g} (relative; I_f is "
                "ill-conditioned there: extreme mass, length or inertia ratios)" for i in flagged]
    layout = model.layout
    return [f"impact at t = {i.t:.9g} s: its energy is accurate only to {i.roundoff:.2g} (relative): "
            + accuracy_cause(model, p, layout.reduce(i.q), layout.reduce(i.qd_before),
                             impact_contact_indices(model, i), i.law, i.residual, i.roundoff_cause)
            for i in flagged]


def impact_contact_indices(model: CompiledModel, impact: Impact) -> list[int | None]:
    """The model's indices of an impact's contacts (None for one not found), as accuracy_cause takes them."""
    return [_contact_index(model, c) for c in impact.contacts]


def _contact_index(model: CompiledModel, contact: Contact) -> int | None:
    """The model's index of an impact's contact (None if not found)."""
    for k, (point, wall) in enumerate(model.contacts):
        if point == contact.point and wall.name == contact.wall:
            return k
    return None


CHART_NEAR = 1e-2          # the base chart's measure chi below which an inaccurate impact is blamed on it
DEPENDENT_CONTACTS = 1e8   # cond(J I_f^-1 J^T) over an impact's contacts above which they are nearly dependent
CANCELLING = 1e3           # sum |qd_i| |(I_f qd)_i| / 2T above which the velocities' components cancel


# Which of an impact's checks refused it (record.refusal by name, model.REFUSALS), as a phrase
REFUSED = {"accuracy": "its measured accuracy is above GAC_IMPACT_ROUNDOFF_MAX",
           "elastic-rounds": "its elastic rounds (every contact e = 1) did not end, and a plastic round would take "
                             "energy",
           "elastic-change": "its elastic law changed the kinetic energy beyond its accuracy",
           "pull": "an impulse pulls beyond round-off",
           "gain": "the kinetic energy grew beyond its accuracy",
           "approach": "a contact is left approaching its wall faster than its accuracy allows"}


# What each part of an impact's measured accuracy stands for (Impact.roundoff_cause, its largest part), as the lead
# of its cause
ROUNDOFF_PARTS = {
    "stored": "the velocities after, stored as doubles, miss the law's energy by that much (each component's "
              "rounding chosen to bring it nearest)",
    "evaluation": "evaluating the momentum balance resolves no more",
    "law": "the contact law's residual",
    "identity": "evaluating the kinetic energy resolves no more",
    "rounds-energy": "after its rounds the kinetic energy changed beyond what the law gives",
    "hold": "holding the resting contacts after the law",
    "link": "the momentum balance of its law with link pairs or obstacles",
}


def accuracy_cause(model: CompiledModel, p, q, qd, contacts: list, law: str = "frictionless",
                   residual: float = 0.0, part: str = "floor") -> str:
    """Why an impact at (q, qd) (the model's coordinates; contacts: the model's contact indices) could not be solved
    more accurately, as a phrase: what its accuracy is made of (part: the record's largest part, ROUNDOFF_PARTS;
    'floor': not known) and why the chain makes it so, the first that applies of the frictional law's own residual
    (where part is the law's or not known), the base chart near its singular pose (chi = |det E| below CHART_NEAR:
    I_f's smallest eigenvalue falls like chi^2), contacts whose rows are nearly dependent (cond(J I_f^-1 J^T) above
    DEPENDENT_CONTACTS), velocities whose components cancel in the energy (along a soft direction of I_f), and else
    I_f's condition with the chain's most extreme ratio (ill_conditioning)."""
    p = model.parameters() if p is None else np.asarray(p, dtype=float)
    if part in ("floor", "law") and law != "frictionless" and residual > 1e-11:
        return f"the frictional law's solve left its conditions at {residual:.2g} (relative; " + \
            _friction_residual_cause(model, p, q, [c for c in contacts if c is not None]) + ")"
    why = _conditioning_cause(model, p, q, qd, contacts)
    return why if part not in ROUNDOFF_PARTS else f"{ROUNDOFF_PARTS[part]}: {why}"


def _conditioning_cause(model: CompiledModel, p, q, qd, contacts: list) -> str:
    """What in the chain at (q, qd) makes an impact's residuals large, as a phrase (accuracy_cause's order)."""
    planar = model.layout.planar_normal is not None
    chi = chart_measure(model, q)
    if chi < CHART_NEAR:
        return (f"the base chart is near its singular pose: its measure chi = |det E| = {chi:.2g} (I_f's "
                "smallest eigenvalue falls like chi^2)")
    M = model.mass_matrix(q, p)
    chain, block = impact_chain(model, contacts)       # of several chains, one chain's own block of I_f
    eigenvalues = np.linalg.eigvalsh(M[np.ix_(block, block)])
    cond = float(eigenvalues[-1] / eigenvalues[0]) if eigenvalues[0] > 0.0 else math.inf
    rows = []
    for c in contacts:
        if c is None:
            continue
        point, wall = model.contacts[c]
        if hasattr(wall, "axis") and (point, wall.axis) in model.contact_rows:
            rows.append(model.contact_rows.index((point, wall.axis)))
    if len(rows) > 1:
        N = model.contact_jacobian(q, p)[rows]
        A = N @ np.linalg.solve(M, N.T)
        cond_A = float(np.linalg.cond(A))
        if cond_A > DEPENDENT_CONTACTS:
            return (f"its {len(rows)} contacts' rows are nearly dependent: cond(J I_f^-1 J^T) = {cond_A:.2g} over "
                    "them")
    own = "" if chain is None else f" (chain {chain}'s block)"
    momentum = M[np.ix_(block, block)] @ qd[block]
    energy2 = float(qd[block] @ momentum)
    if energy2 > 0.0:
        cancel = float(np.abs(qd[block]) @ np.abs(momentum)) / energy2
        if cancel > CANCELLING:
            return (f"the velocities' components cancel in the energy (sum |qd_i| |(I_f qd)_i| is {cancel:.2g} "
                    f"times 2T): they lie along a soft direction of I_f{own} (cond(I_f) = {cond:.2g})")
    if chain is None:
        return (f"I_f is ill-conditioned there (cond(I_f) = {cond:.2g}); "
                + ill_conditioning(model.scene, p, planar=planar))
    scene = model.scene
    return (f"I_f is ill-conditioned there (chain {chain}'s block of it: cond = {cond:.2g}); in chain {chain}, "
            + ill_conditioning(scene.chains[chain - 1], p[scene.parameter_map(chain)], planar=planar))


def impact_chain(model: CompiledModel, contacts: list) -> tuple[int | None, np.ndarray]:
    """Of a scene of several chains, where all an impact's contacts touch one chain k: (k, the model's coordinates of
    chain k), since I_f is block-diagonal over the chains and such an impact moves chain k alone; else (None, every
    coordinate)."""
    scene, every = model.scene, np.arange(model.nq)
    if not hasattr(scene, "chains"):
        return None, every
    points = set()
    for c in contacts:
        if c is not None:
            point, contact = model.contacts[c]
            points.add(point)
            if hasattr(contact, "j"):                   # a link pair: its other link too
                points.add(contact.j)
    touched = {k for k, chain in enumerate(scene.chains, start=1) for point in points
               if scene.point_offset(k) < point <= scene.point_offset(k) + chain.n + 1}
    if len(touched) != 1:
        return None, every
    (k,) = touched
    lo = scene.state_offset(k)
    return k, np.array([m for m, full in enumerate(model.layout.free) if lo <= full < lo + scene.chains[k - 1].nq])


def chart_measure(model: CompiledModel, q) -> float:
    """The base chart's measure chi = |det E| at q (chart A's coordinates): of several chains, the smallest of the
    chains whose theta_0 is a coordinate; 1 where no base can near its lock (planar or mounted)."""
    from codegen.charts import Chart
    scene, full = model.scene, model.layout.expand(q)
    chains = [(scene, 0)] if not hasattr(scene, "chains") else \
        [(chain, scene.state_offset(k)) for k, chain in enumerate(scene.chains, start=1)]
    return min([float(Chart.of(chain.base_twists).measure(full[offset + 1])) for chain, offset in chains
                if offset + 1 in model.layout.free], default=1.0)


def _friction_residual_cause(model: CompiledModel, p, q, contacts: list) -> str:
    """Why a frictional impact's law was left above round-off: one contact's problem always has a solution, found
    exactly, so its residual is the round-off of its velocities W Lambda + gamma where its contact-space inverse
    inertia W (its normal and tangential rows) is ill-conditioned; several contacts' cones may also interact."""
    rows = [model.contact_rows.index((point, axis)) for point, wall in (model.contacts[c] for c in contacts)
            for axis in range(3) if hasattr(wall, "axis") and (point, axis) in model.contact_rows]
    cond = math.inf
    if rows:
        N = model.contact_jacobian(q, p)[rows]
        cond = float(np.linalg.cond(N @ np.linalg.solve(model.mass_matrix(q, p), N.T)))
    if len(contacts) == 1:
        return (f"the round-off of its contact's velocities: its contact-space inverse inertia W = J I_f^-1 J^T over "
                f"its normal and tangential rows has cond(W) = {cond:.2g}")
    return f"contacts whose friction cones interact strongly; cond(W) = {cond:.2g} over their rows"


def ill_conditioning(scene: Scene, p, planar: bool) -> str:
    """The largest of the ratios that make I_f ill-conditioned, as a phrase: that of the links' masses, of their
    lengths, of their principal moments of inertia about their centres of mass (axial ones included; a planar model
    turns its links about their joint axes only, so only those count), and that of the whole chain's moment of
    inertia (straight, about its end: M L^2 / 3) to its largest link's, which measures how I_f grows with the
    number of links (docs/simulation.md).  p: the parameters (scene.parameter_names()); planar: the model is."""
    values = np.asarray(p, dtype=float).tolist()

    def value(kind, owner):
        return values[scene.parameter_index(kind, owner)]
    masses, lengths, moments = [], [], []          # (value, link); moments: (value, link, which one)
    for i, link in enumerate(scene.links, start=1):
        l = value("l", i)
        if link.kind == "line":
            m = value("mu", i) * l
            axial = l * value("Jxx", i)
            across_y, across_z = (m * l * l / 12 + l * value(key, i) for key in ("Jyy", "Jzz"))
            found = [(across_z, "about its joint axis")] if planar else \
                [(axial, "axial"), (across_y, "transverse"), (across_z, "transverse")]
        else:
            m = value("m", i)
            Ixx, Iyy, Izz, Ixy, Ixz, Iyz = (value(key, i) for key in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"))
            inertia = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
            found = [(Izz, "about its joint axis")] if planar else \
                [(v, "principal") for v in np.linalg.eigvalsh(inertia)]
        masses.append((m, i))
        lengths.append((l, i))
        moments += [(v, i, which) for v, which in found if v > 0.0]
    candidates = []
    if len(scene.links) > 1:
        (lo, a), (hi, b) = min(masses), max(masses)
        candidates.append((hi / lo, f"that of the links' masses: {hi:.3g} kg (link {b}) is {hi / lo:.2g} times "
                                    f"{lo:.3g} kg (link {a})"))
        (lo, a), (hi, b) = min(lengths), max(lengths)
        candidates.append((hi / lo, f"that of the links' lengths: {hi:.3g} m (link {b}) is {hi / lo:.2g} times "
                                    f"{lo:.3g} m (link {a})"))
    if moments:
        (lo, a, low), (hi, b, high) = min(moments), max(moments)
        candidates.append((hi / lo, f"that of the links' moments of inertia: {hi:.3g} kg m^2 (link {b}, {high}) is "
                                    f"{hi / lo:.2g} times {lo:.3g} kg m^2 (link {a}, {low})"))
        whole = sum(m for m, _ in masses) * sum(l for l, _ in lengths) ** 2 / 3
        candidates.append((whole / hi, f"the chain's length: its {scene.n} links, straight, have a moment of inertia "
                                       f"about its end (M L^2 / 3 = {whole:.3g} kg m^2) {whole / hi:.2g} times its "
                                       f"largest link's ({hi:.3g} kg m^2)"))
    return "its most extreme ratio is " + max(candidates)[1] if candidates else "extreme mass, length or inertia ratios"


def friction_warnings(model: CompiledModel, p, sim, method: str) -> list[str]:
    """A sentence when the regularised friction limited the steps: at least FRICTION_WARN_STEPS of the run's
    accepted steps, and FRICTION_WARN_SHARE of them, began with a point resting on a rough wall and sliding slower
    than GAC_SLOW_SLIDING friction_velocity (sim.n_slow_sliding), where the friction force is nearly viscous,
    -c_f lambda v_t / friction_velocity: a stiff term of time constant about tau = friction_velocity / (c_f g) that
    caps an explicit step near a few tau.  Steps far shorter than tau are limited by something else, and RK4's
    step is the caller's: neither is named."""
    slow, steps = int(sim.n_slow_sliding), int(sim.n_steps)
    if method == "rk4" or slow < max(FRICTION_WARN_STEPS, FRICTION_WARN_SHARE * steps):
        return []
    v_s = model.scene.friction_velocity
    names = model.scene.parameter_names()
    c_f = max((float(p[k]) for k, name in enumerate(names) if split_parameter_name(name)[0] == "friction"),
             default=0.0)
    h = float(sim.t_slow_sliding) / slow
    tau = v_s / (c_f * abs(float(p[0]))) if c_f * abs(float(p[0])) > 0.0 else None
    if tau is not None and h < 0.01 * tau:
        return []
    scale = f" (time constant about friction_velocity / (c_f g) = {tau:.2g} s)" if tau is not None else ""
    return [f"{slow:,} of the run's {steps:,} steps ({slow / max(steps, 1):.0%}) began with a point resting on a rough "
            f"wall and sliding slower than {model.lib.GAC_SLOW_SLIDING} friction_velocity, at a mean step of "
            f"{h:.2g} s: there the regularised friction is a stiff viscous force{scale} that limits the step. The "
            f"scene's friction_velocity = {v_s:g} m/s: a larger one takes proportionally fewer steps there, at the "
            "price of a slow creep (below friction_velocity) where the chain would stick"]


def _read_impact(model: CompiledModel, r) -> Impact:
    nq = model.nq
    contacts = []
    for k in range(r.ncontact):
        point, wall = model.contacts[r.contact[k]]
        kind = ("stop" if isinstance(wall, JointStop) else "link" if isinstance(wall, LinkPair)
                else "obstacle" if isinstance(wall, ObstacleContact) else "wall")
        contacts.append(Contact(point, wall.name, float(r.impulse[k]), kind,
                                (float(r.impulse_t[2 * k]), float(r.impulse_t[2 * k + 1])),
                                wall.links if kind in ("link", "obstacle") else ()))
    unpack, layout = model.ffi.unpack, model.layout
    return Impact(float(r.t), contacts, float(r.energy_before), float(r.energy_after), bool(r.complementarity),
                  layout.expand(unpack(r.q, nq)), layout.expand(unpack(r.qd_before, nq), velocity=True),
                  layout.expand(unpack(r.qd_after, nq), velocity=True), int(r.rounds), bool(r.plastic),
                  float(r.energy_rest), float(r.roundoff), bool(r.law_elastic), model.impact_law_name(int(r.law)),
                  float(r.residual), model.roundoff_cause_name(int(r.roundoff_cause)))


def _read_contact_events(model: CompiledModel, r) -> list[ContactEvent]:
    events = []
    for kind, count, indices in (("rest", r.nlanded, r.landed), ("release", r.nreleased, r.released),
                                 ("stick", r.nstuck, r.stuck), ("slip", r.nslipped, r.slipped)):
        for k in range(count):
            point, wall = model.contacts[indices[k]]
            events.append(ContactEvent(float(r.t), point, wall.name, kind))
    return events


def _reduce(layout, full, name: str, velocity: bool) -> np.ndarray:
    """A user's full-layout state (Eq. 13) -> the model's coordinates, refusing what the model cannot do."""
    full = np.asarray(full, dtype=float)
    if full.shape != (layout.nq_full,):
        raise ValueError(f"{name}: expected {layout.nq_full} values (the layout of Eq. 13), got shape {full.shape}")
    if not np.all(np.isfinite(full)):
        raise ValueError(f"{name}: must be finite, got {full.tolist()}")
    for index, value in layout.fixed:
        target = 0.0 if velocity else value
        if abs(full[index] - target) > 1e-12 * max(1.0, abs(target)):
            if index in layout.held:
                raise ValueError(f"{name}[{index}]: the scene's base holds it at {target!r} (not a coordinate of the "
                                 f"model), got {float(full[index])!r}")
            raise ValueError(f"{name}[{index}]: this specialised (planar) model holds it at {target!r}, got "
                             f"{full[index]!r}; load the general model (specialise=False) for other states")
    return np.ascontiguousarray(layout.reduce(full))


def sample_times(t_eval, t_end: float) -> np.ndarray:
    """The sample times of a run: ``t_eval`` checked (strictly increasing, within [0, t_end]), or by
    default every 1 ms and t_end."""
    if t_eval is None:
        t_eval = np.unique(np.r_[np.arange(0.0, t_end, 1e-3), t_end])
    t_eval = np.ascontiguousarray(t_eval, dtype=float)
    _check(t_eval.ndim == 1 and np.all(np.diff(t_eval) > 0), "t_eval", "must be a strictly increasing 1-D array")
    _check(len(t_eval) == 0 or (t_eval[0] >= 0 and t_eval[-1] <= t_end), "t_eval",
           f"must lie within [0, t_end] = [0, {t_end}]")
    return t_eval


def _check_parameters(model: CompiledModel, p: np.ndarray) -> None:
    """A parameter vector given to simulate(): the scene's layout, finite, in the ranges a scene file allows,
    and equal to the model's own value wherever the model has that parameter built in as a constant."""
    names = model.scene.parameter_names()
    _check(p.shape == model.p.shape and bool(np.all(np.isfinite(p))), "p",
           f"expected {len(names)} finite values ({', '.join(names)}), got {np.asarray(p).tolist()}")
    if np.array_equal(p, model.p):              # the scene's own values, checked when it was loaded
        return
    try:
        check_vector(parameter_rules(model.scene), p, changed=[names[k] for k in np.flatnonzero(p != model.p)])
    except SceneError as exc:
        raise ValueError(str(exc)) from None
    for k, name in enumerate(names):
        if model.generated.bake_params and p[k] != model.p[k]:
            raise ValueError(f"p[{name}]: this model has every parameter built in as a constant (bake_params=True), "
                             f"so {float(p[k])!r} instead of {float(model.p[k])!r} would be ignored; load the "
                             "model with bake_params=False to change parameters at run time")
        if name in model.layout.held_params and p[k] != model.p[k]:
            raise ValueError(f"p[{name}]: this planar model holds {name} = {float(model.p[k])!r} (the obstacle stays "
                             f"symmetric about the chain's plane), so {float(p[k])!r} is refused; to move it out of "
                             "the plane, load the general model (load_model(scene, specialise=False))")
        if name in model.layout.zero_params and p[k] != 0.0:
            raise ValueError(f"p[{name}]: this model has {name} = 0 built in (the scene's value is 0, so its "
                             f"terms were left out), so {float(p[k])!r} would be ignored; to vary it, load the "
                             f"general model (load_model(scene, specialise=False)) or give {name} a non-zero value "
                             "in the scene")


def _check_inside(model: CompiledModel, q: np.ndarray, p: np.ndarray, name: str) -> None:
    """Refuse a start with a contact point outside its wall (beyond round-off): no impact can fix it."""
    if not model.contacts:
        return
    gaps = model.contact_gaps(q, p)
    points = model.contact_points(q, p)
    for c in np.flatnonzero(gaps < -1e-12 * max(1.0, float(np.abs(points).max()))):
        point, wall = model.contacts[c]
        if isinstance(wall, ObstacleContact):           # the obstacle's geometry (its radius too) is p's
            o = wall.obstacle
            radius = model.scene.capsule_radius(wall.i) + (
                float(p[model.parameter_names.index(f"radius_{o.name}")]) if not o.bounded_by_planes else 0.0)
            if wall.end != 0:                           # a joint point on a plane
                raise ValueError(f"{name}: O_{wall.joint} (an end of link {wall.i}) overlaps the plane {o.name}: it "
                                 f"is {gaps[c] + radius:.6g} m from the plane, less than its radius {radius:g} m "
                                 f"(gap {gaps[c]:.3g} m)")
            raise ValueError(f"{name}: link {wall.i} overlaps the obstacle {o.name}: its segment is "
                             f"{gaps[c] + radius:.6g} m from the obstacle's, less than their radii {radius:g} "
                             f"m together (gap {gaps[c]:.3g} m)")
        if isinstance(wall, LinkPair):
            raise ValueError(f"{name}: links {wall.i} and {wall.j} overlap as capsules: their segments are "
                             f"{gaps[c] + wall.radius:.6g} m apart, less than their radii {wall.radius:g} m together "
                             f"(gap {gaps[c]:.3g} m)")
        if isinstance(wall, JointStop):
            raise ValueError(f"{name}: joint {point} is beyond its {'lower' if wall.side < 0 else 'upper'} limit "
                             f"{wall.parameter} by {-gaps[c]:.3g} rad")
        axis = f"X{wall.axis + 1}"
        position = p[model.scene.parameter_index("wall", wall.name)]
        radius = model.scene.point_radius(point)          # a capsule's end sphere: the gap is less its radius
        bound = position + radius if wall.side < 0 else position - radius
        reach = f", its capsule's radius {radius:g} m included" if radius > 0.0 else ""
        raise ValueError(f"{name}: contact point O_{point} is outside the wall {wall.name}: {axis} = "
                         f"{points[point - 1, wall.axis]:.6g} m, allowed {axis} {'>=' if wall.side < 0 else '<='} "
                         f"{bound:g} (gap {gaps[c]:.3g} m{reach})")


def _step_diagnosis(model: CompiledModel, sim, t_from: float, steps: int) -> str:
    """Where the steps go: their mean size since t_from and the state component that dominated the error
    estimate of the last step (the fastest mode), with its rate."""
    h_mean = (float(sim.t) - t_from) / max(steps, 1)
    nq = model.nq
    names = [model.scene.full_coordinate_names()[i] for i in model.layout.free]
    index = int(sim.err_index)
    x = np.array(model.ffi.unpack(sim.x, 2 * nq))
    what = f"{names[index]}" if index < nq else f"the rate of {names[index - nq]}"
    rate = x[nq + index] if index < nq else None
    detail = f" (d{names[index]}/dt = {rate:.3g})" if rate is not None else ""
    return (f"mean step {h_mean:.3g} s; the step is limited by {what}{detail}, the fastest mode of the chain "
            f"(largest |qd|: {names[int(np.argmax(np.abs(x[nq:])))]} at {np.abs(x[nq:]).max():.3g}); raise "
            "max_steps / max_wall_time or loosen rtol/atol")


def _lost_contact_detail(model: CompiledModel, sim, x) -> str:
    """Which contact the loop found beyond its wall (GAC_ERR_LOST_CONTACT), how deep against the depth allowed, in
    which step, and whether I_f's conditioning can explain it: accelerations from I_f carry a relative error of about
    cond(I_f) eps, so over the step the points stray by about cond(I_f) eps v h (v their fastest speed at the step's
    start x, chart A): I_f is the cause if that reaches a tenth of the depth, else a crossing missed inside the step
    (for RK4: its fixed step too long for the motion)."""
    c = int(sim.lost_contact)
    if not 0 <= c < len(model.contacts):
        return ""
    point, wall = model.contacts[c]
    label = wall.name if isinstance(wall, (JointStop, LinkPair, ObstacleContact)) else f"O{point}/{wall.name}"
    nq, eps = model.nq, float(np.finfo(float).eps)
    p = np.array(model.ffi.unpack(sim.p, len(model.parameters())))
    cond = float(np.linalg.cond(model.mass_matrix(x[:nq], p)))
    t0, t1, gap = float(sim.lost_step[0]), float(sim.lost_step[1]), float(sim.lost_gap)
    travel = float(np.abs(model.contact_velocities(x[:nq], x[nq:], p)).max(initial=0.0)) * (t1 - t0)
    stray = cond * eps * travel
    if stray >= 0.1 * abs(gap):
        cause = f"I_f too ill-conditioned for the tolerance (cond(I_f) eps v h = {stray:.3g} m)"
    else:
        remedy = (f"the fixed step dt = {float(sim.opt.dt):g} s too long for the motion"
                  if int(sim.opt.method) == model.lib.GAC_METHOD_RK4 else
                  "a crossing the event search missed inside the step")
        cause = (f"not I_f's conditioning (cond(I_f) eps v h = {stray:.3g} m, the points' travel v h = "
                 f"{travel:.3g} m): {remedy}")
    return (f" ({label}: gap {gap:.3g} m at t = {float(sim.lost_t):.12g} s, deeper than the "
            f"{float(sim.lost_depth):.3g} m allowed (contact_tol + the simultaneity window), in the step from "
            f"{t0:.12g} s to {t1:.12g} s "
            f"(h = {t1 - t0:.3g} s); cond(I_f) = {cond:.3g} at its start: {cause})")


def _end_message(model: CompiledModel, sim, code: int, segment_t: float, segment_steps: int, n_impacts: int,
                  record=None, x_stop=None) -> str:
    """The result's message for a run the C loop stopped with ``code``: the loop's reason, and for the budgets,
    RK4's stability rule, the energy balance and an impact's accuracy what the run was doing (the loop decided;
    this only reports its numbers; record: the C impact record, for the impact's round-off bound)."""
    lib = model.lib
    max_steps, max_wall_time, dt = int(sim.opt.max_steps), float(sim.opt.max_wall_time), float(sim.opt.dt)
    where = f"at t = {float(sim.t):.12g} s"
    if code == lib.GAC_ERR_MAX_IMPACTS:
        return (f"stopped after {n_impacts} impacts {where}: the max_impacts limit of {int(sim.opt.max_impacts)} "
                "(raise max_impacts to go on)")
    steps = int(sim.n_steps) + int(sim.n_rejected) - segment_steps
    if code == lib.GAC_ERR_MAX_STEPS:
        return (f"{where}: maximum number of steps reached ({int(max_steps)} steps since t = {segment_t:.6g} s, the "
                f"last event): {_step_diagnosis(model, sim, segment_t, steps)}")
    if code == lib.GAC_ERR_WALL_TIME:
        used = f"{where}: wall-time budget of {max_wall_time:g} s used up ({int(sim.n_steps)} steps, {n_impacts} impacts)"
        return f"{used}: {_step_diagnosis(model, sim, segment_t, steps)}" if steps > 0 else used
    if code == lib.GAC_ERR_STOPPED:
        return f"{where}: stopped by the progress callback"
    message = f"{where}: {model.error_message(code)}"
    if code == lib.GAC_ERR_UNSTABLE:
        message += (f" (dt = {dt:g} s: h rho = {float(sim.rk4_h_rho):.3g} in the last step, rho the rate of the "
                    "chain's fastest mode seen in it)")
    if code in (lib.GAC_ERR_DRIFT, lib.GAC_ERR_PROJECTION):
        residual, scale = float(sim.energy_residual), float(sim.energy_scale)
        message += (f" (the balance's residual is {residual:.3g} J, {abs(residual) / scale:.3g} of the scale "
                    f"{scale:.6g} J; projections onto resting contacts changed the energy by "
                    f"{float(sim.energy_projection):.3g} J in all, impacts took {float(sim.loss_impacts):.6g} J)")
    if code == lib.GAC_ERR_IMPACT_ACCURACY and record is not None:
        nq, unpack = model.nq, model.ffi.unpack
        p = np.array(unpack(sim.p, len(model.parameters())))
        cause = accuracy_cause(model, p, np.array(unpack(record.q, nq)),
                               np.array(unpack(record.qd_before, nq)),
                               [int(record.contact[k]) for k in range(int(record.ncontact))],
                               model.impact_law_name(int(record.law)), float(record.residual),
                               model.roundoff_cause_name(int(record.roundoff_cause)))
        refused = REFUSED.get(model.refusal_name(int(record.refusal)))
        message += (f" ({'refused: ' + refused + '; ' if refused else ''}this impact's energy is known only to "
                    f"{float(record.roundoff):.3g} relative, its measured accuracy: {cause})")
    if code == lib.GAC_ERR_LINK_REST:
        q = np.array(model.ffi.unpack(sim.x, model.nq))
        gaps = model.contact_gaps(q, np.array(model.ffi.unpack(sim.p, len(model.parameters()))))
        first = len(model.layout.contacts)
        pair = model.contacts[first + int(np.argmin(gaps[first:]))][1]
        message += (f" (the contact closest at the stop: "
                    f"{f'link {pair.i}' if pair.end == 0 else f'O_{pair.joint}'} on the obstacle {pair.obstacle.name}, "
                    f"{pair.name})" if isinstance(pair, ObstacleContact)
                    else f" (the pair closest at the stop: links {pair.i} and {pair.j}, {pair.name})")
    if code == lib.GAC_ERR_LINK_LINE:
        held = [model.contacts[c][1].name for c in range(len(model.contacts))
                if int(sim.is_resting[c]) and isinstance(model.contacts[c][1], (LinkPair, ObstacleContact))]
        message += f" (held at the stop: {', '.join(held)})"
    if code == lib.GAC_ERR_LOST_CONTACT and x_stop is not None:
        message += _lost_contact_detail(model, sim, x_stop)
    if code == lib.GAC_ERR_NONFINITE and sim.opt.method == lib.GAC_METHOD_RK4:
        message += f" (rk4 with dt = {dt:g} s is unstable on this motion: reduce dt, or use an adaptive method)"
    return message


def _watch(model: CompiledModel, sim, max_wall_time: float, progress):
    """Give the C loop time.perf_counter as its clock (for max_wall_time) and ``progress`` as its progress callback
    (progress(t, n_steps, n_impacts) returning False stops the run).  Returns the handle the loop points at."""
    ffi, c = model.ffi, model.c

    def clock(user):
        return time.perf_counter()

    def report(t, n_steps, n_impacts, user):
        callback = ffi.from_handle(user)
        try:
            return int(callback(float(t), int(n_steps), int(n_impacts)) is False)
        except BaseException:             # noqa: BLE001 - an error in the callback stops the run
            return 1

    c.define_callback("python_clock", clock)
    c.define_callback("python_progress", report)
    if max_wall_time > 0.0:
        c.sim_set_clock(sim, c.python_clock, ffi.NULL)
    if progress is None:
        return None
    handle = ffi.new_handle(progress)
    c.sim_set_progress(sim, c.python_progress, handle)
    return handle
