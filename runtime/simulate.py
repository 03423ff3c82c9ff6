"""The hybrid simulation from Python, in the spirit of scipy.integrate.solve_ivp.

    from runtime import simulate
    result = simulate("paper-case1", t_end=1.5)
    for impact in result.impacts:
        print(impact.t, [(c.point, c.wall) for c in impact.contacts])

Flight segments run in compiled code (``NAME_sim_advance``) up to the next impact, which is
located, resolved and applied in C; Python talks to C once per flight segment, checks every
impact (no contact still approaching its wall, no energy gain) and collects the result.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import Scene

from .model import CompiledModel, load_model

METHODS = ("dopri5", "dop853", "rk4")


@dataclass
class Contact:
    """One contact of an impact: point O_point (1-based, as in the paper) on a wall, and its impulse."""

    point: int
    wall: str
    impulse: float        # N s along the wall's inward normal (>= 0: it pushes)


@dataclass
class Impact:
    t: float
    contacts: list[Contact]
    energy_before: float
    energy_after: float
    complementarity: bool               # the complementarity form was needed (some contact would pull)
    q: np.ndarray
    qd_before: np.ndarray
    qd_after: np.ndarray


@dataclass
class ContactEvent:
    """A change of the persistent (resting) contact set: point O_point (1-based) on a wall became
    persistent ('persist') or was released ('release') at time t."""

    t: float
    point: int
    wall: str
    kind: str             # 'persist' | 'release'


@dataclass
class SimulationResult:
    """What simulate() returns.  status 0: reached t_end; -1: stopped early (see message)."""

    t: np.ndarray                 # sample times (s)
    q: np.ndarray                 # (len(t), nq) configuration samples, layout of Eq. 13
    qd: np.ndarray                # (len(t), nq) velocity samples (pre-impact at an impact time)
    impacts: list[Impact]
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
    persistent_final: list = field(default_factory=list)  # (point, wall) of the contacts resting at t_final

    @property
    def success(self) -> bool:
        return self.status == 0

    @property
    def energy_drift(self) -> float:
        """(E_final - E_initial) / |E_initial|."""
        return (self.energy_final - self.energy_initial) / abs(self.energy_initial)

    def impact_table(self) -> str:
        lines = [f"{'#':>3} {'t (s)':>14}  contacts (point/wall: impulse N s)"]
        for k, impact in enumerate(self.impacts, start=1):
            contacts = ", ".join(f"O{c.point}/{c.wall}: {c.impulse:.6g}" for c in impact.contacts)
            lines.append(f"{k:>3} {impact.t:14.9f}  {contacts}")
        return "\n".join(lines)

    def contact_event_table(self) -> str:
        """The resting-contact events, one line each ('' when there are none)."""
        if not self.contact_events:
            return ""
        lines = [f"resting contact: {'t (s)':>14}  point/wall"]
        lines += [f"{e.kind:>15} {e.t:14.9f}  O{e.point}/{e.wall}" for e in self.contact_events]
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {
            "impacts": [{"t": i.t, "contacts": [{"point": c.point, "wall": c.wall, "impulse": c.impulse}
                                                for c in i.contacts],
                         "energy_before": i.energy_before, "energy_after": i.energy_after,
                         "complementarity": i.complementarity} for i in self.impacts],
            "t_final": self.t_final, "q_final": self.q_final.tolist(), "qd_final": self.qd_final.tolist(),
            "energy_initial": self.energy_initial, "energy_final": self.energy_final,
            "n_rhs": self.n_rhs, "n_steps": self.n_steps, "n_rejected": self.n_rejected,
            "status": self.status, "message": self.message, "method": self.method, "options": self.options,
            "contact_events": [{"t": e.t, "point": e.point, "wall": e.wall, "kind": e.kind}
                               for e in self.contact_events],
            "persistent_final": [{"point": point, "wall": wall} for point, wall in self.persistent_final],
        }


def _check(condition: bool, field_name: str, message: str) -> None:
    if not condition:
        raise ValueError(f"{field_name}: {message}")


def simulate(scene: Scene | str | CompiledModel, t_end: float, method: str = "dopri5", rtol: float = 1e-8,
             atol: float = 1e-10, dt: float | None = None, t_eval=None, h_max: float = 0.0,
             contact_tol: float = 1e-6, event_samples: int = 4, event_tol: float = 1e-13,
             max_impacts: int = 10000, max_steps: int = 10_000_000, rest_height: float | None = None,
             zeno_impacts: int = 20, p=None, q0=None, qd0=None) -> SimulationResult:
    """Simulate the scene's hybrid dynamics from its initial state over [0, t_end].

    method        'dopri5' (adaptive Dormand-Prince 5(4), rtol/atol), 'dop853' (adaptive 8(5,3)),
                  or 'rk4' (fixed step dt, as the paper)
    t_eval        sample times (ascending, within [0, t_end]); default: every 1 ms and t_end
    contact_tol   approaching contacts within this gap (m) of their wall join a simultaneous impact
    event_samples interpolant samples per step searched for wall crossings
    max_impacts   stop with status -1 beyond this many impacts (impact accumulation)
    rest_height   m: at an impact on a wall with e < 1, a contact whose bounce would rise less than this
                  (v+^2 <= 2 a rest_height, a its normal acceleration towards the wall) rests on the wall:
                  persistent frictionless contact, released when its force would pull.
                  None (default): 10 contact_tol; 0: never by this rule
    zeno_impacts  a contact becomes persistent after this many impacts at shrinking intervals (0: never)
    p, q0, qd0    override the scene's parameters and initial state (q0, qd0 in the full layout of Eq. 13)
    Samples, final state and impact states are returned in the full layout of Eq. 13 whatever the model.
    """
    model = scene if isinstance(scene, CompiledModel) else load_model(scene)
    ffi, lib, name = model.ffi, model.lib, model.name
    _check(method in METHODS, "method", f"must be one of {METHODS}, got {method!r}")
    _check(np.isfinite(t_end) and t_end >= 0, "t_end", f"must be a finite time >= 0 s, got {t_end!r}")
    if method == "rk4":
        _check(dt is not None and np.isfinite(dt) and dt > 0, "dt", f"rk4 needs a step dt > 0 s, got {dt!r}")
    else:
        _check(np.isfinite(rtol) and rtol > 0, "rtol", f"must be > 0, got {rtol!r}")
        _check(np.isfinite(atol) and atol > 0, "atol", f"must be > 0, got {atol!r}")
        _check(dt is None or (np.isfinite(dt) and dt > 0), "dt", f"first step must be > 0 s, got {dt!r}")
    _check(contact_tol >= 0, "contact_tol", f"must be >= 0 m, got {contact_tol!r}")
    _check(int(event_samples) >= 1, "event_samples", f"must be >= 1, got {event_samples!r}")
    _check(event_tol > 0, "event_tol", f"must be > 0 s, got {event_tol!r}")
    _check(h_max >= 0, "h_max", f"must be >= 0 s (0: unbounded), got {h_max!r}")
    _check(rest_height is None or (np.isfinite(rest_height) and rest_height >= 0), "rest_height",
           f"must be a finite height >= 0 m (or None: 10 contact_tol), got {rest_height!r}")
    _check(int(zeno_impacts) == zeno_impacts and zeno_impacts >= 0, "zeno_impacts",
           f"must be an integer >= 0 (0: off), got {zeno_impacts!r}")

    nq, nx = model.nq, 2 * model.nq
    layout = model.layout
    overridden = p is not None or q0 is not None      # the scene's own values were checked when it was loaded
    p = model.p if p is None else np.ascontiguousarray(p, dtype=float)
    if overridden:
        _check_parameters(model, p)
    q = model.q0 if q0 is None else _reduce(layout, q0, "q0", velocity=False)
    qd = model.qd0 if qd0 is None else _reduce(layout, qd0, "qd0", velocity=True)
    if overridden:
        _check_inside(model, q, p, "q0" if q0 is not None else "initial.q")
    t_eval = sample_times(t_eval, t_end)

    opt = ffi.new(f"{name}_options *")
    getattr(lib, f"{name}_default_options")(opt)
    opt.method = getattr(lib, f"{name.upper()}_METHOD_{method.upper()}")
    opt.dt = dt if dt is not None else 0.0
    opt.rtol, opt.atol, opt.h_max = rtol, atol, h_max
    opt.event_samples, opt.event_tol, opt.contact_tol = int(event_samples), event_tol, contact_tol
    opt.max_steps = int(max_steps)
    opt.rest_height = -1.0 if rest_height is None else float(rest_height)
    opt.zeno_impacts = int(zeno_impacts)
    sim = ffi.new(f"{name}_sim *")
    ptr = model._ptr
    code = getattr(lib, f"{name}_sim_init")(sim, 0.0, ptr(q), ptr(qd), ptr(p), opt)
    if code < 0:
        raise ValueError(f"simulate: {ffi.string(getattr(lib, f'{name}_error_message')(code)).decode()}")

    x_eval = np.zeros((len(t_eval), nx))
    i_eval = ffi.new("int *", 0)
    while i_eval[0] < len(t_eval) and t_eval[i_eval[0]] <= 0.0:      # samples at the start (as sim_init left it)
        x_eval[i_eval[0]] = ffi.unpack(sim.x, nx)
        i_eval[0] += 1
    record = ffi.new(f"{name}_impact_record *")
    advance = getattr(lib, f"{name}_sim_advance")
    SIM_END, SIM_IMPACT = getattr(lib, f"{name.upper()}_SIM_END"), getattr(lib, f"{name.upper()}_SIM_IMPACT")
    SIM_CONTACT = getattr(lib, f"{name.upper()}_SIM_CONTACT")
    contact_events: list[ContactEvent] = []
    t_eval_ptr = ffi.cast("double *", ffi.from_buffer(t_eval))
    x_eval_ptr = ffi.cast("double *", ffi.from_buffer(x_eval))
    energy_initial = sum(model.energy(q, qd, p))
    impacts: list[Impact] = []
    names = model.scene.parameter_names()
    elastic_walls = {w.name for w in model.scene.walls if p[names.index(f"e_{w.name}")] == 1.0}
    # energy scale of lifting the whole chain by its own length: round-off floor of the impact energy checks
    energy_ref = sum(link.mass for link in model.scene.links) * max(abs(p[0]), 1.0) * sum(
        link.length for link in model.scene.links)
    status, message = 0, "reached t_end"
    while True:
        t_call = float(sim.t)
        code = advance(sim, float(t_end), t_eval_ptr, len(t_eval), i_eval, x_eval_ptr, record)
        if code == SIM_END:
            break
        if code in (SIM_IMPACT, SIM_CONTACT):
            contact_events += _read_contact_events(model, record)
        if code == SIM_CONTACT:
            continue
        if code != SIM_IMPACT:
            status = -1
            message = f"at t = {sim.t:.12g} s: {ffi.string(getattr(lib, f'{name}_error_message')(code)).decode()}"
            if code == _header_constant(model, "ERR_MAX_STEPS"):
                message += (f" ({int(max_steps)} steps since t = {t_call:.6g} s, {(sim.t - t_call) / max_steps:.2g} s "
                            "per step: raise max_steps, or loosen rtol/atol if the step size collapsed)")
            break
        impact = _read_impact(model, record)
        impacts.append(impact)
        problem = _impact_problem(model, impact, record, elastic_walls, energy_ref)
        if problem:
            status, message = -1, f"impact at t = {impact.t:.12g} s: {problem}"
            break
        if len(impacts) >= max_impacts:
            status = -1
            message = (f"stopped after {len(impacts)} impacts at t = {impact.t:.12g} s (max_impacts): "
                       "impacts accumulate (Zeno behaviour?)")
            break
    x_final = np.array(ffi.unpack(sim.x, nx))
    n = i_eval[0]
    return SimulationResult(
        t=t_eval[:n].copy(), q=layout.expand(x_eval[:n, :nq]), qd=layout.expand(x_eval[:n, nq:], velocity=True),
        impacts=impacts, t_final=float(sim.t), q_final=layout.expand(x_final[:nq]),
        qd_final=layout.expand(x_final[nq:], velocity=True),
        energy_initial=energy_initial, energy_final=sum(model.energy(x_final[:nq], x_final[nq:], p)),
        n_steps=int(sim.n_steps), n_rejected=int(sim.n_rejected), n_rhs=int(sim.n_rhs), status=status,
        message=message, method=method, contact_events=contact_events,
        persistent_final=[(model.contacts[sim.active[k]][0], model.contacts[sim.active[k]][1].name)
                          for k in range(sim.nactive)],
        options={"rtol": rtol, "atol": atol, "dt": dt, "contact_tol": contact_tol, "event_samples": event_samples,
                 "event_tol": event_tol, "h_max": h_max, "t_end": t_end, "rest_height": rest_height,
                 "zeno_impacts": zeno_impacts})


def _header_constant(model: CompiledModel, suffix: str) -> int | None:
    """An integer #define NAME_<suffix> of the generated header (error codes are not in the cffi cdef)."""
    match = re.search(rf"#define\s+{model.name.upper()}_{suffix}\s+(-?\d+)", model.generated.header)
    return int(match.group(1)) if match else None


def _read_impact(model: CompiledModel, r) -> Impact:
    nq = model.nq
    contacts = []
    for k in range(r.ncontact):
        point, wall = model.contacts[r.contact[k]]
        contacts.append(Contact(point, wall.name, float(r.impulse[k])))
    unpack, layout = model.ffi.unpack, model.layout
    return Impact(float(r.t), contacts, float(r.energy_before), float(r.energy_after), bool(r.complementarity),
                  layout.expand(unpack(r.q, nq)), layout.expand(unpack(r.qd_before, nq), velocity=True),
                  layout.expand(unpack(r.qd_after, nq), velocity=True))


def _read_contact_events(model: CompiledModel, r) -> list[ContactEvent]:
    events = []
    for kind, count, indices in (("persist", r.nactivated, r.activated), ("release", r.nreleased, r.released)):
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
    """A parameter vector given to simulate(): the scene's layout, finite, physical ranges."""
    names = model.scene.parameter_names()
    _check(p.shape == model.p.shape and bool(np.all(np.isfinite(p))), "p",
           f"expected {len(names)} finite values ({', '.join(names)}), got {np.asarray(p).tolist()}")
    for name, value in zip(names, p):
        if name.startswith("e_"):
            _check(0.0 <= value <= 1.0, f"p[{name}]", f"restitution must be in [0, 1], got {float(value)!r}")
        elif name.split("_")[0] in ("l", "mu", "m"):
            _check(value > 0.0, f"p[{name}]", f"must be > 0, got {float(value)!r}")


def _check_inside(model: CompiledModel, q: np.ndarray, p: np.ndarray, name: str) -> None:
    """Refuse a start with a contact point outside its wall (beyond round-off): no impact can fix it."""
    if not model.contacts:
        return
    gaps = model.contact_gaps(q, p)
    points = model.contact_points(q, p)
    for c in np.flatnonzero(gaps < -1e-12 * max(1.0, float(np.abs(points).max()))):
        point, wall = model.contacts[c]
        axis = f"X{wall.axis + 1}"
        position = p[model.scene.parameter_names().index(f"wall_{wall.name}")]
        raise ValueError(f"{name}: contact point O_{point} is outside the wall {wall.name}: {axis} = "
                         f"{points[point - 1, wall.axis]:.6g} m, allowed {axis} {'>=' if wall.side < 0 else '<='} "
                         f"{position:g} (gap {gaps[c]:.3g} m)")


APPROACH_FLOOR = 1e-6   # m/s: below 1e-9 of this (1e-15 m/s) an approach is round-off (a resting contact touched
                        # at zero speed), whatever the impact's own speed


def _impact_problem(model: CompiledModel, impact: Impact, record, elastic_walls: set, energy_ref: float) -> str:
    """The post-impact checks: no contact at its wall still approaching it (measured in C with the
    contact_velocities kernel, independent of the impact solve); no energy gain, and no loss when
    every wall involved has e = 1.  Returns '' when all hold."""
    if record.approach_after > 1e-9 * max(record.approach_before, APPROACH_FLOOR):
        return f"a contact still approaches its wall after the impact ({record.approach_after:.3g} m/s)"
    E0, E1 = impact.energy_before, impact.energy_after
    tol = 1e-10 * max(abs(E0), energy_ref)      # energy_ref: a floor for a chain at rest near V = 0
    if E1 > E0 + tol:
        return f"energy increased from {E0!r} J to {E1!r} J"
    elastic = all(c.wall in elastic_walls for c in impact.contacts) and not record.nactivated
    if elastic and not impact.complementarity and abs(E1 - E0) > tol:
        return f"elastic impact changed the energy from {E0!r} J to {E1!r} J"
    return ""
