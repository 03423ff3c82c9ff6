"""The second base chart of a free base, near the gimbal lock of its own (the generator's side; the C library's
runtime/c/gac_chart.c does the same at run time).

The orientation of link 1 is parametrised by three angles (docs/model.md, "Frame convention")::

    ^{ref}R_1 = T_{-1} Rz(theta_-1) T_0 Rz(theta_0) T_1 Rz(theta_1)

and the map from their rates to the angular velocity, omega = E(theta) thetadot with the columns of E
the three joint axes u_{-1}, u_0, u_1 in the reference frame, is singular when the three axes are
coplanar.  With T_0 and T_1 turning each axis a right angle from the previous one (the default twists)
|det E| = |u_{-1} x u_1| = |cos theta_0|: the chart is singular when link 1's joint axis z_1 lies
along the fixed first axis u_{-1} = T_{-1} e_z (X2 for the default twists); I_f contains E through
the link Jacobians, and its smallest eigenvalue falls like det(E)^2.

Chart A is the scene's own parametrisation.  Chart B is the same scene with T_{-1} replaced by
C T_{-1}, C a constant right-angle rotation that turns the first axis u_{-1} into a perpendicular
direction (X1 or X3, whichever is farther from z_1 at the scene's start): T_0, T_1 and every link stay
the same, so link 1's frame, the inner joint angles theta_2..theta_n and the base position X are the
same in both charts and only (theta_-1, theta_0, theta_1) and their rates change.  The generator
derives chart B's kernels beside chart A's (``chart_b_scene``); the C loop switches to B where
chi_A < chart_switch and back where chi_A > 2 chart_switch, so that on B chi_A <= 0.7 and, u_-1 of B
being perpendicular to A's, chi_B >= sqrt(1 - 0.7^2) > 0.71.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .scene import Scene

CHART_NAMES = ("A", "B")
EZ = np.array([0.0, 0.0, 1.0])
RECOMPOSE_TOL = 1e-11     # max |R(angles) - R| accepted from the closed-form extraction
LOCK_TOL = 1e-12          # mu below this: at the chart's lock, theta_-1 is taken from the previous value


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
        At the chart's own singularity (chi < LOCK_TOL) only theta_-1 + theta_1 (or the difference) is
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


BASE_ANGLES = ("theta_-1", "theta_0", "theta_1")


def chart_b_scene(scene: Scene, layout) -> Scene | None:
    """The scene on chart B (T_-1 replaced by C T_-1, its start converted), for a model whose layout keeps the
    three base angles as coordinates; None where the model gets no second chart: a planar model (it never
    reaches the lock), base twists whose T_0 or T_1 does not turn its axis a right angle, or an input on a base
    angle (its generalised force differs between the charts)."""
    if not {0, 1, 2} <= set(layout.free) or any(name in BASE_ANGLES for name in scene.inputs):
        return None
    try:
        chart_a = Chart.of(scene.base_twists)
    except ChartError:
        return None
    q0, qd0 = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float)
    chart_b = Chart.of(chart_b_twists(chart_a, chart_a.rotation(q0[:3])))
    qb, qdb = convert_state(q0, qd0, chart_a, chart_b)
    return dataclasses.replace(scene, base_twists=chart_b.twists, q0=tuple(qb), qd0=tuple(qdb))
