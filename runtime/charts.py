"""Near gimbal lock: integrate on a second chart of the base orientation and switch back.

The orientation of link 1 is parametrised by three angles (docs/model.md, "Frame convention")::

    ^{ref}R_1 = T_{-1} Rz(theta_-1) T_0 Rz(theta_0) T_1 Rz(theta_1)

and the map from their rates to the angular velocity, omega = E(theta) thetadot with the columns of E
the three joint axes u_{-1}, u_0, u_1 in the reference frame, is singular when the three axes are
coplanar.  With T_0 and T_1 turning each axis a right angle from the previous one (the default twists)
|det E| = |u_{-1} x u_1| = |cos theta_0|: the chart is singular when link 1's joint axis z_1 lies
along the fixed first axis u_{-1} = T_{-1} e_z (X2 for the default twists); I_f contains E through
the link Jacobians, and its smallest eigenvalue falls like det(E)^2 (tests/test_charts.py).

Chart A is the scene's own parametrisation.  Chart B is the same scene with T_{-1} replaced by
C T_{-1}, C a constant right-angle rotation that turns the first axis u_{-1} into a perpendicular
direction (X1 or X3, whichever is farther from z_1 at the start): T_0, T_1 and every link stay the
same, so link 1's frame, the inner joint angles theta_2..theta_n and the base position X are the same
in both charts and only (theta_-1, theta_0, theta_1) and their rates change.  Because z_1 cannot lie
within 45 degrees of two perpendicular axes, max(mu_A, mu_B) >= sin 45 deg everywhere.

``simulate_with_charts`` integrates on the current chart in chunks (each one an ordinary
``runtime.simulate`` call from the chunk's state, so the hybrid loop is reused as it is; a restart costs
one initial-step estimate), watches the conditioning measure mu = |det E| (one sine per sample) on a
monitor grid fine enough for the base's rotation rate, and at the first monitor sample where mu falls
below ``threshold`` integrates once more from the chunk's start to that sample (so the next chart
starts from an integrator state, not from the dense output) and continues on the other chart.  It
returns to chart A when mu_A exceeds ``switch_back`` (hysteresis).  Backstops: a chunk first runs with
a step budget (integrating into a lock makes the steps collapse), and if mu was first seen below
``hard_limit``, or the chunk failed with mu below ``threshold``, the stretch is redone from the last
good sample on the other chart.  Samples and impacts are reported in chart A's coordinates (the
scene's layout of Eq. 13); ``chart`` says, per sample, which chart was integrated, ``q_native`` /
``qd_native`` hold those coordinates (chart A's rates grow like 1/mu_A near its own lock).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import Scene, load_scene

from .model import CompiledModel, load_model
from .simulate import (Impact, Impacts, SimulationResult, _check_inside, _check_parameters, energy_scale,
                       impact_warnings, sample_times, simulate)

CHART_NAMES = ("A", "B")
EZ = np.array([0.0, 0.0, 1.0])
RECOMPOSE_TOL = 1e-11     # max |R(angles) - R| accepted from the closed-form extraction
LOCK_TOL = 1e-12          # mu below this: at the chart's lock, theta_-1 is taken from the previous value
MIN_MONITOR_DT = 1e-6     # s: the finest monitor grid (a base turning faster than ~1e5 rad/s is not followed)
MAX_MONITOR_SAMPLES = 2000  # a chunk is shortened so that its monitor grid has at most this many samples


class ChartError(ValueError):
    """The base twists do not admit the closed-form chart conversion, or a conversion failed."""


# ---------------------------------------------------------------------------
# the geometry of one chart
# ---------------------------------------------------------------------------
def _rz(angle):
    """Rz of an angle or an array of angles, shape (..., 3, 3)."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1] = c, -s, s, c
    out[..., 2, 2] = 1.0
    return out


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


@dataclass(frozen=True)
class Chart:
    """The base-orientation chart (T_-1, T_0, T_1): ^{ref}R_1 = T_-1 Rz(a) T_0 Rz(b) T_1 Rz(c)."""

    T_minus1: np.ndarray
    T_0: np.ndarray
    T_1: np.ndarray

    @classmethod
    def of(cls, twists) -> "Chart":
        T = [np.array(t, dtype=float) for t in twists[:3]]
        for name, M in (("T_0", T[1]), ("T_1", T[2])):
            if abs(M[2, 2]) > 1e-12:
                raise ChartError(f"base_twists: chart switching needs {name} to turn the joint axis by a right "
                                 f"angle ({name}[2][2] = 0, as the default twists do), got {name}[2][2] = {M[2, 2]!r}")
        return cls(*T)

    @property
    def twists(self) -> tuple:
        return tuple(tuple(tuple(float(x) for x in row) for row in M) for M in (self.T_minus1, self.T_0, self.T_1))

    @property
    def first_axis(self) -> np.ndarray:
        """u_-1 = T_-1 e_z, fixed in the reference frame: the chart is singular when z_1 lies along it."""
        return self.T_minus1 @ EZ

    @property
    def phi(self) -> float:
        """theta_0 at which z_1 is along +u_-1 is phi, so mu = |sin(theta_0 - phi)| (phi = pi/2 by default)."""
        w, v = self.T_0.T @ EZ, self.T_1 @ EZ
        return math.atan2(w[1] * v[0] - w[0] * v[1], w[0] * v[0] + w[1] * v[1])

    # -- kinematics ------------------------------------------------------------
    def rotation(self, angles) -> np.ndarray:
        """^{ref}R_1 for angles (..., 3) = (theta_-1, theta_0, theta_1); shape (..., 3, 3)."""
        angles = np.asarray(angles, dtype=float)
        R = self.T_minus1 @ _rz(angles[..., 0]) @ self.T_0 @ _rz(angles[..., 1]) @ self.T_1
        return R @ _rz(angles[..., 2])

    def axes(self, angles) -> np.ndarray:
        """E(theta): columns u_-1, u_0, u_1 (reference frame), omega_1 = E thetadot; shape (..., 3, 3)."""
        angles = np.asarray(angles, dtype=float)
        R_m1 = self.T_minus1 @ _rz(angles[..., 0])
        R_0 = R_m1 @ self.T_0 @ _rz(angles[..., 1])
        u1 = np.broadcast_to(self.T_minus1 @ EZ, R_m1.shape[:-1])
        return np.stack([u1, R_m1 @ self.T_0 @ EZ, R_0 @ self.T_1 @ EZ], axis=-1)

    def measure(self, theta_0) -> np.ndarray:
        """mu = |det E| = |sin(theta_0 - phi)| = |u_-1 x z_1|, in [0, 1]; 0 at the chart's gimbal lock."""
        return np.abs(np.sin(np.asarray(theta_0, dtype=float) - self.phi))

    def measure_of(self, R) -> np.ndarray:
        """mu of this chart for orientations R (..., 3, 3) given in any chart."""
        return np.linalg.norm(np.cross(self.first_axis, np.asarray(R)[..., :, 2]), axis=-1)

    # -- inverse kinematics ----------------------------------------------------
    def angles(self, R, near=None) -> np.ndarray:
        """(theta_-1, theta_0, theta_1) with rotation(angles) = R, in closed form.

        Of the two solutions (theta_0 - phi in [-pi, 0] or [0, pi]) and their 2 pi shifts, the one
        closest to ``near`` (sum of the three distances) is returned; without ``near`` the principal one
        (theta_0 - phi in [-pi, 0], |theta_0| <= pi/2 for the default twists) wrapped to (-pi, pi].
        At the chart's own singularity (mu < LOCK_TOL) only theta_-1 + theta_1 (or the difference) is
        defined; theta_-1 is then taken from ``near`` (or 0).  The result is checked by recomposition.
        """
        return self.angles_path(np.asarray(R, dtype=float)[None], near)[0]

    def angles_path(self, R, near=None) -> np.ndarray:
        """angles() of a sequence of orientations R (N, 3, 3), each one continued from the previous
        result (the first from ``near``): shape (N, 3)."""
        R = np.asarray(R, dtype=float)
        t = np.einsum("ji,nj->ni", self.T_minus1, R[:, :, 2])     # z_1 in frame -1 before Rz(theta_-1)
        s, d = np.hypot(t[:, 0], t[:, 1]), t[:, 2]                # |u_-1 x z_1|, u_-1 . z_1
        lock = s <= LOCK_TOL
        v = self.T_1 @ EZ
        branches = []
        for sign in (-1.0, 1.0):                                 # principal branch first
            b = self.phi + np.arctan2(sign * s, d)
            g = np.einsum("ij,njk,k->ni", self.T_0, _rz(b), v)    # z_1 before Rz(theta_-1); |g_xy| = s
            a = np.where(lock, 0.0, np.arctan2(t[:, 1], t[:, 0]) - np.arctan2(g[:, 1], g[:, 0]))
            branches.append(np.stack([a, b, self._third(R, a, b)], axis=-1))
        out = np.empty_like(branches[0])
        if near is None:
            out[0] = [_wrap(x) for x in branches[0][0]]
        candidates = [b.tolist() for b in branches]               # plain floats: a fast sequential pass
        prev = out[0].tolist() if near is None else [float(x) for x in near]
        two_pi = 2.0 * math.pi
        for k in range(0 if near is not None else 1, len(R)):
            best, best_cost = None, math.inf
            for branch in candidates:
                x = branch[k]
                if lock[k]:                                       # theta_-1 from the previous value
                    x = [prev[0], x[1], float(self._third(R[k:k + 1], [prev[0]], [x[1]])[0])]
                x = [v + two_pi * round((p - v) / two_pi) for v, p in zip(x, prev)]
                cost = abs(x[0] - prev[0]) + abs(x[1] - prev[1]) + abs(x[2] - prev[2])
                if cost < best_cost:
                    best, best_cost = x, cost
            out[k] = prev = best
        error = np.abs(self.rotation(out) - R).max(initial=0.0)
        if not error <= RECOMPOSE_TOL:
            raise ChartError(f"chart conversion: recomposed orientation differs by {error:.3g} from the target")
        return out

    def _third(self, R, a, b) -> np.ndarray:
        """theta_1 given theta_-1 = a and theta_0 = b: Rz(theta_1) = (T_-1 Rz(a) T_0 Rz(b) T_1)^T R."""
        P = self.T_minus1 @ _rz(a) @ self.T_0 @ _rz(b) @ self.T_1
        N = np.einsum("nji,njk->nik", P, R)
        return np.arctan2(N[:, 1, 0], N[:, 0, 0])

    def rates(self, angles, omega) -> np.ndarray:
        """thetadot with E(angles) thetadot = omega (reference frame), for one state or a stack.  Within
        LOCK_TOL of the chart's lock E is singular: the least-squares (minimum-norm) rates are returned."""
        angles, omega = np.asarray(angles, dtype=float), np.asarray(omega, dtype=float)
        E = self.axes(angles)
        lock = np.atleast_1d(self.measure(angles[..., 1]) <= LOCK_TOL)
        if not lock.any():
            return np.linalg.solve(E, omega[..., None])[..., 0]
        E, w = E.reshape(-1, 3, 3), omega.reshape(-1, 3)
        out = np.array([np.linalg.lstsq(e, x, rcond=None)[0] if flag else np.linalg.solve(e, x)
                        for e, x, flag in zip(E, w, lock)])
        return out.reshape(omega.shape)


def chart_b_twists(chart_a: Chart, R_start) -> tuple:
    """Chart B: T_-1 turned by a right angle so its first axis is perpendicular to chart A's, choosing
    of the two coordinate-like perpendicular directions the one farther from z_1 at the start."""
    e1 = chart_a.first_axis
    basis = np.eye(3)
    helper = basis[int(np.argmin(np.abs(e1)))]
    p1 = np.cross(e1, helper)
    p1 /= np.linalg.norm(p1)
    p2 = np.cross(e1, p1)
    z1 = np.asarray(R_start)[:, 2]
    target = max((p1, p2), key=lambda p: np.linalg.norm(np.cross(p, z1)))
    k = np.cross(e1, target)                           # rotate e1 onto target: 90 deg about e1 x target
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    C = np.eye(3) + K + K @ K                          # Rodrigues with sin = 1, 1 - cos = 1
    C[np.abs(C) < 1e-14] = 0.0
    C[np.abs(C - 1.0) < 1e-14] = 1.0
    C[np.abs(C + 1.0) < 1e-14] = -1.0
    return (C @ chart_a.T_minus1, chart_a.T_0, chart_a.T_1)


def convert_state(q, qd, source: Chart, target: Chart, near=None) -> tuple[np.ndarray, np.ndarray]:
    """(q, qd) in the full layout of Eq. 13 on chart ``source`` -> the same physical state on ``target``:
    same ^{ref}R_1 and omega_1; theta_2..theta_n, X and their rates are unchanged.  q, qd may be one
    state or a time series (N, nq), converted in order with continuous angles (see Chart.angles_path)."""
    q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
    single = q.ndim == 1
    q, qd = np.atleast_2d(q), np.atleast_2d(qd)
    omega = np.einsum("nij,nj->ni", source.axes(q[:, :3]), qd[:, :3])
    angles = target.angles_path(source.rotation(q[:, :3]), near)
    q[:, :3], qd[:, :3] = angles, target.rates(angles, omega)
    return (q[0], qd[0]) if single else (q, qd)


# ---------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------
@dataclass
class ChartSwitch:
    t: float                  # s
    source: str               # 'A' or 'B'
    target: str
    measure_source: float     # mu of the chart left, at t
    measure_target: float     # mu of the chart entered, at t
    reason: str

    def to_json(self) -> dict:
        return dataclasses.asdict(self)


@dataclass
class ChartResult(SimulationResult):
    """A SimulationResult (status, message, samples, impacts, energies) from simulate_with_charts.

    ``t``, ``q``, ``qd``, the impacts' states and ``q_final``/``qd_final`` are in chart A's coordinates,
    the scene's own layout of Eq. 13, whichever chart was integrated.  Chart A's rates grow like 1/mu_A
    near its own lock (``measure_a``), so physical quantities are best evaluated from the integrated
    coordinates: ``chart`` (0 = A, 1 = B per sample), ``q_native``/``qd_native``; ``contact_points()``,
    ``contact_gaps()`` and ``energies()`` do that.  ``switches`` lists every chart switch in order;
    ``impact_chart`` the chart of each impact."""

    chart: np.ndarray = None
    q_native: np.ndarray = None
    qd_native: np.ndarray = None
    measure_a: np.ndarray = None      # mu_A per sample (1: far from chart A's lock, 0: at it)
    impact_chart: list = field(default_factory=list)
    switches: list = field(default_factory=list)
    chart_twists: tuple = ()          # (T_-1, T_0, T_1) of chart A and of chart B
    chart_b_name: str = ""
    min_measure: float = 1.0          # smallest mu of the integrated chart at any monitor sample
    models: "ChartModels" = field(default=None, repr=False)

    def _per_sample(self, kernel: str, p=None, *velocity) -> np.ndarray:
        out = []
        for k in range(len(self.t)):
            model = self.models.models[self.chart[k]]
            args = [model.layout.reduce(self.q_native[k])]
            if velocity:
                args.append(model.layout.reduce(self.qd_native[k]))
            out.append(getattr(model, kernel)(*args, p))
        return np.array(out)

    def contact_points(self, p=None) -> np.ndarray:
        """O_1..O_{n+1} at every sample, (len(t), n + 1, 3), from the integrated chart's coordinates."""
        return self._per_sample("contact_points", p)

    def contact_gaps(self, p=None) -> np.ndarray:
        """Every (point, wall) gap at every sample, from the integrated chart's coordinates."""
        return self._per_sample("contact_gaps", p)

    def energies(self, p=None) -> np.ndarray:
        """Total energy T + V at every sample, from the integrated chart's coordinates."""
        return self._per_sample("energy", p, True).sum(axis=1)

    def switch_table(self) -> str:
        lines = [f"{'#':>3} {'t (s)':>14}  from -> to  mu(from)  mu(to)  reason"]
        for k, s in enumerate(self.switches, start=1):
            lines.append(f"{k:>3} {s.t:14.9f}  {s.source} -> {s.target}    {s.measure_source:7.4f}  "
                         f"{s.measure_target:6.4f}  {s.reason}")
        return "\n".join(lines)

    def to_json(self) -> dict:
        data = super().to_json()
        data["charts"] = {"switches": [s.to_json() for s in self.switches], "impact_chart": self.impact_chart,
                          "twists": {"A": self.chart_twists[0], "B": self.chart_twists[1]} if self.chart_twists
                          else {}, "min_measure": self.min_measure}
        return data


# ---------------------------------------------------------------------------
# the driver
# ---------------------------------------------------------------------------
class ChartModels:
    """The compiled models of chart A (the scene) and chart B (the scene with C T_-1)."""

    def __init__(self, scene: Scene, progress=None):
        self.scene = scene
        model_a = load_model(scene, progress=progress)
        if model_a.layout.fixed:
            model_a = load_model(scene, progress=progress, specialise=False)
        self.charts = (Chart.of(scene.base_twists), None)
        a = self.charts[0]
        q0, qd0 = np.array(scene.q0), np.array(scene.qd0)
        twists_b = chart_b_twists(a, a.rotation(q0[:3]))
        chart_b = Chart.of(twists_b)
        self.charts = (a, chart_b)
        qb, qdb = convert_state(q0, qd0, a, chart_b)
        name_b = f"{scene.name[:41]}_chartB"
        scene_b = dataclasses.replace(scene, name=name_b, base_twists=chart_b.twists, q0=tuple(qb), qd0=tuple(qdb))
        model_b = load_model(scene_b, progress=progress)
        if model_b.layout.fixed:
            model_b = load_model(scene_b, progress=progress, specialise=False)
        self.models = (model_a, model_b)
        self.name_b = name_b


def _monitor_grid(t0: float, t1: float, monitor_dt: float, user: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local sample times of one chunk [t0, t1]: the monitor grid and the user's samples inside it.
    Returns (local times, index into ``user`` or -1 for a monitor-only sample)."""
    n = max(1, int(math.ceil((t1 - t0) / monitor_dt - 1e-9)))
    monitor = np.linspace(0.0, t1 - t0, n + 1)
    inside = np.flatnonzero((user >= t0) & (user <= t1))
    local_user = user[inside] - t0
    keep = np.ones(len(monitor), dtype=bool)                # drop monitor samples on top of a user sample
    if len(local_user):
        j = np.searchsorted(local_user, monitor)
        below = local_user[np.maximum(j - 1, 0)]
        above = local_user[np.minimum(j, len(local_user) - 1)]
        keep = np.minimum(np.abs(monitor - below), np.abs(monitor - above)) > 1e-12
    times = np.concatenate([monitor[keep], local_user])
    index = np.concatenate([np.full(int(keep.sum()), -1), inside])
    order = np.argsort(times, kind="stable")
    times = np.clip(times[order], 0.0, t1 - t0)
    index = index[order]
    return times, index


def simulate_with_charts(scene: Scene | str, t_end: float, threshold: float = 0.3, switch_back: float = 0.6,
                         hard_limit: float = 0.05, chunk: float = 0.1, monitor_dt: float = 5e-4,
                         chunk_steps: int = 20000, t_eval=None, p=None, q0=None, qd0=None,
                         max_impacts: int = 10000, max_steps: int = 10_000_000, models: ChartModels | None = None,
                         progress=None, **options) -> ChartResult:
    """Simulate like ``runtime.simulate`` while switching the base-orientation chart near the gimbal lock.

    threshold    leave the current chart when its measure mu = |det E| (|cos theta_0| for the default
                 twists) falls below this at a monitor sample
    switch_back  return from chart B to chart A when mu_A exceeds this (> threshold: hysteresis)
    hard_limit   if a monitor sample first sees mu below this (it fell past threshold between samples),
                 the stretch from the previous sample is redone on the other chart
    chunk        s of integration per simulate() call (bounds the work thrown away at a switch)
    monitor_dt   s between monitor samples (the measure is checked there); made finer when the base turns
                 fast, so that mu cannot move by more than (threshold - hard_limit) between two samples
    chunk_steps  a chunk first runs with this step budget: integrating into a lock makes the steps
                 collapse, and the budget ends that quickly (the chunk is then redone from its last
                 good sample on the other chart, or, far from the lock, again with max_steps)
    t_eval, p, q0, qd0, max_impacts, max_steps (per chunk) and ``options`` (method, rtol, atol, dt,
    max_wall_time (for the whole run), ...) as for simulate(); q0/qd0 are in chart A's coordinates (the
    scene's layout).
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    _check(0.0 < hard_limit < threshold < switch_back < math.sqrt(0.5), "threshold",
           "need 0 < hard_limit < threshold < switch_back < sqrt(1/2) (= the worst of the better chart), got "
           f"hard_limit = {hard_limit!r}, threshold = {threshold!r}, switch_back = {switch_back!r}")
    _check(np.isfinite(t_end) and t_end >= 0, "t_end", f"must be a finite time >= 0 s, got {t_end!r}")
    _check(np.isfinite(chunk) and chunk > 0, "chunk", f"must be > 0 s, got {chunk!r}")
    _check(np.isfinite(monitor_dt) and 0 < monitor_dt <= chunk, "monitor_dt",
           f"must be in (0, chunk = {chunk}] s, got {monitor_dt!r}")
    _check(int(chunk_steps) == chunk_steps and chunk_steps >= 1, "chunk_steps",
           f"must be an integer >= 1, got {chunk_steps!r}")
    started = time.perf_counter()                     # the wall-time budget counts compiling chart B too
    models = models or ChartModels(scene, progress=progress)      # compiled for the scene's own start
    charts, compiled = models.charts, models.models
    user = sample_times(t_eval, t_end)
    if isinstance(p, dict):
        p = compiled[0].parameters(p)
    p_vec = compiled[0].p if p is None else np.asarray(p, dtype=float)
    if p is not None:
        _check_parameters(compiled[0], p_vec)
    # The start: the scene's, or q0/qd0 checked like simulate() checks them, against the walls of p (which may
    # move the box: the scene's own walls say nothing about an overridden start)
    q_start = np.array(scene.q0 if q0 is None else _full_state(q0, scene.nq, "q0"), dtype=float)
    qd_start = np.array(scene.qd0 if qd0 is None else _full_state(qd0, scene.nq, "qd0"), dtype=float)
    if p is not None or q0 is not None:
        compiled_a = compiled[0]
        _check_inside(compiled_a, compiled_a.layout.reduce(q_start), p_vec, "q0" if q0 is not None else "initial.q")
    out = _Output(len(user), scene.nq)
    impacts: list[Impact] = []
    impact_chart: list[int] = []
    switches: list[ChartSwitch] = []
    events, persistent, resting = [], [], set()      # contact events, and the contacts resting now
    totals = {"n_steps": 0, "n_rejected": 0, "n_rhs": 0}

    wall_budget = options.pop("max_wall_time", None)  # one wall-time budget for the whole run

    def run_chunk(model, duration, times, q, qd, steps):
        remaining = None if wall_budget is None else max(wall_budget - (time.perf_counter() - started), 1e-3)
        run = simulate(model, duration, t_eval=times, p=p_vec, q0=q, qd0=qd, max_steps=steps,
                       max_impacts=max(1, max_impacts - len(impacts)), charts=False, max_wall_time=remaining,
                       check_start=False,
                       **options)
        for key in totals:
            totals[key] += getattr(run, key)
        return run

    t = 0.0
    q, qd = q_start.copy(), qd_start.copy()
    energy_initial = _energy(compiled[0], q, qd, p_vec)
    T0, V0 = compiled[0].energy(compiled[0].layout.reduce(q), compiled[0].layout.reduce(qd), p_vec)
    current = 0
    out.last_a = q[:3].copy()
    if charts[0].measure(q[1]) < threshold:               # start on B when A is already poor
        q, qd = convert_state(q, qd, charts[0], charts[1])
        switches.append(ChartSwitch(0.0, "A", "B", float(charts[0].measure(q_start[1])),
                                    float(charts[1].measure(q[1])), "start: mu_A < threshold"))
        current = 1
    min_measure = float(charts[current].measure(q[1]))
    speed = float(np.abs(qd[:3]).sum())                   # >= |omega_1| (rad/s): the axes are unit vectors
    status, message = 0, "reached t_end"
    last_redo = None                                      # (t, chart) of the last redo: no ping-pong
    full_budget = False                                   # retry the chunk with max_steps

    while t < t_end:
        if wall_budget is not None and time.perf_counter() - started > wall_budget:
            status, message = -1, (f"at t = {t:.12g} s: wall-time budget of {wall_budget:g} s used up "
                                   f"({totals['n_steps']} steps, {len(switches)} chart switches)")
            break
        chart, model = charts[current], compiled[current]
        spacing = max(min(monitor_dt, 0.5 * (threshold - hard_limit) / max(speed, 1e-300)), MIN_MONITOR_DT)
        t1 = min(t + chunk, t + MAX_MONITOR_SAMPLES * spacing)
        t1 = t_end if t_end - t1 < 1e-12 else t1
        times, index = _monitor_grid(t, t1, spacing, user)
        budget = max_steps if full_budget else min(int(chunk_steps), max_steps)
        run = run_chunk(model, t1 - t, times, q, qd, budget)
        if len(run.t) > 1:
            fastest = float(np.abs(run.qd[:, :3]).sum(axis=1).max())     # >= |omega_1| (unit axes)
            if fastest * np.diff(run.t).max() > threshold - hard_limit and spacing > MIN_MONITOR_DT:
                speed = fastest                           # the base turns too fast for the grid: finer
                continue
            speed = fastest
        mu = chart.measure(run.q[:, 1])
        mu_a = charts[0].measure_of(chart.rotation(run.q[:, :3])) if current == 1 else mu
        impact_times = {imp.t for imp in run.impacts}

        def restartable(k):          # a sample the next chunk may start from
            return (run.t[k] not in impact_times
                    and model.contact_gaps(model.layout.reduce(run.q[k]), p_vec).min(initial=1.0) > 0.0)

        cut, reason, redo = None, "", False
        for k in range(1, len(run.t)):
            if mu[k] < threshold and restartable(k):
                cut, redo = k, bool(mu[k] < hard_limit)
                reason = (f"mu_{CHART_NAMES[current]} < threshold" if not redo else
                          f"mu_{CHART_NAMES[current]} = {mu[k]:.3g} < hard_limit at a monitor sample: redo")
                break
            if current == 1 and mu_a[k] > switch_back and restartable(k):
                cut, reason = k, "back: mu_A > switch_back"
                break
        if cut is None and run.status != 0:
            mu_fail = float(chart.measure(run.q_final[1]))
            if mu_fail < threshold:                       # failed near the singular set: redo on the other chart
                cut, redo = len(run.t), True
                reason = f"failed at mu_{CHART_NAMES[current]} = {mu_fail:.3g}: redo ({run.message})"
            elif run.n_steps >= budget and budget < max_steps:
                full_budget = True                        # a hard stretch far from the lock: full budget
                continue
        full_budget = False
        if redo:                                          # back to the last good sample before the cut
            cut -= 1
            while cut > 0 and not restartable(cut):
                cut -= 1
            if cut < 0 or last_redo == (t + run.t[cut], current):
                status = -1
                message = (f"at t = {t + (run.t[max(cut, 0)] if len(run.t) else 0.0):.12g} s: neither chart "
                           f"can continue ({reason})")
                cut = None
            else:
                last_redo = (t + run.t[cut], 1 - current)
        if cut is not None and cut > 0:
            # integrate once more from the chunk's start to the cut, so that the next chart starts from an
            # integrator state (a step end) rather than from the dense-output interpolant
            again = run_chunk(model, run.t[cut], times[:cut + 1], q, qd, max_steps)
            if again.status == 0 and len(again.t) == cut + 1:
                run = again
                run.q[cut], run.qd[cut] = again.q_final, again.qd_final
        accept = len(run.t) if cut is None else cut
        out.store(run, index, accept, current, charts)
        if accept:
            min_measure = min(min_measure, float(mu[:accept].min()))
        for imp in run.impacts:
            if cut is None or imp.t < run.t[cut]:
                impacts.append(_impact_in_a(imp, t, current, charts, out.last_a))
                impact_chart.append(current)
        for event in getattr(run, "contact_events", ()):      # persistent contact (if the runtime has it)
            key = (event.point, event.wall)
            if cut is not None and event.t >= run.t[cut]:
                continue
            if event.t == 0.0 and event.kind == "persist" and key in resting:
                continue                                  # still resting from before the restart
            events.append(dataclasses.replace(event, t=t + event.t))
            if event.kind == "persist":
                resting.add(key)
            else:
                resting.discard(key)
        persistent = getattr(run, "persistent_final", [])
        if cut is None:
            q, qd = run.q_final.copy(), run.qd_final.copy()
            if status != 0 or run.status != 0:
                if status == 0:
                    status, message = -1, f"chart {CHART_NAMES[current]}: {run.message}"
                t = t + run.t_final
                break
            t = t1
            if len(impacts) >= max_impacts and t < t_end:
                status, message = -1, (f"stopped after {len(impacts)} impacts at t = {t:.12g} s: the "
                                       f"max_impacts limit of {max_impacts} (raise max_impacts to go on)")
                break
            continue
        # continue from sample `cut` on the other chart
        t_cut = user[index[cut]] if index[cut] >= 0 else t + run.t[cut]
        target = 1 - current
        q_new, qd_new = convert_state(run.q[cut], run.qd[cut], chart, charts[target],
                                      near=out.last_a if target == 0 else None)
        switches.append(ChartSwitch(float(t_cut), CHART_NAMES[current], CHART_NAMES[target],
                                    float(mu[cut]), float(charts[target].measure(q_new[1])), reason))
        if progress:
            progress(f"t = {t_cut:.6f} s: chart {CHART_NAMES[current]} -> {CHART_NAMES[target]} ({reason})")
        if target == 0:
            out.last_a = q_new[:3].copy()
        t, q, qd, current = float(t_cut), q_new, qd_new, target

    q_final, qd_final = (q, qd) if current == 0 else convert_state(q, qd, charts[1], charts[0], near=out.last_a)
    n_done = out.count()
    opts = dict(options, threshold=threshold, switch_back=switch_back, hard_limit=hard_limit, chunk=chunk,
                monitor_dt=monitor_dt, chunk_steps=chunk_steps, max_steps=max_steps, t_end=t_end)
    if status == 0:
        message = f"{message}; {len(switches)} chart switch(es)"
    extra = {"contact_events": events, "persistent_final": persistent} \
        if "contact_events" in {f.name for f in dataclasses.fields(SimulationResult)} else {}
    accuracy = impact_warnings(impacts, compiled[0], p_vec)
    warnings = compiled[0].scene.warnings + accuracy
    return ChartResult(
        **extra, t=user[:n_done].copy(), q=out.q[:n_done], qd=out.qd[:n_done], impacts=Impacts.of(impacts),
        t_final=float(t), q_final=q_final, qd_final=qd_final, energy_initial=energy_initial,
        energy_final=_energy(compiled[current], q, qd, p_vec),
        n_steps=totals["n_steps"], n_rejected=totals["n_rejected"], n_rhs=totals["n_rhs"], status=status,
        message=message + (f"; {len(accuracy)} impact(s) of limited accuracy (see warnings)" if accuracy else ""),
        method=options.get("method", "dopri5"), options=opts, warnings=warnings,
        energy_scale=energy_scale(scene, p_vec, T0, V0),
        chart=out.chart[:n_done], q_native=out.q_native[:n_done], qd_native=out.qd_native[:n_done],
        impact_chart=impact_chart, switches=switches, chart_twists=(charts[0].twists, charts[1].twists),
        measure_a=charts[0].measure(out.q[:n_done, 1]), chart_b_name=models.name_b, min_measure=min_measure,
        models=models)


class _Output:
    """The user's samples, filled chunk by chunk; chart-B samples converted to chart A in time order."""

    def __init__(self, n: int, nq: int):
        self.q, self.qd = np.zeros((n, nq)), np.zeros((n, nq))
        self.q_native, self.qd_native = np.zeros((n, nq)), np.zeros((n, nq))
        self.chart = np.full(n, -1)
        self.last_a = np.zeros(3)         # chart-A angles of the latest output (continuity of the conversion)

    def store(self, run, index, accept: int, current: int, charts) -> None:
        """The user samples among the chunk's first ``accept`` samples."""
        ks = np.flatnonzero(index[:accept] >= 0)
        if not len(ks):
            return
        i, q, qd = index[ks], run.q[ks], run.qd[ks]
        self.q_native[i], self.qd_native[i], self.chart[i] = q, qd, current
        if current == 1:
            q, qd = convert_state(q, qd, charts[1], charts[0], near=self.last_a)
        self.q[i], self.qd[i] = q, qd
        self.last_a = q[-1, :3].copy()

    def count(self) -> int:
        """Samples written without a gap from the first."""
        missing = np.flatnonzero(self.chart < 0)
        return int(missing[0]) if len(missing) else len(self.chart)


def _full_state(values, nq: int, name: str) -> np.ndarray:
    """A start q0/qd0 in the full layout of Eq. 13: nq finite numbers."""
    values = np.asarray(values, dtype=float).ravel()
    _check(values.shape == (nq,) and bool(np.all(np.isfinite(values))), name,
           f"expected {nq} finite numbers (the full layout of Eq. 13), got {values.tolist()!r}")
    return values


def _energy(model: CompiledModel, q, qd, p) -> float:
    return float(sum(model.energy(model.layout.reduce(q), model.layout.reduce(qd), p)))


def _check(condition: bool, field_name: str, message: str) -> None:
    if not condition:
        raise ValueError(f"{field_name}: {message}")


def _impact_in_a(imp: Impact, t0: float, current: int, charts, last_a) -> Impact:
    """An impact of a chunk starting at t0, with its states in chart A's coordinates."""
    q, qd_before, qd_after = imp.q, imp.qd_before, imp.qd_after
    if current == 1:
        qa, qd_before = convert_state(q, qd_before, charts[1], charts[0], near=last_a)
        _, qd_after = convert_state(q, qd_after, charts[1], charts[0], near=last_a)
        q = qa
    return dataclasses.replace(imp, t=t0 + imp.t, q=q, qd_before=qd_before, qd_after=qd_after)
