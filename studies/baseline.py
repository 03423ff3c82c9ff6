"""The outside baseline: scipy's solve_ivp on the same compiled right-hand side, with events and impacts.

    from studies.baseline import scipy_hybrid
    run = scipy_hybrid(model, t_end=1.5, rtol=1e-10, atol=1e-12, method="DOP853")
    run.impacts[0].t, run.impacts[0].contacts, run.x_final, run.n_rhs

Flight: ``solve_ivp`` (any of its methods; Radau gets scipy's own finite-difference Jacobian) on the
compiled ``NAME_rhs`` through cffi.  Events: one terminal scipy event per (point, wall) pair, on the compiled
gap function, falling through zero.  Impacts: every contact within ``contact_tol`` of its wall that
approaches it joins; the compiled Eq. 48 resolves them (its complementarity form when some impulse would
pull), and contacts that still approach after the impact join and the impact is solved again, as the
compiled runtime does.  Nothing here is shared with the compiled integrators or their event location.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.model import CompiledModel


@dataclass
class BaselineImpact:
    t: float
    contacts: frozenset           # {(point 1..n+1, wall name)}
    energy_before: float
    energy_after: float


@dataclass
class BaselineRun:
    """What scipy_hybrid returns; states in the full layout of Eq. 13.  status 0: reached t_end."""

    impacts: list
    t_final: float
    q_final: np.ndarray
    qd_final: np.ndarray
    energy_initial: float
    energy_final: float
    n_rhs: int                    # every call of the compiled rhs, finite-difference Jacobians included
    n_steps: int
    status: int
    message: str

    @property
    def times(self) -> np.ndarray:
        return np.array([impact.t for impact in self.impacts])


def _approaching(model: CompiledModel, q, qd, p, contact_tol: float) -> list:
    gaps = model.contact_gaps(q, p)
    v = model.contact_velocities(q, qd, p)
    return [c for c, (point, wall) in enumerate(model.contacts)
            if gaps[c] <= contact_tol and wall.normal_sign * v[point - 1, wall.axis] < 0]


def _resolve(model: CompiledModel, q, qd, p, contact_set: list, contact_tol: float) -> tuple[np.ndarray, list]:
    """Eq. 48 for the contact set, growing it while some contact at its wall still approaches."""
    contact_set = sorted(contact_set)
    for _ in range(len(model.contacts) + 1):
        qd_plus, impulse = model.impact(q, qd, contact_set, p)
        if np.any(impulse < 0):
            qd_plus, impulse = model.impact(q, qd, contact_set, p, mode="complementarity")
        more = sorted(set(_approaching(model, q, qd_plus, p, contact_tol)) - set(contact_set))
        if not more:
            return qd_plus, contact_set
        contact_set = sorted(set(contact_set) | set(more))
    raise RuntimeError("impact: the contact set did not settle")


def scipy_hybrid(model: CompiledModel, t_end: float, rtol: float, atol: float, method: str = "RK45",
                 contact_tol: float = 1e-6, max_impacts: int = 10000) -> BaselineRun:
    """Simulate the model's scene over [0, t_end] with scipy.integrate.solve_ivp(method=...)."""
    from scipy.integrate import solve_ivp
    nq, p, layout = model.nq, model.p, model.layout
    calls = [0]

    def rhs(t, x):
        calls[0] += 1
        return model.rhs(t, x, p)

    events = []
    for c in range(len(model.contacts)):
        def gap(t, x, c=c):
            return model.contact_gaps(x[:nq], p)[c]
        gap.terminal, gap.direction = True, -1
        events.append(gap)
    t, x = 0.0, np.r_[model.q0, model.qd0]
    energy_initial = sum(model.energy(x[:nq], x[nq:], p))
    impacts, n_steps, status, message = [], 0, 0, "reached t_end"
    while t < t_end:
        solution = solve_ivp(rhs, (t, t_end), x, method=method, rtol=rtol, atol=atol, events=events)
        n_steps += len(solution.t) - 1
        t, x = float(solution.t[-1]), solution.y[:, -1].copy()
        if solution.status == -1:
            status, message = -1, f"at t = {t:.12g} s: solve_ivp failed: {solution.message}"
            break
        if solution.status != 1:
            break
        q, qd = x[:nq], x[nq:]
        contact_set = _approaching(model, q, qd, p, contact_tol)
        if not contact_set:
            # scipy stopped on a crossing of a point that is not approaching: step past it
            t_next = min(t + 1e-9, t_end)
            x = solve_ivp(rhs, (t, t_next), x, method=method, rtol=rtol, atol=atol).y[:, -1]
            t = t_next
            continue
        qd_plus, contact_set = _resolve(model, q, qd, p, contact_set, contact_tol)
        energy_before = sum(model.energy(q, qd, p))
        x[nq:] = qd_plus
        impacts.append(BaselineImpact(t, frozenset((model.contacts[c][0], model.contacts[c][1].name)
                                                   for c in contact_set),
                                      energy_before, sum(model.energy(q, qd_plus, p))))
        if len(impacts) >= max_impacts:
            status, message = -1, f"stopped after {len(impacts)} impacts at t = {t:.12g} s (max_impacts)"
            break
    return BaselineRun(impacts, t, layout.expand(x[:nq]), layout.expand(x[nq:], velocity=True), energy_initial,
                       sum(model.energy(x[:nq], x[nq:], p)), calls[0], n_steps, status, message)
