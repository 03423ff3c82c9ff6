"""Forward sensitivities of a hybrid run, as Python names them: the directions (initial-state components and
parameters by name), the seeds the C loop starts from (gac_sens_attach), and what a run returns (the final-state
matrix, the verdict).  The C library carries them along the run (runtime/c/gac_sens.c; docs/simulation.md,
"Sensitivities").

A direction is named
    q0[NAME] / qd0[NAME]   an initial coordinate or velocity, NAME a coordinate of the full layout of Eq. 13
                           ("theta_1", "X2") or its index there ("q0[8]"); only the model's own (free) coordinates
    PARAMETER              a runtime parameter by its name in model.parameter_names ("e_x2_min", "g", "l_1"), an
                           obstacle's position and size among them ("center_x_ball", "radius_bar", "half_y_box",
                           "point_y_floor"); not a box's rotation entry nor a plane's normal entry

One-sided derivatives (simulate(..., one_sided=True)): the C loop carries each direction twice, seeded with +e_j
and -e_j, and at a mode boundary inside an impact each column takes the side its own direction leads to
(gac_sens.one_sided); the right derivative is the first copy, the left one minus the second.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from codegen.scene import OBSTACLE_PARAMETERS, WALL_NAMES, split_parameter_name

# an obstacle's geometry entries that are not directions of their own: a box's rotation stays orthonormal and a
# plane's normal unit, so no single entry can move alone (gac_obstacle_turn_admissible); a plane's normal turns
# instead, about the box axis X1, X2 or X3 through the plane's point: the direction turn_x_<plane> (y, z) seeds
# dn = e_k x n on its normal's entries
HELD_GEOMETRY_KINDS = OBSTACLE_PARAMETERS["box"][6:] + OBSTACLE_PARAMETERS["plane"][3:]
_TURN = re.compile(r"^turn_([xyz])_(.+)$")


# gac.h's GAC_SENS_* status codes, in words
STATUS_WORDS = {
    0: "valid",
    1: "a point sliding at rest with friction (on a wall, a link or an obstacle) with a slip direction over two "
       "tangential axes whose derivative is not known, or slower than friction_velocity at an impact (its friction "
       "there is not differentiated)",
    2: "an impact by a frictional law with a common e, or by Newton + Coulomb",
    3: "an impact at a joint stop",
    4: "an impact with dependent contact rows, or of several rounds that were not reproduced or too many to trace",
    5: "a grazing contact (normal velocity ~ 0 at the wall)",
    6: "a tangential impact (Painleve)",
    7: "a switch to a base chart without tangent kernels (or at its own lock)",
    8: "inputs from a controller (they may depend on the state)",
    9: "the sensitivities overflowed",
    10: "a mode boundary (a contact's impulse ~0 at the law's bound inside an impact, resting contacts released "
        "together, a slip with another slip or a release, or points sticking together at different speeds)",
    11: "a link pair or a link on an obstacle where their closest points or contact frame have no derivative "
        "(crossing or parallel axes, a link parallel to a face)",
    12: "a stick-slip transition on a rough wall (a stuck point left the wall or slipped at an impact, or came to "
        "stick at an impact without taking its impulse)",
}

_STATE = re.compile(r"^(q0|qd0)\[([^\]]+)\]$")


def directions(model, names, p=None) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The directions ``names`` as (names, seed_x (k x nx), seed_p (k x nparam)); a bad name is a ValueError naming
    what is allowed.  p: the run's parameters (a plane's turn is about its normal there; the model's by default)."""
    if isinstance(names, str):
        names = [names]
    names = list(names)
    if not names:
        raise ValueError("sensitivities: give at least one direction (q0[NAME], qd0[NAME] or a parameter name)")
    full = model.scene.full_coordinate_names()
    free = list(model.layout.free)
    nq = model.nq
    seed_x = np.zeros((len(names), 2 * nq))
    seed_p = np.zeros((len(names), len(model.parameter_names)))
    planes = [name[len("normal_x_"):] for name in model.parameter_names if name.startswith("normal_x_")]
    allowed = (", ".join(f"q0[{full[i]}]" for i in free) + ", the same with qd0, or a parameter: "
               + ", ".join(n for n in model.parameter_names if split_parameter_name(n)[0] not in HELD_GEOMETRY_KINDS)
               + "".join(f", turn_x_{plane}, turn_y_{plane}, turn_z_{plane}" for plane in planes))
    for j, name in enumerate(names):
        if not isinstance(name, str):
            raise ValueError(f"sensitivities[{j}]: expected a name, got {name!r}; allowed: {allowed}")
        match = _STATE.match(name.strip())
        if match:
            which, coordinate = match.groups()
            index = int(coordinate) if coordinate.isdigit() else full.index(coordinate) if coordinate in full else -1
            if index not in free:
                raise ValueError(f"sensitivities[{j}] = {name!r}: not a coordinate of this model; allowed: {allowed}")
            seed_x[j, free.index(index) + (nq if which == "qd0" else 0)] = 1.0
        elif name in model.parameter_names:
            if split_parameter_name(name)[0] in HELD_GEOMETRY_KINDS:
                raise ValueError(f"sensitivities[{j}] = {name!r}: a box's rotation entry or a plane's normal entry is "
                                 "not a direction (the rotation stays orthonormal, the normal unit, so no entry moves "
                                 "alone); an obstacle's position and size are (center_*, half_*, a_*, b_*, radius_*, "
                                 "point_*), and a plane's normal turns about the box axes (turn_x_<plane>, "
                                 "turn_y_<plane>, turn_z_<plane>)")
            seed_p[j, model.parameter_names.index(name)] = 1.0
        elif _TURN.match(name.strip()) and plane_normal(model, _TURN.match(name.strip()).group(2), p) is not None:
            axis, plane = _TURN.match(name.strip()).groups()
            names_n, n = plane_normal(model, plane, p)
            dn = np.cross(np.eye(3)["xyz".index(axis)], n)
            for k, entry in enumerate(names_n):
                seed_p[j, model.parameter_names.index(entry)] = dn[k]
        else:
            raise ValueError(f"sensitivities[{j}] = {name!r}: unknown direction; allowed: {allowed}")
    if len(set(names)) != len(names):
        raise ValueError(f"sensitivities: a direction is named twice in {names}")
    return names, seed_x, seed_p


def plane_normal(model, plane: str, p=None):
    """(its normal's parameter names, the normal n in p, the model's by default) of plane obstacle ``plane`` whose
    geometry is among the model's parameters, or None."""
    names = [f"{kind}_{plane}" for kind in OBSTACLE_PARAMETERS["plane"][3:]]
    if not all(name in model.parameter_names for name in names):
        return None
    values = model.p if p is None else np.asarray(p, dtype=float)
    return names, np.array([values[model.parameter_names.index(name)] for name in names], dtype=float)


def state_names(model) -> list[str]:
    """The rows of a sensitivity matrix: q[NAME] then qd[NAME] of the model's own coordinates."""
    full = model.scene.full_coordinate_names()
    coords = [full[i] for i in model.layout.free]
    return [f"q[{c}]" for c in coords] + [f"qd[{c}]" for c in coords]


@dataclass
class Sensitivities:
    """d x(t_final) / d(direction): ``matrix`` (2 nq x k; rows ``rows``, the model's own coordinates q then qd;
    columns ``directions``), NaN when not valid.  ``status`` 'valid', or what ended them (``message``: the event,
    its contact and time; ``t_event``)."""

    rows: list[str]
    directions: list[str]
    matrix: np.ndarray
    status: str = "valid"
    message: str = "every event of the run differentiated"
    t_event: float | None = None
    n_impacts: int = 0                       # impacts differentiated
    code: int = 0                            # GAC_SENS_* of gac.h
    extra: dict = field(default_factory=dict)
    at_samples: np.ndarray | None = None     # simulate(sensitivities_at_samples=True): len(t) x 2 nq x k, NaN from
                                             # the first event not differentiated on (one-sided: the right ones)
    right: np.ndarray | None = None          # one-sided (status 'one-sided'): D+ (2 nq x k), the derivative along +e_j
    left: np.ndarray | None = None           # and D- = -(the derivative along -e_j); None where there was no boundary
    at_samples_left: np.ndarray | None = None   # one-sided, with at_samples: the left ones at the samples

    @property
    def valid(self) -> bool:
        return self.status == "valid"

    @property
    def one_sided(self) -> bool:
        """True where a mode boundary was crossed: ``right`` and ``left`` hold the one-sided derivatives."""
        return self.status == "one-sided"

    def __getitem__(self, key) -> float:
        """sens["q[X2]", "e_x2_min"]: one entry by row and direction name."""
        row, column = key
        if row not in self.rows:
            raise KeyError(f"row {row!r}: one of {', '.join(self.rows)}")
        if column not in self.directions:
            raise KeyError(f"direction {column!r}: one of {', '.join(self.directions)}")
        return float(self.matrix[self.rows.index(row), self.directions.index(column)])

    def column(self, direction: str) -> dict:
        """One direction's column, by row name."""
        return {row: self[row, direction] for row in self.rows}


def contact_label(model, contact: int) -> str:
    if contact < 0:
        return ""
    point, wall = model.contacts[contact]
    return f"O{point}/{wall.name}" if wall.name in WALL_NAMES else wall.name     # a stop, pair, obstacle: its own


def seeds(seed_x: np.ndarray, seed_p: np.ndarray, one_sided: bool) -> tuple[np.ndarray, np.ndarray]:
    """The C loop's seeds: the directions' own, then (one-sided) their negatives."""
    if not one_sided:
        return np.ascontiguousarray(seed_x), np.ascontiguousarray(seed_p)
    return np.ascontiguousarray(np.vstack([seed_x, -seed_x])), np.ascontiguousarray(np.vstack([seed_p, -seed_p]))


AGREE = 1e-9       # one-sided: a column whose right and left derivatives agree to this (relative) is two-sided


def read(model, sim, sens, names: list[str], run_ok: bool, run_message: str, samples=None) -> Sensitivities:
    """The final Sensitivities from the C struct ``sens`` (gac_sens) of the simulation ``sim`` after a run, in chart
    A's coordinates (gac_sens_state, whichever base chart the run ended on); ``samples`` (n x k x nx, the C loop's S
    at each sample) as at_samples (n x nx x k).  With sens.one_sided the loop carried 2k columns (+e_j, then -e_j):
    where it crossed a mode boundary the result is one-sided (right, left; matrix only where they agree), else the
    first k as without."""
    nx, k = 2 * model.nq, len(names)
    one_sided = bool(sens.one_sided)
    total = 2 * k if one_sided else k
    final = np.zeros((total, nx))
    model.lib.gac_sens_state(model.ffi.addressof(sim, "base"), model._ptr(final))
    matrix = final[:k].T.copy()
    code = int(sens.status)
    result = Sensitivities(state_names(model), list(names), matrix, n_impacts=int(sens.n_impacts), code=code,
                           at_samples=None if samples is None else np.transpose(samples[:, :k], (0, 2, 1)).copy())
    if code == 0 and one_sided and int(sens.n_boundaries) > 0:
        right, left = matrix, -final[k:].T
        scale = np.maximum(np.abs(right).max(axis=0), np.abs(left).max(axis=0))
        agree = np.abs(right - left).max(axis=0) <= AGREE * np.maximum(scale, 1e-300)
        result.right, result.left = right.copy(), left.copy()
        result.matrix = np.where(agree, 0.5 * (right + left), np.nan)
        if samples is not None:
            result.at_samples_left = -np.transpose(samples[:, k:], (0, 2, 1))
        where = contact_label(model, int(sens.contact_boundary))
        result.status = "one-sided"
        result.t_event = float(sens.t_boundary)
        result.extra["n_boundaries"] = int(sens.n_boundaries)
        result.message = (f"one-sided from t = {result.t_event:.9g} s on: a mode boundary inside an impact (a "
                          f"contact's impulse ~0 at the law's bound)" + (f" at {where}" if where else "")
                          + f"; right and left derivatives in .right and .left, .matrix only the "
                          f"{int(agree.sum())} of {k} column(s) where they agree (NaN elsewhere)"
                          + ("" if run_ok else f"; the run did not reach t_end ({run_message})"))
        return result
    if code != 0:
        where = contact_label(model, int(sens.contact_status))
        result.status = STATUS_WORDS.get(code, f"status {code}")
        result.t_event = float(sens.t_status)
        result.message = (f"not differentiated from t = {result.t_event:.9g} s on: {result.status}"
                          + (f" at {where}" if where else "") + "; the sensitivities after it are NaN")
        result.matrix[:] = np.nan
    elif not run_ok:
        result.status = "run ended early"
        result.message = f"the run did not reach t_end ({run_message}): the sensitivities are those at t_final"
    return result
