"""Scene description: the chain, its parameters, the box and the initial state.

A scene is everything the generator and the runtime need to know about one
simulation set-up.  It is built from dataclasses (validated on construction)
or loaded from a TOML or JSON file with :func:`load_scene`.  Every bad value is
rejected with a :class:`SceneError` that names the field and the allowed range.

State layout (Eq. 13 of the paper), used everywhere in this project::

    q = [theta_-1, theta_0, theta_1, ..., theta_n, X1, X2, X3]      (n + 5)

Units are SI: m, kg, s, rad.
"""
from __future__ import annotations

import json
import math
import re
import sys
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .errors import SceneError
from .urdf import urdf_chain, urdf_mount_frame

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

WALL_NAMES = ("x1_min", "x1_max", "x2_min", "x2_max", "x3_min", "x3_max")
DEFAULT_GRAVITY = 9.81
DEFAULT_GRAVITY_DIRECTION = (0.0, -1.0, 0.0)   # gravity along -X2 (the paper's convention)
GRAVITY_DIRECTION_TOL = 1e-9                   # | |d| - 1 | allowed of a gravity direction
URDF_GRAVITY_DIRECTION = (0.0, 0.0, -1.0)      # a URDF's gravity, along its world's -z (the box frame unturned)
# Table 1 and 2 of the paper: moment of inertia per unit length, kg m.
PAPER_J = (5.89e-5, 2.94e-5, 2.94e-5)
GIMBAL_MARGIN = 1e-6  # |cos(theta_0)| below this is the gimbal lock of the base chart

# Longest chain a scene may have.  Every generated kernel is O(n) code and the build grows about linearly
# (docs/performance.md, "Long chains": n = 256 in about 30 s, n = 1024 in about 4 minutes and 1.1 GB on a
# 2-core machine), so a longer chain is refused up front instead of leaving the user waiting on a build that
# takes far longer than that.
MAX_LINKS = 1024
MAX_LINKS_REASON = (f"at most {MAX_LINKS} links: generating and compiling the model grows faster than n "
                    "(docs/performance.md, 'Long chains')")

# Ranges of the physical numbers: wide enough for ratios of 1e6 and more within one chain, narrow enough
# that the products the kernels form (masses times squared lengths and rates) stay normal doubles.
LENGTH_RANGE = (1e-9, 1e9)        # m
MASS_RANGE = (1e-12, 1e12)        # kg, and kg/m for mu
INERTIA_MAX = 1e100               # |J| (kg m), |I| (kg m^2): 0 or at least the smallest normal double
COORDINATE_MAX = 1e9              # |wall position| (m), |initial state entry|
GRAVITY_MAX = 1e6                 # |gravity| (m/s^2)

# Values a scene may hold but that suggest a slip of units: warnings (Scene.warnings), not errors.
UNITS_LENGTH = (1e-4, 1e2)        # m: a link length outside it suggests mm or km given as m
UNITS_MASS = (1e-6, 1e4)          # kg: a link mass outside it suggests g or t given as kg
UNITS_ANGLE = 2 * math.pi         # rad: an angle beyond it in magnitude suggests degrees given as radians


# ---------------------------------------------------------------------------
# small validators
# ---------------------------------------------------------------------------
def _real(value, fieldname: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SceneError(f"{fieldname}: expected a number, got {value!r}")
    return float(value)


def _number(value, fieldname: str, largest: float = COORDINATE_MAX) -> float:
    """A finite number of magnitude 0 or within [smallest normal double, largest]."""
    value = _real(value, fieldname)
    if not math.isfinite(value):
        raise SceneError(f"{fieldname}: must be a finite number, got {value!r}")
    if abs(value) > largest:
        raise SceneError(f"{fieldname}: must be within [-{largest:g}, {largest:g}], got {value!r}")
    if value != 0.0 and abs(value) < sys.float_info.min:
        raise SceneError(f"{fieldname}: {value!r} is below the smallest normal double "
                         f"({sys.float_info.min:.3g}); give 0 or a larger magnitude")
    return value


def _in_range(value, fieldname: str, bounds: tuple[float, float], unit: str) -> float:
    """A positive number within bounds (a physical length or mass)."""
    value = _real(value, fieldname)
    lo, hi = bounds
    if not lo <= value <= hi:
        raise SceneError(f"{fieldname}: must be in [{lo:g}, {hi:g}] {unit}, got {value!r}")
    return value


def _nonnegative(value, fieldname: str, largest: float = INERTIA_MAX) -> float:
    value = _number(value, fieldname, largest)
    if not value >= 0.0:
        raise SceneError(f"{fieldname}: must be >= 0, got {value!r}")
    return value


def _vector(value, size: int, fieldname: str, largest: float = COORDINATE_MAX) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != size:
        raise SceneError(f"{fieldname}: expected a list of {size} numbers, got {value!r}")
    return tuple(_number(v, f"{fieldname}[{i}]", largest) for i, v in enumerate(value))


def _unit_direction(value, fieldname: str) -> tuple[float, float, float]:
    """A unit 3-vector: three finite numbers whose length is 1 within GRAVITY_DIRECTION_TOL (not normalised here,
    so that the scene file says exactly the direction the model uses; the error gives the normalised vector)."""
    d = _vector(value.tolist() if isinstance(value, np.ndarray) else value, 3, fieldname, largest=1e3)
    length = math.sqrt(sum(x * x for x in d))
    if length == 0.0:
        raise SceneError(f"{fieldname}: must be a unit vector (the direction gravity acts along, box frame), "
                         f"got the zero vector {list(d)!r}")
    if abs(length - 1.0) > GRAVITY_DIRECTION_TOL:
        unit = [round(x / length, 15) for x in d]
        raise SceneError(f"{fieldname}: must be a unit vector (length 1 within {GRAVITY_DIRECTION_TOL:g}; the "
                         f"magnitude is 'gravity'), got {list(d)!r} of length {length!r}; normalised: {unit!r}")
    return tuple(x + 0.0 for x in d)          # -0.0 as 0.0: the same direction hashes the same


def _matrix3(value, fieldname: str, largest: float = COORDINATE_MAX) -> tuple[tuple[float, ...], ...]:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise SceneError(f"{fieldname}: expected a 3x3 matrix (list of 3 rows), got {value!r}")
    return tuple(_vector(row, 3, f"{fieldname}[{i}]", largest) for i, row in enumerate(value))


def _check_keys(table: dict, allowed: tuple[str, ...], where: str) -> None:
    if not isinstance(table, dict):
        raise SceneError(f"{where}: expected a table, got {table!r}")
    for key in table:
        if key not in allowed:
            raise SceneError(f"{where}: unknown key {key!r}; allowed keys: {', '.join(allowed)}")


# ---------------------------------------------------------------------------
# links
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class LineLink:
    """A uniform slender link as in the paper's Tables 1-2.

    length  l > 0 (m); mu > 0 mass per unit length (kg/m);
    J = (Jxx, Jyy, Jzz) >= 0, mass moment of inertia per unit length (kg m),
    in the link frame (x along the link, z along the joint axis).
    """

    length: float
    mu: float
    J: tuple[float, float, float] = PAPER_J
    radius: float = 0.0      # m: the link is a capsule of this radius about O_i -> O_{i+1} (0: a segment)

    def validate(self, where: str) -> None:
        _in_range(self.length, f"{where}.length", LENGTH_RANGE, "m")
        _in_range(self.mu, f"{where}.mu", MASS_RANGE, "kg/m")
        J = _vector(list(self.J), 3, f"{where}.J", INERTIA_MAX)
        for axis, value in zip("xyz", J):
            _nonnegative(value, f"{where}.J ({'J' + axis + axis})")
        _check_radius(self.radius, where)

    kind = "line"
    param_names = ("l", "mu", "Jxx", "Jyy", "Jzz")

    def param_values(self) -> tuple[float, ...]:
        return (self.length, self.mu, *self.J)

    @property
    def mass(self) -> float:
        return self.length * self.mu


@dataclass(frozen=True)
class RigidLink:
    """A general rigid link: mass, centre of mass and inertia tensor about the centre of mass.

    com is given in the link frame (m), inertia (kg m^2) is the 3x3 tensor about
    the centre of mass in the link frame.  The link still spans O_i -> O_i + l x_i.
    """

    length: float
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]
    radius: float = 0.0      # m: the link is a capsule of this radius about O_i -> O_{i+1} (0: a segment)

    kind = "rigid"
    param_names = ("l", "m", "cx", "cy", "cz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")

    def validate(self, where: str) -> None:
        _in_range(self.length, f"{where}.length", LENGTH_RANGE, "m")
        _in_range(self.mass, f"{where}.mass", MASS_RANGE, "kg")
        _check_radius(self.radius, where)
        _vector(list(self.com), 3, f"{where}.com")
        inertia = np.array(_matrix3([list(r) for r in self.inertia], f"{where}.inertia", INERTIA_MAX))
        if not np.allclose(inertia, inertia.T, rtol=0, atol=1e-12 * max(1.0, np.abs(inertia).max())):
            raise SceneError(f"{where}.inertia: must be symmetric")
        for k in range(3):                      # the moments about the axes (a parameter's range: Ixx, Iyy, Izz)
            _nonnegative(inertia[k, k], f"{where}.inertia[{k}][{k}]")
        eig = np.linalg.eigvalsh(inertia)
        tol = 1e-12 * max(1.0, eig.max())
        if eig.min() < -tol:
            raise SceneError(f"{where}.inertia: must be positive semi-definite, eigenvalues {eig.tolist()}")
        a, b, c = eig
        if a + b < c - tol:
            raise SceneError(
                f"{where}.inertia: principal moments {eig.tolist()} violate the triangle inequality "
                "(no real mass distribution has them)")

    def param_values(self) -> tuple[float, ...]:
        I = self.inertia
        return (self.length, self.mass, *self.com, I[0][0], I[1][1], I[2][2], I[0][1], I[0][2], I[1][2])


Link = LineLink | RigidLink


def _check_radius(radius, where: str) -> float:
    """A link's capsule radius: 0 (a segment) or a length in LENGTH_RANGE."""
    radius = _number(radius, f"{where}.radius", LENGTH_RANGE[1])
    if radius != 0.0:
        _in_range(radius, f"{where}.radius", LENGTH_RANGE, "m (or 0: a segment of no thickness)")
    return radius


# ---------------------------------------------------------------------------
# joints and inputs
# ---------------------------------------------------------------------------
STIFFNESS_MAX = 1e12      # N m/rad, and N m s/rad for damping
FRICTION_MAX = 1e3        # Coulomb coefficients of the walls
FRICTION_VELOCITY_RANGE = (1e-9, 1.0)   # m/s: below it sliding friction is regularised (see Scene)


def coordinate_names(n: int) -> list[str]:
    """Names of the full state of Eq. 13: theta_-1, theta_0, theta_1..theta_n, X1, X2, X3."""
    return ["theta_-1", "theta_0"] + [f"theta_{k}" for k in range(1, n + 1)] + ["X1", "X2", "X3"]


@dataclass(frozen=True)
class Joint:
    """Joint k (2..n), between link k-1 and link k, turning about its z axis by theta_k.

    stiffness  K >= 0 (N m/rad) of a linear torsional spring, torque -K (theta_k - rest_angle);
               None: no spring
    rest_angle theta_k at which the spring is relaxed (rad)
    damping    C >= 0 (N m s/rad) of a viscous damper, torque -C theta_dot_k; None: no damper
    Both enter the flight equations as the generalised force of theta_k (Eq. 10-11: dS/dtheta_ddot_k = Q_k);
    the spring's potential 1/2 K (theta_k - rest_angle)^2 is part of the energy.
    """

    stiffness: float | None = None
    rest_angle: float = 0.0
    damping: float | None = None
    lower: float | None = None            # rad: a stop theta_k >= lower (None: none)
    upper: float | None = None            # rad: a stop theta_k <= upper (None: none)
    limit_restitution: float = 0.0        # e of both stops (Newton's law, Eq. 47, on the joint's rate)

    def validate(self, where: str) -> None:
        for key in ("lower", "upper"):
            if getattr(self, key) is not None:
                _number(getattr(self, key), f"{where}.{key}")
        if self.lower is not None and self.upper is not None and not self.lower < self.upper:
            raise SceneError(f"{where}.upper: must be > lower = {self.lower!r} rad, got {self.upper!r}")
        e = _number(self.limit_restitution, f"{where}.limit_restitution")
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"{where}.limit_restitution: must be in [0, 1], got {e!r}")
        if e != 0.0 and self.lower is None and self.upper is None:
            raise SceneError(f"{where}.limit_restitution: given without a lower or upper limit")
        if self.stiffness is not None:
            _nonnegative(self.stiffness, f"{where}.stiffness", STIFFNESS_MAX)
        elif self.rest_angle != 0.0:
            raise SceneError(f"{where}.rest_angle: given without a stiffness; a rest angle belongs to a spring")
        _number(self.rest_angle, f"{where}.rest_angle")
        if self.damping is not None:
            _nonnegative(self.damping, f"{where}.damping", STIFFNESS_MAX)

    @property
    def is_free(self) -> bool:
        """No spring and no damper (stops act at impacts and as constraints, not as forces in flight)."""
        return self.stiffness is None and self.damping is None


@dataclass(frozen=True)
class JointStop:
    """The stop of joint k at its lower or upper limit: a unilateral constraint on theta_k, handled like a
    wall (an event when the gap closes, an impact by Newton's law on the row of the identity, a resting
    constraint), with gap = theta_k - lower or upper - theta_k (rad)."""

    joint: int            # k, 2..n
    side: int             # -1: lower, +1: upper
    position: float       # rad
    restitution: float

    @property
    def name(self) -> str:
        return f"theta_{self.joint}_{'lower' if self.side < 0 else 'upper'}"

    @property
    def normal_sign(self) -> float:
        """+1 for a lower stop (the gap grows with theta_k), -1 for an upper one."""
        return -float(self.side)

    @property
    def parameter(self) -> str:
        return parameter_name("lower" if self.side < 0 else "upper", self.joint)


@dataclass(frozen=True)
class LinkPair:
    """Links i < j as capsules meeting each other: a contact of the loop (an event when their gap closes, an impact
    by Newton's law on their closest points' relative normal velocity (with friction.links' Coulomb coefficient),
    and resting contact once landed), with gap = the
    distance of their segments less radius = r_i + r_j (m)."""

    i: int
    j: int
    radius: float         # m, r_i + r_j
    restitution: float
    friction: float = 0.0  # Coulomb coefficient at their impacts and at rest (friction.links; 0: frictionless)
    end: int = 0          # 0: link i's whole segment; 1, 2: its start O_i or end O_i+1 alone against link j (gac.h)

    @property
    def joint(self) -> int | None:
        """The joint point O_p measured against link j (a pair's end contact), or None for the whole link i."""
        return None if self.end == 0 else self.i + (self.end == 2)

    @property
    def name(self) -> str:
        return f"L{self.i}-L{self.j}" if self.end == 0 else f"O{self.joint}-L{self.j}"

    @property
    def links(self) -> tuple[int, int]:
        return (self.i, self.j)


def pair_ends(pairs: list[LinkPair], radius) -> list[LinkPair]:
    """The end contacts of link pairs: each joint point of a paired link against the other link of the pair, once
    per (point, other link), on the link of larger radius ending at that point among those paired with it (radius(i):
    link i's capsule radius).  Two segments are nearest at an end of one of them, along a stretch whose ends are
    ends (lying parallel), or at a crossing inside both: the pair's own contact measures all of these, but holds one
    point; where it is nearest at an end (or along a stretch reaching one) the end's contact takes its place
    (gac_redundant), so a link that comes down along another rests on two points, a line contact."""
    paired = {(p.i, p.j) for p in pairs} | {(p.j, p.i) for p in pairs}
    first = {(p.i, p.j): p for p in pairs} | {(p.j, p.i): p for p in pairs}
    keys = sorted({(point, b) for a, b in paired for point in (a, a + 1)})
    out = []
    for point, b in keys:
        carriers = [a for a in (point - 1, point) if (a, b) in paired]
        a = max(carriers, key=radius)
        pair = first[(a, b)]
        out.append(LinkPair(a, b, radius(a) + radius(b), pair.restitution, pair.friction, end=2 if a == point - 1 else 1))
    return out


OBSTACLE_KINDS = ("sphere", "capsule", "box", "plane")
OBSTACLE_KEYS = ("name", "kind", "center", "a", "b", "radius", "restitution", "links", "half_extents", "rotation",
                 "point", "normal", "friction")
OBSTACLE_FIELDS = {"sphere": ("center", "radius"), "capsule": ("a", "b", "radius"),
                   "box": ("center", "half_extents", "rotation"), "plane": ("point", "normal")}
OBSTACLE_SHAPE_CODES = {"sphere": 3, "capsule": 0, "box": 1, "plane": 2}   # gac.h GAC_OBSTACLE_*
OBSTACLE_NSHAPE = 16                                                      # gac.h GAC_OBSTACLE_NSHAPE
# An obstacle's geometry as runtime parameters (kind_<name>, after every obstacle's e and friction), per kind in the
# order of its shape row (gac.h obstacle_shapes, after the kind code; a sphere's centre standing for both ends):
_XYZ = ("x", "y", "z")
OBSTACLE_PARAMETERS = {
    "sphere": tuple(f"center_{c}" for c in _XYZ) + ("radius",),
    "capsule": tuple(f"a_{c}" for c in _XYZ) + tuple(f"b_{c}" for c in _XYZ) + ("radius",),
    "box": tuple(f"center_{c}" for c in _XYZ) + tuple(f"half_{c}" for c in _XYZ)
           + tuple(f"rotation_{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)),
    "plane": tuple(f"point_{c}" for c in _XYZ) + tuple(f"normal_{c}" for c in _XYZ),
}
OBSTACLE_GEOMETRY_KINDS = tuple(dict.fromkeys(k for kinds in OBSTACLE_PARAMETERS.values() for k in kinds))
ROTATION_TOL = 1e-9          # a box's rotation: orthonormal with det +1 within it; a plane's normal: unit within it
_OBSTACLE_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,22}[A-Za-z_]$|^[A-Za-z]$")


@dataclass(frozen=True)
class Obstacle:
    """A convex body fixed in the box that links strike: a capsule of ``radius`` (m) about the fixed segment a -> b
    (box frame, m); a sphere is the capsule with a = b (kind 'sphere', centre a).  Kind 'box': an oriented box of
    centre a, ``half_extents`` (m) and ``rotation`` (3x3, its columns the box's axes; None: the identity); kind
    'plane': the half-space n . (x - a) <= 0 below the plane through a of unit ``normal`` n (pointing into the free
    side).  A box or a plane has no radius.  ``restitution``: its e (None: the scene's default); ``links``: the links
    (1-based) that can touch it (None: every link that moves); ``friction``: the Coulomb coefficient c_f of its
    impacts and of its resting contacts (the runtime parameter friction_<name> when > 0; 0: frictionless)."""

    name: str
    kind: str = "sphere"
    a: tuple = (0.0, 0.0, 0.0)
    b: tuple | None = None        # None: a (a sphere, a box, a plane)
    radius: float = 0.0
    restitution: float | None = None
    links: tuple | None = None
    half_extents: tuple | None = None   # a box's
    rotation: tuple | None = None       # a box's (3 rows of 3); None: the identity
    normal: tuple | None = None         # a plane's
    friction: float = 0.0               # Coulomb coefficient at its impacts and at rest (0: frictionless)

    @staticmethod
    def box(name: str, center, half_extents, rotation=None, restitution: float | None = None,
            links=None, friction: float = 0.0) -> "Obstacle":
        rows = None if rotation is None else tuple(tuple(r) for r in np.asarray(rotation, dtype=float).tolist())
        return Obstacle(name, "box", tuple(center), None, 0.0, restitution, links, tuple(half_extents), rows,
                        friction=friction)

    @staticmethod
    def plane(name: str, point, normal, restitution: float | None = None, links=None,
              friction: float = 0.0) -> "Obstacle":
        return Obstacle(name, "plane", tuple(point), None, 0.0, restitution, links, normal=tuple(normal),
                        friction=friction)

    @staticmethod
    def sphere(name: str, center, radius: float, restitution: float | None = None, links=None,
               friction: float = 0.0) -> "Obstacle":
        return Obstacle(name, "sphere", tuple(center), None, radius, restitution, links, friction=friction)

    @staticmethod
    def bar(name: str, a, b, radius: float, restitution: float | None = None, links=None,
            friction: float = 0.0) -> "Obstacle":
        return Obstacle(name, "capsule", tuple(a), tuple(b), radius, restitution, links, friction=friction)

    @property
    def segment(self) -> tuple[tuple, tuple]:
        return self.a, self.a if self.b is None else self.b

    @property
    def bounded_by_planes(self) -> bool:
        """A box or a plane (signed distance, gac_obstacle.c), not a capsule about a segment (gac_link.c)."""
        return self.kind in ("box", "plane")

    @property
    def shape(self) -> tuple[float, ...]:
        """The model's shape row (gac.h obstacle_shapes, OBSTACLE_NSHAPE numbers): kind code, then a sphere's or a
        bar's segment a, b (a sphere: its centre twice) and radius, a box's centre, half extents and rotation
        (row-major) or a plane's point and normal."""
        if self.kind == "box":
            values = [*self.a, *self.half_extents, *(x for row in self.box_rotation for x in row)]
        elif self.kind == "plane":
            values = [*self.a, *self.normal]
        else:
            a, b = self.segment
            values = [*a, *b, self.radius]
        values = [float(OBSTACLE_SHAPE_CODES[self.kind]), *map(float, values)]
        return tuple(values + [0.0] * (OBSTACLE_NSHAPE - len(values)))

    @property
    def geometry_names(self) -> list[str]:
        """The names of its geometry's runtime parameters: 'center_x_ball', ..., 'radius_ball' (OBSTACLE_PARAMETERS)."""
        return [parameter_name(kind, self.name) for kind in OBSTACLE_PARAMETERS[self.kind]]

    @property
    def geometry_values(self) -> list[float]:
        """Its geometry in the order of geometry_names."""
        if self.kind == "sphere":
            return [*map(float, self.a), float(self.radius)]
        if self.kind == "capsule":
            return [*map(float, self.a), *map(float, self.b), float(self.radius)]
        return list(self.shape[1:1 + len(OBSTACLE_PARAMETERS[self.kind])])

    def with_geometry(self, values) -> "Obstacle":
        """The same obstacle (name, kind, e, friction, links) with its geometry from ``values`` (geometry_names' order,
        unchecked: Scene checks it)."""
        v = [float(x) for x in values]
        if self.kind == "sphere":
            return replace(self, a=tuple(v[0:3]), radius=v[3])
        if self.kind == "capsule":
            return replace(self, a=tuple(v[0:3]), b=tuple(v[3:6]), radius=v[6])
        if self.kind == "box":
            return replace(self, a=tuple(v[0:3]), half_extents=tuple(v[3:6]),
                           rotation=(tuple(v[6:9]), tuple(v[9:12]), tuple(v[12:15])))
        return replace(self, a=tuple(v[0:3]), normal=tuple(v[3:6]))

    @property
    def box_rotation(self) -> tuple:
        return ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)) if self.rotation is None else self.rotation

    def distance(self, p0, p1) -> float:
        """The least signed distance (m, negative inside) of segment p0-p1 from the obstacle's surface (numpy; scene
        validation): a capsule's from its segment less its radius; a plane's at an end; a box's by golden section
        over the convex function s -> sd(p0 + s (p1 - p0)) after a scan."""
        p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
        if self.kind == "plane":
            n = np.asarray(self.normal)
            return float(min(n @ (p0 - self.a), n @ (p1 - self.a)))
        if self.kind != "box":
            a, b = self.segment
            return segment_distance(p0, p1, a, b) - self.radius
        f = lambda s: box_signed_distance(self, p0 + s * (p1 - p0))
        grid = np.linspace(0.0, 1.0, 65)
        k = int(np.argmin([f(s) for s in grid]))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, 64)]
        ratio = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(80):
            m1, m2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
            if f(m1) <= f(m2):
                hi = m2
            else:
                lo = m1
        return float(min(f(0.0), f(1.0), f(0.5 * (lo + hi))))

    def checked(self, where: str, default_e: float, n: int, moving: list[int]) -> "Obstacle":
        """The obstacle with every field validated (SceneError naming ``where``.field), restitution and links
        filled in: n links, of which ``moving`` can move (a fixed base welds link 1)."""
        if not isinstance(self.name, str) or not _OBSTACLE_NAME_RE.match(self.name):
            raise SceneError(f"{where}.name: 1..24 letters, digits or _, starting with a letter and not ending with a "
                             f"digit (it names the parameter e_<name> and the contacts L<i>/<name>), got {self.name!r}")
        if self.name in WALL_NAMES or self.name == "limit":
            raise SceneError(f"{where}.name: {self.name!r} is taken (a wall's name, or e_limit of the joint stops); "
                             "give another name")
        where = f"{where} ({self.name})"
        if self.kind not in OBSTACLE_KINDS:
            raise SceneError(f"{where}.kind: one of {', '.join(repr(k) for k in OBSTACLE_KINDS)}, got {self.kind!r}")
        if self.kind in ("box", "plane"):
            return self._checked_planes(where, default_e, n, moving)
        for field in ("half_extents", "rotation", "normal"):
            if getattr(self, field) is not None:
                raise SceneError(f"{where}.{field}: a {self.kind} takes {', '.join(OBSTACLE_FIELDS[self.kind])}; "
                                 f"{field} belongs to a {'plane' if field == 'normal' else 'box'}")
        a = _vector(list(self.a) if isinstance(self.a, (list, tuple)) else self.a, 3,
                    f"{where}.{'center' if self.kind == 'sphere' else 'a'}")
        if self.kind == "sphere":
            if self.b is not None and tuple(self.b) != a:
                raise SceneError(f"{where}.b: a sphere has a centre only; give kind = 'capsule' for a bar a -> b")
            b = a
        else:
            if self.b is None:
                raise SceneError(f"{where}.b: required for a capsule (a bar from a to b, m)")
            b = _vector(list(self.b) if isinstance(self.b, (list, tuple)) else self.b, 3, f"{where}.b")
        radius = _in_range(self.radius, f"{where}.radius", LENGTH_RANGE, "m (an obstacle's radius must be > 0)")
        e, links, friction = self._checked_contacts(where, default_e, n, moving)
        return Obstacle(self.name, self.kind, a, None if self.kind == "sphere" else b, float(radius), e, links,
                        friction=friction)

    def _checked_planes(self, where: str, default_e: float, n: int, moving: list[int]) -> "Obstacle":
        """A box or a plane with every field validated."""
        if self.b is not None:
            raise SceneError(f"{where}.b: a {self.kind} takes {', '.join(OBSTACLE_FIELDS[self.kind])}, not a bar's "
                             "end points")
        if self.radius not in (0, 0.0, None):
            raise SceneError(f"{where}.radius: a {self.kind} has none (its faces are its surface), got "
                             f"{self.radius!r}; a rounded obstacle is a sphere or a capsule")
        a = _vector(list(self.a) if isinstance(self.a, (list, tuple)) else self.a, 3,
                    f"{where}.{'center' if self.kind == 'box' else 'point'}")
        half = rotation = normal = None
        if self.kind == "box":
            if self.normal is not None:
                raise SceneError(f"{where}.normal: a box takes center, half_extents and rotation; normal belongs "
                                 "to a plane")
            if self.half_extents is None:
                raise SceneError(f"{where}.half_extents: required for a box (3 half widths along its axes, m)")
            if not isinstance(self.half_extents, (list, tuple)) or len(self.half_extents) != 3:
                raise SceneError(f"{where}.half_extents: expected a list of 3 numbers (m), got {self.half_extents!r}")
            half = tuple(float(_in_range(h, f"{where}.half_extents[{k}]", LENGTH_RANGE, "m"))
                         for k, h in enumerate(self.half_extents))
            rotation = None if self.rotation is None else _rotation(self.rotation, f"{where}.rotation")
        else:
            for field in ("half_extents", "rotation"):
                if getattr(self, field) is not None:
                    raise SceneError(f"{where}.{field}: a plane takes point and normal; {field} belongs to a box")
            if self.normal is None:
                raise SceneError(f"{where}.normal: required for a plane (its unit normal, into the free side)")
            normal = _vector(list(self.normal) if isinstance(self.normal, (list, tuple)) else self.normal, 3,
                             f"{where}.normal", largest=1e3)
            length = math.sqrt(sum(x * x for x in normal))
            if not abs(length - 1.0) <= ROTATION_TOL:
                hint = ("" if length == 0.0 else
                        "; normalised: [" + ", ".join(f"{x / length:.17g}" for x in normal) + "]")
                raise SceneError(f"{where}.normal: must be a unit vector (length 1 within {ROTATION_TOL:g}), got "
                                 f"{list(normal)!r} of length {length:.17g}{hint}")
        e, links, friction = self._checked_contacts(where, default_e, n, moving)
        return Obstacle(self.name, self.kind, a, None, 0.0, e, links, half, rotation, normal, friction)

    def _checked_contacts(self, where: str, default_e: float, n: int,
                          moving: list[int]) -> tuple[float, tuple, float]:
        """The obstacle's e, the links that can touch it and its friction coefficient, validated."""
        e = default_e if self.restitution is None else self.restitution
        e = _number(e, f"{where}.restitution")
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"{where}.restitution: must be in [0, 1], got {e!r}")
        c_f = _number(self.friction, f"{where}.friction")
        if not 0.0 <= c_f <= FRICTION_MAX:
            raise SceneError(f"{where}.friction: the Coulomb coefficient must be in [0, {FRICTION_MAX:g}], got {c_f!r}")
        if self.links is None:
            links = tuple(moving)
        else:
            if isinstance(self.links, (str, bytes)) or not isinstance(self.links, (list, tuple)) or not self.links:
                raise SceneError(f"{where}.links: expected a non-empty list of link numbers 1..{n}, got {self.links!r}")
            for i in self.links:
                if isinstance(i, bool) or not isinstance(i, int) or not 1 <= i <= n:
                    raise SceneError(f"{where}.links: link numbers must be integers in 1..{n}, got {i!r}")
                if i not in moving:
                    raise SceneError(f"{where}.links: link {i} is welded to the box by the fixed base and never "
                                     f"strikes anything; allowed: {', '.join(str(k) for k in moving)}")
            if len(set(self.links)) != len(self.links):
                raise SceneError(f"{where}.links: a link is named twice in {list(self.links)}")
            links = tuple(sorted(self.links))
        return float(e), links, float(c_f)


def rotation_defects(R) -> tuple[float, float]:
    """How far a 3 x 3 matrix is from a proper rotation: the largest entry of R^T R - I, and det R (each held to
    ROTATION_TOL by the scene's loader and by the runtime parameters' check)."""
    M = np.array(R, dtype=float).reshape(3, 3)
    return float(np.abs(M.T @ M - np.eye(3)).max()), float(np.linalg.det(M))


def _rotation(value, fieldname: str) -> tuple:
    """A box's rotation: 3 rows of 3 numbers, orthonormal with det +1 within ROTATION_TOL."""
    rows = value.tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(rows, (list, tuple)) or len(rows) != 3:
        raise SceneError(f"{fieldname}: expected 3 rows of 3 numbers (a rotation matrix, its columns the box's "
                         f"axes), got {value!r}")
    R = tuple(_vector(list(r) if isinstance(r, (list, tuple)) else r, 3, f"{fieldname}[{k}]", largest=1e3)
              for k, r in enumerate(rows))
    off, det = rotation_defects(R)
    if not off <= ROTATION_TOL:
        raise SceneError(f"{fieldname}: must be orthonormal (R^T R = I within {ROTATION_TOL:g}), got a departure "
                         f"of {off:.3g}")
    if not abs(det - 1.0) <= ROTATION_TOL:
        raise SceneError(f"{fieldname}: must be a proper rotation (det +1 within {ROTATION_TOL:g}), got det "
                         f"{det:.6g} (a reflection: swap two columns)")
    return R


def box_signed_distance(box: "Obstacle", x) -> float:
    """The signed distance (m, negative inside) of point x from a box obstacle's surface: in the box's frame,
    |y - clamp(y)| outside, the nearest face's max_k (|y_k| - h_k) inside."""
    R, h = np.array(box.box_rotation), np.array(box.half_extents)
    y = R.T @ (np.asarray(x, dtype=float) - np.array(box.a))
    d = y - np.clip(y, -h, h)
    dist = float(np.linalg.norm(d))
    return dist if dist > 0.0 else float(np.max(np.abs(y) - h))


@dataclass(frozen=True)
class ObstacleContact:
    """Link i and a fixed obstacle: a contact of the loop like a link pair whose second side never moves (an event
    when their gap closes, an impact with the obstacle's e and friction, at rest held by its normal and, rough, stuck
    or sliding along its contact frame), with gap
    = the distance of the link's segment from the obstacle's less radius = r_i + r_obstacle (m)."""

    i: int
    obstacle: Obstacle
    index: int            # the obstacle's place in Scene.obstacles (0-based): the model's obstacle table
    radius: float         # m, r_i + r_obstacle
    end: int = 0          # 0: the link's whole segment; 1: its start O_i alone; 2: its end O_i+1 alone (gac.h)

    @property
    def joint(self) -> int | None:
        """The joint point O_p the contact is measured from (a plane's contacts), or None for the whole link."""
        return None if self.end == 0 else self.i + (self.end == 2)

    @property
    def name(self) -> str:
        return f"L{self.i}/{self.obstacle.name}" if self.end == 0 else f"O{self.joint}/{self.obstacle.name}"

    def segment(self, points) -> tuple:
        """The part of the chain the gap is measured from, as a segment (its two ends; a joint point twice), from
        the joint points (npoint x 3, O_1 first)."""
        if self.end == 0:
            return points[self.i - 1], points[self.i]
        return points[self.joint - 1], points[self.joint - 1]

    @property
    def links(self) -> tuple[int]:
        return (self.i,)

    @property
    def restitution(self) -> float:
        return float(self.obstacle.restitution)

    @property
    def friction(self) -> float:
        return float(self.obstacle.friction)


def segment_distance(a0, a1, b0, b1) -> float:
    """The distance (m) of segments a0-a1 and b0-b1 (numpy; scene validation): the minimum over the clamped closest
    points of the two lines and of each end point against the other segment."""
    a0, a1, b0, b1 = (np.asarray(v, dtype=float) for v in (a0, a1, b0, b1))

    def to_segment(x, p0, p1):
        d = p1 - p0
        dd = float(d @ d)
        t = 0.0 if dd == 0.0 else min(1.0, max(0.0, float((x - p0) @ d) / dd))
        return float(np.linalg.norm(x - (p0 + t * d)))

    best = min(to_segment(a0, b0, b1), to_segment(a1, b0, b1), to_segment(b0, a0, a1), to_segment(b1, a0, a1))
    u, v, w = a1 - a0, b1 - b0, a0 - b0
    uu, uv, vv, uw, vw = u @ u, u @ v, v @ v, u @ w, v @ w
    denom = uu * vv - uv * uv
    if denom > 1e-14 * uu * vv:               # interior closest points of the two lines, when both lie inside
        s, t = (uv * vw - vv * uw) / denom, (uu * vw - uv * uw) / denom
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
            best = min(best, float(np.linalg.norm(w + s * u - t * v)))
    return best


FREE_JOINT = Joint()


# ---------------------------------------------------------------------------
# walls
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Wall:
    """A plane wall X_axis = position.  side = -1 for a lower wall (x?_min), +1 for an upper one."""

    name: str
    position: float
    restitution: float = 1.0
    points: tuple[int, ...] = ()  # contact points O_i (1-based) that may touch it
    friction: float = 0.0         # Coulomb (friction) coefficient c_f >= 0 of a point resting on it (0: frictionless)

    @property
    def axis(self) -> int:
        """0, 1 or 2 for X1, X2, X3."""
        return int(self.name[1]) - 1

    @property
    def side(self) -> int:
        return -1 if self.name.endswith("_min") else +1

    @property
    def normal_sign(self) -> float:
        """Sign of the inward normal along the axis: +1 for a lower wall, -1 for an upper one."""
        return -float(self.side)


# ---------------------------------------------------------------------------
# twists
# ---------------------------------------------------------------------------
def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# The frame convention (docs/model.md, "Frame convention"): ^{ref}R_{-1} = T_{-1} Rz(theta_-1),
# ^{k-1}R_k = T_k Rz(theta_k).  These three are fixed; T_k = I for k >= 2 unless the scene says otherwise.
T_MINUS1 = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, -1.0, 0.0))   # Rx(-90 deg)
T_0 = ((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0))        # Rx(+90 deg)
T_1 = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
SNAP = 1e-14  # twist entries within this of 0 or +-1 are taken as exactly 0 or +-1


def _clean_rotation(matrix, fieldname: str) -> tuple[tuple[float, ...], ...]:
    """Validate a rotation matrix and snap round-off (|x| < 1e-14, |x -+ 1| < 1e-14) to exact values."""
    R = np.array(_matrix3([list(r) for r in matrix], fieldname), dtype=float)
    if not np.allclose(R @ R.T, np.eye(3), rtol=0, atol=1e-9) or np.linalg.det(R) < 0:
        raise SceneError(f"{fieldname}: must be a proper rotation matrix (orthonormal, det = +1)")
    for target in (0.0, 1.0, -1.0):
        R[np.abs(R - target) < SNAP] = target
    return tuple(tuple(float(x) for x in row) for row in R)


def twist_about_x(angle: float) -> tuple[tuple[float, ...], ...]:
    """T_k = Rx(angle): the joint axis of link k tilted about the axis of link k-1 (a DH-like twist)."""
    return _clean_rotation(rot_x(angle).tolist(), "twist")


# ---------------------------------------------------------------------------
# the base: how link 1 is held
# ---------------------------------------------------------------------------
BASE_KINDS = ("free", "pinned", "fixed")
BASE_JOINTS = ("spherical", "revolute")
BASE_ANGLE_SNAP = 1e-12   # a base angle within this of a multiple of pi/2 is taken as exactly that multiple


def _snap_quarter(angle: float) -> float:
    quarter = round(angle / (math.pi / 2))
    return quarter * math.pi / 2 if abs(angle - quarter * math.pi / 2) < BASE_ANGLE_SNAP else angle


def axis_angles(axis) -> tuple[float, float]:
    """(theta_-1, theta_0) that turn link 1's joint axis z_1 along the unit vector ``axis`` (box frame), with the
    default base twists: ^{ref}R_1 = Ry(theta_-1) Rz(theta_0) Rx(theta_1) T_1, so z_1 = Ry(theta_-1) Rz(theta_0) e_x
    = (cos theta_-1 cos theta_0, sin theta_0, -sin theta_-1 cos theta_0).  Along X2 (theta_0 = +-pi/2) theta_-1 is 0."""
    d = np.asarray(axis, dtype=float)
    theta0 = math.atan2(d[1], math.hypot(d[0], d[2]))
    theta_m1 = math.atan2(-d[2], d[0]) if math.hypot(d[0], d[2]) > 1e-15 else 0.0
    return _snap_quarter(theta_m1), _snap_quarter(theta0)


def urdf_mount_offset(text: str, tip_length: float | None = None) -> float:
    """theta_1 minus the URDF angle of the revolute or continuous joint that holds a URDF chain's root to ``world``
    (rad, in (-pi, pi]; a constant): the model's theta_1 counts from the base chart's zero direction about the axis
    (axis_angles), the URDF angle from the root's frame at the joint's origin (codegen.urdf.urdf_mount_frame).  0 for
    any other base."""
    frame = urdf_mount_frame(text, tip_length)
    if frame is None:
        return 0.0
    theta_m1, theta0 = axis_angles(frame[:, 2])
    chart = np.array(T_MINUS1) @ rot_z(theta_m1) @ np.array(T_0) @ rot_z(theta0) @ np.array(T_1)   # at theta_1 = 0
    R = chart.T @ frame                                                                          # = Rz(offset)
    return math.atan2(R[1, 0], R[0, 0])


def rotation_angles(R) -> tuple[float, float, float]:
    """(theta_-1, theta_0, theta_1) of link 1's orientation ^{ref}R_1 (columns x_1, y_1, z_1 in the box frame), with
    the default base twists: R T_1^T = Ry(theta_-1) Rz(theta_0) Rx(theta_1) (at theta_0 = +-pi/2, theta_-1 = 0)."""
    M = np.asarray(R, dtype=float) @ np.array(T_1).T
    theta_m1, theta0 = axis_angles(M[:, 0])
    c, s = math.cos(theta_m1), math.sin(theta_m1)
    Ry = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    N = rot_z(theta0).T @ Ry.T @ M                      # = Rx(theta_1)
    return theta_m1, theta0, _snap_quarter(math.atan2(N[2, 1], N[1, 1]))


@dataclass(frozen=True)
class Base:
    """How link 1 (the base) is held; docs/scenes.md, "The base".

    kind      "free": floats (the default; all of theta_-1, theta_0, theta_1, X1, X2, X3 are coordinates);
              "pinned": O_1 held at ``point``, link 1 turning about it through a ``joint``: "spherical" (the three
              angles stay coordinates) or "revolute" about ``axis`` (theta_1 alone stays a coordinate);
              "fixed": link 1 welded to the box at ``point`` with orientation ``angles`` (theta_-1, theta_0,
              theta_1) or ``rotation`` (^{ref}R_1: columns x_1, y_1, z_1 in the box frame)
    The coordinates a base holds are no coordinates of the model (codegen.specialise.Layout.fixed), with zero
    velocity: the pivot does no work.
    """

    kind: str = "free"
    joint: str | None = None
    point: tuple | None = None
    axis: tuple | None = None
    angles: tuple | None = None
    rotation: tuple | None = None

    @property
    def label(self) -> str:
        return f"pinned ({self.joint})" if self.kind == "pinned" else self.kind

    def checked(self) -> "Base":
        """The base validated and normalised (axis of unit length, a fixed base's orientation as angles)."""
        if not isinstance(self.kind, str) or self.kind not in BASE_KINDS:
            raise SceneError(f"base.kind: must be one of {', '.join(repr(k) for k in BASE_KINDS)}, got {self.kind!r}")
        given = {key for key in ("joint", "point", "axis", "angles", "rotation") if getattr(self, key) is not None}
        allowed = {"free": set(), "pinned": {"joint", "point", "axis"}, "fixed": {"point", "angles", "rotation"}}
        for key in sorted(given - allowed[self.kind]):
            raise SceneError(f"base.{key}: not a field of a {self.kind} base (kind = {self.kind!r}); "
                             + (f"a {self.kind} base has {', '.join(sorted(allowed[self.kind]))}"
                                if allowed[self.kind] else "a free base has no other field"))
        if self.kind == "free":
            return Base()
        if self.point is None:
            raise SceneError(f"base.point: required for a {self.kind} base (where O_1 is held, m, box frame)")
        point = _vector(list(self.point) if isinstance(self.point, (list, tuple)) else self.point, 3, "base.point")
        if self.kind == "pinned":
            joint = "spherical" if self.joint is None else self.joint
            if not isinstance(joint, str) or joint not in BASE_JOINTS:
                raise SceneError(f"base.joint: must be one of {', '.join(repr(j) for j in BASE_JOINTS)}, got {joint!r}")
            if joint == "spherical":
                if self.axis is not None:
                    raise SceneError("base.axis: only for joint = 'revolute' (a spherical pin turns about any axis)")
                return Base("pinned", "spherical", point)
            if self.axis is None:
                raise SceneError("base.axis: required for joint = 'revolute' (the direction of the joint axis, box "
                                 "frame)")
            axis = np.array(_vector(list(self.axis) if isinstance(self.axis, (list, tuple)) else self.axis, 3,
                                    "base.axis"))
            norm = float(np.linalg.norm(axis))
            if not norm > 1e-12:
                raise SceneError(f"base.axis: must be a non-zero direction, got {list(self.axis)!r}")
            axis = axis / norm
            axis[np.abs(axis) < SNAP] = 0.0
            axis[np.abs(axis - 1.0) < SNAP] = 1.0
            axis[np.abs(axis + 1.0) < SNAP] = -1.0
            return Base("pinned", "revolute", point, tuple(float(v) for v in axis))
        if (self.angles is None) == (self.rotation is None):
            raise SceneError("base.angles: a fixed base needs its orientation: give angles = [theta_-1, theta_0, "
                             "theta_1] (rad) or rotation = ^{ref}R_1 (3x3, columns x_1, y_1, z_1), one of them")
        if self.angles is not None:
            angles = _vector(list(self.angles) if isinstance(self.angles, (list, tuple)) else self.angles, 3,
                             "base.angles")
            angles = tuple(_snap_quarter(a) for a in angles)
        else:
            angles = rotation_angles(_clean_rotation(self.rotation, "base.rotation"))
        return Base("fixed", None, point, None, angles)

    def held(self, n: int) -> dict[int, float]:
        """The coordinates (full-layout index of Eq. 13) the base holds, and their values."""
        if self.kind == "free":
            return {}
        out = {n + 2 + a: float(x) for a, x in enumerate(self.point)}
        if self.kind == "pinned" and self.joint == "revolute":
            out.update(enumerate(axis_angles(self.axis)))
        elif self.kind == "fixed":
            out.update(enumerate(self.angles))
        return dict(sorted(out.items()))

    def held_points(self) -> tuple[int, ...]:
        """The points O_i the base holds in place (they never touch a wall): O_1 of a pinned base, O_1 and O_2 of a
        fixed one."""
        return {"free": (), "pinned": (1,), "fixed": (1, 2)}[self.kind]

    def source(self, index: int, n: int) -> str:
        """The field of the base that gives held coordinate ``index``."""
        return "base.point" if index >= n + 2 else ("base.axis" if self.kind == "pinned" else "base.angles")


FREE_BASE = Base()


# ---------------------------------------------------------------------------
# parameter names: composed by parameter_name only, read back by split_parameter_name
# ---------------------------------------------------------------------------
WALL_KINDS = ("wall", "e", "friction")      # a wall's parameters, named by the wall: 'e_x2_min'


def parameter_name(kind: str, owner: int | str | None = None) -> str:
    """The name of one runtime parameter: its kind ('l', 'mu', 'Ixx', 'wall', 'e', 'friction', 'stiffness',
    'rest_angle', 'damping', 'lower', 'upper', 'e_limit', an obstacle's geometry: OBSTACLE_PARAMETERS) and its owner,
    a link or joint number or a wall's or obstacle's name: 'l_3', 'wall_x1_max', 'friction_x2_min', 'e_limit_2',
    'stiffness_2', 'center_x_ball', 'rotation_12_crate'; 'g' has no owner."""
    return kind if owner is None else f"{kind}_{owner}"


def split_parameter_name(name: str) -> tuple[str, int | str | None]:
    """(kind, owner) of a parameter's name, the inverse of parameter_name: 'e_limit_3' -> ('e_limit', 3),
    'e_x2_min' -> ('e', 'x2_min'), 'Jxx_2' -> ('Jxx', 2), 'g' -> ('g', None)."""
    name = name.partition(".")[2] or name           # a chain's prefix ('c2.l_1', Chains) dropped
    if name[-1].isdigit():
        kind, owner = name.rsplit("_", 1)
        return kind, int(owner)
    for kind in WALL_KINDS + OBSTACLE_GEOMETRY_KINDS:     # a wall's, an obstacle's ('radius_ball')
        if name.startswith(kind + "_"):
            return kind, name[len(kind) + 1:]
    return name, None


# ---------------------------------------------------------------------------
# the scene
# ---------------------------------------------------------------------------
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,47}$")


def is_c_identifier(name) -> bool:
    """Whether ``name`` can prefix generated C symbols (1..48 characters)."""
    return isinstance(name, str) and bool(_NAME_RE.match(name))


@dataclass(frozen=True)
class Scene:
    """One simulation set-up.  Construction validates every field.

    links      real links 1..n (LineLink or RigidLink), n >= 1
    twists     T_k for k = 2..n (n - 1 rotation matrices); () means all identity
    gravity    g (m/s^2), the magnitude of gravity (the runtime parameter 'g')
    gravity_direction  d, the unit vector gravity acts along, in the box frame (default (0, -1, 0): -X2, the paper's
               convention; the reference frame accelerates at -g d).  A tilted d makes the box's floor an incline
    walls      the walls of the box that exist; an absent wall means no wall
    q0, qd0    initial state, layout [theta_-1, theta_0, theta_1..theta_n, X1, X2, X3]
    joints     springs and dampers of the joints 2..n (Joint; n - 1 entries, or () for none)
    inputs     the actuated coordinates by name ("theta_2", "X2", ...): input u_i is the generalised force
               of inputs[i] (N m on an angle, N on a translation), added to the flight equations
    base       how link 1 is held (Base): floating (the default), pinned at a point or fixed; q0 and qd0 always
               hold the full layout, with the held coordinates at the base's values (zero rates)
    friction_velocity  v_s (m/s): a point resting on a wall with friction coefficient c_f slides against the Coulomb force
               -c_f lambda v_t / max(|v_t|, v_s) (lambda its normal force, v_t its tangential velocity): exact
               Coulomb sliding above v_s, a stiff viscous regime below it in place of sticking
    """

    name: str
    links: tuple[Link, ...]
    walls: tuple[Wall, ...] = ()
    twists: tuple = ()
    gravity: float = DEFAULT_GRAVITY
    q0: tuple[float, ...] = ()
    qd0: tuple[float, ...] = ()
    base_twists: tuple = (T_MINUS1, T_0, T_1)  # T_-1, T_0, T_1: the base chart
    description: str = ""
    joints: tuple = ()          # Joint of joints 2..n (n - 1 entries); () means no springs or dampers
    inputs: tuple = ()          # names of the actuated coordinates (coordinate_names), one input u_i each
    friction_velocity: float = 1e-3   # m/s, see above
    base: Base = FREE_BASE      # how link 1 is held (Base): free, pinned or fixed
    link_restitution: float | None = None   # e of two capsule links meeting (Scene.link_pairs); None: 1
    link_friction: float = 0.0  # Coulomb coefficient of two capsule links meeting (friction.links; 0: frictionless)
    contact_pairs: tuple | None = None      # the link pairs (i, j) that may strike each other ([contacts] links);
    #                                         None: every pair that can (Scene.link_pairs)
    obstacles: tuple = ()       # Obstacle: convex bodies fixed in the box that the links strike ([[obstacles]])
    obstacle_restitution: float = 1.0   # e of an obstacle that gives none (the scene's restitution default)
    gravity_direction: tuple = DEFAULT_GRAVITY_DIRECTION   # d: gravity acts along it, unit vector, box frame

    def __post_init__(self):
        if not isinstance(self.name, str) or not _NAME_RE.match(self.name):
            raise SceneError(f"name: must be a C identifier of 1..48 characters "
                             f"(letters, digits, _; not starting with a digit), got {self.name!r}")
        links = tuple(self.links)
        if len(links) < 1:
            raise SceneError("links: a chain needs n >= 1 real links, got n = 0")
        if len(links) > MAX_LINKS:
            raise SceneError(f"links: {MAX_LINKS_REASON}; got n = {len(links)}")
        for i, link in enumerate(links, start=1):
            if not isinstance(link, (LineLink, RigidLink)):
                raise SceneError(f"links[{i}]: expected a LineLink or RigidLink, got {link!r}")
            link.validate(f"links[{i}]")
        object.__setattr__(self, "links", links)
        n = len(links)
        twists = tuple(self.twists) if self.twists else (IDENTITY,) * (n - 1)
        if len(twists) != n - 1:
            raise SceneError(f"twists: expected n - 1 = {n - 1} matrices (T_2..T_n), got {len(twists)}")
        twists = tuple(_clean_rotation(T, f"links[{k}].twist") for k, T in enumerate(twists, start=2))
        object.__setattr__(self, "twists", twists)
        base = tuple(_clean_rotation(T, f"base_twists[{k}]") for k, T in enumerate(self.base_twists))
        if len(base) != 3:
            raise SceneError("base_twists: expected 3 matrices (T_-1, T_0, T_1)")
        object.__setattr__(self, "base_twists", base)
        self._validate_base()
        object.__setattr__(self, "gravity", _number(self.gravity, "gravity"))
        if abs(self.gravity) > GRAVITY_MAX:
            raise SceneError(f"gravity: must be within [-1e6, 1e6] m/s^2, got {self.gravity!r}")
        object.__setattr__(self, "gravity_direction", _unit_direction(self.gravity_direction, "gravity_direction"))
        object.__setattr__(self, "friction_velocity", _in_range(self.friction_velocity, "friction_velocity",
                                                                FRICTION_VELOCITY_RANGE, "m/s"))
        self._validate_walls()
        if self.link_restitution is not None:
            e = _number(self.link_restitution, "restitution.links")
            if not 0.0 <= e <= 1.0:
                raise SceneError(f"restitution.links: must be in [0, 1], got {e!r}")
            object.__setattr__(self, "link_restitution", e)
        c_f = _number(self.link_friction, "friction.links")
        if not 0.0 <= c_f <= FRICTION_MAX:
            raise SceneError(f"friction.links: the Coulomb coefficient must be in [0, {FRICTION_MAX:g}], got {c_f!r}")
        object.__setattr__(self, "link_friction", float(c_f))
        if self.contact_pairs is not None:
            object.__setattr__(self, "contact_pairs", self._checked_pairs(self.contact_pairs))
        self._validate_joints()
        self._validate_obstacles()
        self._validate_state()

    # -- derived sizes -----------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.links)

    @property
    def nq(self) -> int:
        return self.n + 5

    @property
    def npoint(self) -> int:
        """The joint points O_1..O_(n+1)."""
        return self.n + 1

    @property
    def all_twists(self) -> tuple:
        """T_-1, T_0, T_1, T_2, ..., T_n (n + 2 matrices)."""
        return tuple(self.base_twists) + tuple(self.twists)

    def wall(self, name: str) -> Wall | None:
        for w in self.walls:
            if w.name == name:
                return w
        return None

    # -- validation helpers --------------------------------------------------
    def _validate_base(self) -> None:
        if not isinstance(self.base, Base):
            raise SceneError(f"base: expected a codegen.scene.Base, got {self.base!r}")
        base = self.base.checked()
        if base.kind == "fixed" and self.n < 2:
            raise SceneError("base.kind: a fixed base welds link 1 to the box, so a chain of n = 1 link has nothing "
                             "to move; give links 2..n (or kind = 'pinned')")
        if base.kind != "free" and (base.kind == "fixed" or base.joint == "revolute") and \
                self.base_twists != (T_MINUS1, T_0, T_1):
            raise SceneError(f"base: a {base.label} base is placed through the default base twists "
                             "(T_-1, T_0, T_1 of docs/model.md); base_twists must be the default")
        object.__setattr__(self, "base", base)

    def _validate_walls(self) -> None:
        n = self.n
        seen = set()
        walls = []
        for w in self.walls:
            if w.name not in WALL_NAMES:
                raise SceneError(f"walls: unknown wall {w.name!r}; allowed: {', '.join(WALL_NAMES)}")
            if w.name in seen:
                raise SceneError(f"walls.{w.name}: given twice")
            seen.add(w.name)
            _number(w.position, f"walls.{w.name}")
            e = _number(w.restitution, f"restitution.{w.name}")
            if not 0.0 <= e <= 1.0:
                raise SceneError(f"restitution.{w.name}: must be in [0, 1], got {e!r}")
            held = self.base.held_points()
            points = tuple(w.points) if w.points else tuple(p for p in range(1, n + 2) if p not in held)
            for p in points:
                if isinstance(p, bool) or not isinstance(p, int) or not 1 <= p <= n + 1:
                    raise SceneError(f"contacts.{w.name}: point indices must be integers in 1..{n + 1} "
                                     f"(O_1..O_{n + 1}), got {p!r}")
                if p in held:
                    raise SceneError(f"contacts.{w.name}: O_{p} is held in place by the {self.base.label} base and "
                                     f"never touches a wall; allowed points: "
                                     f"{', '.join(str(i) for i in range(1, n + 2) if i not in held)}")
            if len(set(points)) != len(points):
                raise SceneError(f"contacts.{w.name}: repeated point index in {list(points)}")
            c_f = _number(w.friction, f"friction.{w.name}")
            if not 0.0 <= c_f <= FRICTION_MAX:
                raise SceneError(f"friction.{w.name}: the Coulomb coefficient must be in [0, {FRICTION_MAX:g}], got {c_f!r}")
            walls.append(Wall(w.name, float(w.position), e, tuple(sorted(points)), float(c_f)))
        walls.sort(key=lambda w: WALL_NAMES.index(w.name))
        for axis in range(3):
            lo = self._find(walls, f"x{axis + 1}_min")
            hi = self._find(walls, f"x{axis + 1}_max")
            if lo and hi and not lo.position < hi.position:
                raise SceneError(f"walls.x{axis + 1}_max: must be > x{axis + 1}_min = {lo.position}, "
                                 f"got {hi.position}")
        object.__setattr__(self, "walls", tuple(walls))

    def _validate_joints(self) -> None:
        n = self.n
        joints = tuple(self.joints) if self.joints else (FREE_JOINT,) * (n - 1)
        if len(joints) != n - 1:
            raise SceneError(f"joints: expected n - 1 = {n - 1} joints (2..n), got {len(joints)}")
        for k, joint in enumerate(joints, start=2):
            if not isinstance(joint, Joint):
                raise SceneError(f"links[{k}]: expected a Joint for joint {k}, got {joint!r}")
            joint.validate(f"links[{k}]")
        object.__setattr__(self, "joints", joints)
        names = coordinate_names(n)
        inputs = self.inputs
        if isinstance(inputs, str) or not isinstance(inputs, (list, tuple)):
            raise SceneError(f"inputs: expected a list of coordinate names, got {inputs!r}")
        for name in inputs:
            if name not in names:
                raise SceneError(f"inputs: unknown coordinate {name!r}; allowed: {', '.join(names)}")
        if len(set(inputs)) != len(inputs):
            raise SceneError(f"inputs: a coordinate is named twice in {list(inputs)}")
        held = self.base.held(n)
        for name in inputs:
            if names.index(name) in held:
                raise SceneError(f"inputs: {name} is held by the {self.base.label} base (not a coordinate of the "
                                 f"model); allowed: {', '.join(x for i, x in enumerate(names) if i not in held)}")
        object.__setattr__(self, "inputs", tuple(inputs))

    @property
    def nu(self) -> int:
        return len(self.inputs)

    @property
    def driven(self) -> bool:
        """Whether anything but gravity acts in flight: inputs, springs or dampers."""
        return bool(self.inputs) or any(not j.is_free for j in self.joints)

    def input_coordinates(self) -> list[int]:
        """The full-layout index (Eq. 13) of each input's coordinate."""
        names = coordinate_names(self.n)
        return [names.index(name) for name in self.inputs]

    @staticmethod
    def _find(walls, name):
        return next((w for w in walls if w.name == name), None)

    def _validate_obstacles(self) -> None:
        if isinstance(self.obstacles, (str, bytes, dict)) or not isinstance(self.obstacles, (list, tuple)):
            raise SceneError(f"obstacles: expected a list of obstacles, got {self.obstacles!r}")
        e = _number(self.obstacle_restitution, "restitution")
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"restitution: must be in [0, 1], got {e!r}")
        held = self.base.held_points()
        moving = [i for i in range(1, self.n + 1) if not (i in held and i + 1 in held)]
        out, names = [], set()
        for k, item in enumerate(self.obstacles, start=1):
            if not isinstance(item, Obstacle):
                raise SceneError(f"obstacles[{k}]: expected a codegen.scene.Obstacle, got {item!r}")
            item = item.checked(f"obstacles[{k}]", e, self.n, moving)
            if item.name in names:
                raise SceneError(f"obstacles[{k}].name: {item.name!r} is given twice; obstacle names are unique")
            names.add(item.name)
            out.append(item)
        object.__setattr__(self, "obstacles", tuple(out))
        object.__setattr__(self, "obstacle_restitution", e)

    def _validate_state(self) -> None:
        nq = self.nq
        held = self.base.held(self.n)
        q0 = self._held_state(self.q0, held, "initial.q")
        qd0 = self._held_state(self.qd0, {i: 0.0 for i in held}, "initial.qd")
        if 1 not in held and abs(math.cos(q0[1])) < GIMBAL_MARGIN:
            raise SceneError("initial.q[1] (theta_0): at the gimbal lock theta_0 = +-pi/2 of the base "
                             "orientation chart; allowed |theta_0| < pi/2")
        object.__setattr__(self, "q0", q0)
        object.__setattr__(self, "qd0", qd0)
        for k, stop in self.stops():
            theta = q0[k + 1]
            if stop.normal_sign * (theta - stop.position) < 0:
                raise SceneError(f"initial.q[{k + 1}] (theta_{k}): {theta!r} rad is beyond the joint's "
                                 f"{'lower' if stop.side < 0 else 'upper'} limit {stop.position!r} rad")
        points = contact_points(self, np.array(q0))
        for w in self.walls:
            for p in self.base.held_points():
                x = points[p - 1, w.axis]
                if not (x >= w.position if w.side < 0 else x <= w.position):
                    raise SceneError(f"base.point: the {self.base.label} base holds O_{p} at X{w.axis + 1} = "
                                     f"{x:.6g}, outside the wall {w.name} = {w.position:g}; allowed X{w.axis + 1} "
                                     f"{'>=' if w.side < 0 else '<='} {w.position:g}")
        for c in self.obstacle_contacts():
            if c.obstacle.bounded_by_planes:
                gap = c.obstacle.distance(*c.segment(points)) - c.radius
                if gap < 0.0:
                    part = f"link {c.i}" if c.end == 0 else f"O_{c.joint} (an end of link {c.i})"
                    raise SceneError(f"initial.q: {part} overlaps the {c.obstacle.kind} {c.obstacle.name} by "
                                     f"{-gap:.6g} m (it reaches {gap + c.radius:.6g} m from the surface, "
                                     f"less than its radius {c.radius:g} m); allowed: a start with every link "
                                     "clear of it")
                continue
            a, b = c.obstacle.segment
            gap = segment_distance(points[c.i - 1], points[c.i], a, b) - c.radius
            if gap < 0.0:
                raise SceneError(f"initial.q: link {c.i} overlaps the obstacle {c.obstacle.name} by {-gap:.6g} m (its "
                                 f"segment is {gap + c.radius:.6g} m from the obstacle's, less than their radii "
                                 f"{c.radius:g} m together); allowed: a start with every link clear of it")
        for w in self.walls:
            for p in w.points:
                x, r = points[p - 1, w.axis], self.point_radius(p)
                inside = x - r >= w.position if w.side < 0 else x + r <= w.position
                if not inside:
                    reach = f" (its capsule's radius {r:g} m included)" if r > 0.0 else ""
                    bound = w.position + r if w.side < 0 else w.position - r
                    raise SceneError(
                        f"initial.q: contact point O_{p} has X{w.axis + 1} = {x:.6g}, outside the wall "
                        f"{w.name} = {w.position:g}{reach}; allowed X{w.axis + 1} "
                        f"{'>=' if w.side < 0 else '<='} {bound:g}")

    def _held_state(self, given, held: dict[int, float], field: str) -> tuple[float, ...]:
        """The full-layout initial q (or qd) from what the scene gives: nothing (the default start), the full layout
        of Eq. 13 (the held entries at the base's values) or the model's coordinates alone (Eq. 13 order, the held
        ones left out), with the held entries set to the base's values exactly."""
        nq, names = self.nq, coordinate_names(self.n)
        if isinstance(given, np.ndarray):
            given = given.tolist()
        if not len(given):
            given = default_planar_state(self.n) if field == "initial.q" else (0.0,) * nq
        elif held and isinstance(given, (list, tuple)) and len(given) == nq - len(held):
            values = iter(_vector(list(given), nq - len(held), field))
            given = [held[i] if i in held else next(values) for i in range(nq)]
        elif held and (not isinstance(given, (list, tuple)) or len(given) != nq):
            raise SceneError(f"{field}: expected {nq} values (the layout of Eq. 13) or the {nq - len(held)} "
                             f"coordinates the {self.base.label} base leaves ("
                             f"{', '.join(x for i, x in enumerate(names) if i not in held)}), got {given!r}")
        else:
            values = _vector(list(given), nq, field)
            for i, value in held.items():
                if abs(values[i] - value) > 1e-9 * max(1.0, abs(value)):
                    what = self.base.source(i, self.n) if field == "initial.q" else "a held coordinate has no rate"
                    raise SceneError(f"{field}[{i}] ({names[i]}): the {self.base.label} base holds it at "
                                     f"{value:.12g} ({what}), got {values[i]!r}")
            given = values
        out = list(_vector(list(given), nq, field))
        for i, value in held.items():
            out[i] = value
        return tuple(out)

    # -- parameters ----------------------------------------------------------
    def parameter_names(self) -> list[str]:
        """Names of the runtime parameter vector p (see the generated header for units)."""
        names = [parameter_name("g")]
        for i, link in enumerate(self.links, start=1):
            names += [parameter_name(kind, i) for kind in link.param_names]
        names += [parameter_name("wall", w.name) for w in self.walls]
        names += [parameter_name("e", w.name) for w in self.walls]
        names += [parameter_name("friction", w.name) for w in self.walls if w.friction > 0.0]
        for k, joint in enumerate(self.joints, start=2):
            if joint.stiffness is not None:
                names += [parameter_name("stiffness", k), parameter_name("rest_angle", k)]
            if joint.damping is not None:
                names.append(parameter_name("damping", k))
            if joint.lower is not None:
                names.append(parameter_name("lower", k))
            if joint.upper is not None:
                names.append(parameter_name("upper", k))
            if joint.lower is not None or joint.upper is not None:
                names.append(parameter_name("e_limit", k))
        names += [parameter_name("e", o.name) for o in self.obstacles]
        names += [parameter_name("friction", o.name) for o in self.obstacles if o.friction > 0.0]
        names += [name for o in self.obstacles for name in o.geometry_names]
        return names

    def parameter_index(self, kind: str, owner: int | str | None = None) -> int:
        """The index in p of parameter ``kind`` of ``owner`` (parameter_name), or SceneError if the scene has none."""
        name = parameter_name(kind, owner)
        names = self.parameter_names()
        if name not in names:
            raise SceneError(f"{name}: this scene has no such parameter (it has {', '.join(names)})")
        return names.index(name)

    def parameter_vector(self) -> np.ndarray:
        values = [self.gravity]
        for link in self.links:
            values += list(link.param_values())
        values += [w.position for w in self.walls]
        values += [w.restitution for w in self.walls]
        values += [w.friction for w in self.walls if w.friction > 0.0]
        for joint in self.joints:
            if joint.stiffness is not None:
                values += [joint.stiffness, joint.rest_angle]
            if joint.damping is not None:
                values.append(joint.damping)
            if joint.lower is not None:
                values.append(joint.lower)
            if joint.upper is not None:
                values.append(joint.upper)
            if joint.lower is not None or joint.upper is not None:
                values.append(joint.limit_restitution)
        values += [o.restitution for o in self.obstacles]
        values += [o.friction for o in self.obstacles if o.friction > 0.0]
        values += [x for o in self.obstacles for x in o.geometry_values]
        return np.array(values, dtype=float)

    @property
    def warnings(self) -> list[str]:
        """Values the scene accepts but that suggest a slip of units (see unit_warnings), one sentence each."""
        return unit_warnings(self)

    def point_radius(self, p: int) -> float:
        """The radius (m) the joint point O_p touches a wall with: the larger of the capsule radii of the links
        that end there (link p - 1 and link p); 0 for segments."""
        return max((self.links[i - 1].radius for i in (p - 1, p) if 1 <= i <= self.n), default=0.0)

    def capsule_radius(self, i: int) -> float:
        """The capsule radius (m) of link i (0 for a segment)."""
        return self.links[i - 1].radius

    def full_coordinate_names(self) -> list[str]:
        """The names of the full layout (Eq. 13): theta_-1, theta_0, theta_1..theta_n, X1, X2, X3."""
        return coordinate_names(self.n)

    def possible_link_pairs(self) -> list[tuple[int, int]]:
        """The pairs of links (i < j, 1-based) that can touch each other as capsules: not adjacent (adjacent links
        share a joint point, where their capsules always overlap) and with radii adding up to more than 0 (two
        segments of no thickness meet only by crossing, which no gap of theirs can see coming)."""
        return [(i, j) for i in range(1, self.n + 1) for j in range(i + 2, self.n + 1)
                if self.links[i - 1].radius + self.links[j - 1].radius > 0.0]

    def link_pairs(self) -> list[tuple[int, int]]:
        """The link pairs that are contacts of the model: possible_link_pairs, or those of them ``contact_pairs``
        names."""
        pairs = self.possible_link_pairs()
        return pairs if self.contact_pairs is None else [pair for pair in pairs if pair in self.contact_pairs]

    def _checked_pairs(self, pairs) -> tuple:
        """contact_pairs as sorted (i, j) tuples, i < j, each a possible pair; a SceneError naming contacts.links."""
        possible = self.possible_link_pairs()
        if not isinstance(pairs, (list, tuple)):
            raise SceneError(f"contacts.links: expected a list of link pairs [i, j], got {pairs!r}")
        out = set()
        for pair in pairs:
            if (not isinstance(pair, (list, tuple)) or len(pair) != 2
                    or not all(isinstance(v, int) and not isinstance(v, bool) for v in pair)):
                raise SceneError(f"contacts.links: expected pairs of link numbers [i, j], got {pair!r}")
            i, j = sorted(pair)
            if (i, j) not in possible:
                raise SceneError(f"contacts.links: links {i} and {j} cannot strike each other (allowed: the pairs "
                                 "of links 1..n, not adjacent, with radii adding up to more than 0: "
                                 f"{', '.join(f'[{a}, {b}]' for a, b in possible) or 'none'}), got {list(pair)!r}")
            out.add((i, j))
        return tuple(sorted(out))

    def link_contacts(self) -> list[LinkPair]:
        """The link pairs as contacts of the loop (after the walls and stops), with their radius sums and e."""
        e = 1.0 if self.link_restitution is None else float(self.link_restitution)
        return [LinkPair(i, j, self.links[i - 1].radius + self.links[j - 1].radius, e, self.link_friction)
                for i, j in self.link_pairs()]

    def obstacle_contacts(self) -> list[ObstacleContact]:
        """The contacts of the obstacles (after the link pairs), obstacle-major: a link and a sphere, a bar or a
        box, in link order; then a plane's or a box's joint points, in point order.  A plane's signed distance is
        linear along a link, so a capsule is nearest to it at an end sphere (or all along, lying flat): its joint
        points are its contacts, each with the larger radius of the listed links ending there (taken on that link),
        and a link that comes to lie on the plane rests on two of them, a line contact.  A box's face is such a
        plane where a link lies over it, but an edge or a corner can touch a link anywhere along it, as a bar can:
        a box and a bar have both, each link's contact (where its nearest point is inside it) and the joint
        points' (which take the link's contact's place where its nearest point is an end: gac_redundant).  A
        sphere touches a link at one point: the link's contact alone."""
        out = []
        for k, o in enumerate(self.obstacles):
            if o.kind != "plane":
                out += [ObstacleContact(i, o, k, self.links[i - 1].radius + o.radius) for i in o.links]
            if o.kind == "sphere":
                continue
            for p in sorted({p for i in o.links for p in (i, i + 1)}):
                carriers = [i for i in (p - 1, p) if i in o.links]      # the listed links ending at O_p
                i = max(carriers, key=lambda i: self.links[i - 1].radius)
                out.append(ObstacleContact(i, o, k, self.links[i - 1].radius + o.radius, end=2 if i == p - 1 else 1))
        return out

    def rowless_contacts(self) -> list:
        """The contacts after the kernel's walls and stops, in the model's table order: each link pair (LinkPair),
        the pairs' end contacts (pair_ends), then each link and obstacle (ObstacleContact)."""
        pairs = self.link_contacts()
        return [*pairs, *pair_ends(pairs, self.capsule_radius), *self.obstacle_contacts()]

    def radius_owner(self, p: int) -> int | None:
        """The link (1-based) whose radius point_radius(p) takes, or None when it is 0."""
        r = self.point_radius(p)
        return next((i for i in (p - 1, p) if 1 <= i <= self.n and self.links[i - 1].radius == r), None) \
            if r > 0.0 else None

    def stops(self) -> list[tuple[int, JointStop]]:
        """The joint stops as (joint k, JointStop) pairs, joint order, lower before upper."""
        out = []
        for k, joint in enumerate(self.joints, start=2):
            for side, position in ((-1, joint.lower), (+1, joint.upper)):
                if position is not None:
                    out.append((k, JointStop(k, side, float(position), float(joint.limit_restitution))))
        return out

    def contacts(self) -> list[tuple]:
        """The (point, wall) pairs with a gap function, wall-major then point order, then the joint stops as
        (joint k, JointStop) pairs."""
        return [(p, w) for w in self.walls for p in w.points] + self.stops()

    def contact_rows(self) -> list[tuple]:
        """The (point, axis) pairs whose Jacobian row (Eq. 42) some wall needs, point-major, then a row
        (k, "theta") for each joint with a stop (a row of the identity)."""
        needed = {(p, w.axis) for w in self.walls for p in w.points}
        needed |= {(p, axis) for w in self.walls if w.friction > 0.0 for p in w.points for axis in range(3)}
        return sorted(needed) + stop_rows(self.stops())


def unit_warnings(scene: Scene) -> list[str]:
    """Link lengths outside UNITS_LENGTH, link masses outside UNITS_MASS, and angles (rest angles, joint limits,
    initial angles) beyond UNITS_ANGLE in magnitude: one sentence per kind, naming the first such field and how
    many more there are."""
    found: dict[str, list[str]] = {"length": [], "mass": [], "angle": []}
    for i, link in enumerate(scene.links, start=1):
        if not UNITS_LENGTH[0] <= link.length <= UNITS_LENGTH[1]:
            found["length"].append(f"links[{i}].length = {link.length:g} m")
        if not UNITS_MASS[0] <= link.mass <= UNITS_MASS[1]:
            found["mass"].append(f"links[{i}].mu = {link.mu:g} kg/m (a mass of {link.mass:g} kg)"
                                 if link.kind == "line" else f"links[{i}].mass = {link.mass:g} kg")
    for k, joint in enumerate(scene.joints, start=2):
        for key in ("rest_angle", "lower", "upper"):
            value = getattr(joint, key)
            if value is not None and abs(value) > UNITS_ANGLE:
                found["angle"].append(f"links[{k}].{key} = {value:g} rad")
    names = coordinate_names(scene.n)
    for index in range(scene.n + 2):
        if abs(scene.q0[index]) > UNITS_ANGLE:
            found["angle"].append(f"initial.q[{index}] ({names[index]}) = {scene.q0[index]:g} rad")
    advice = {
        "length": f"outside {UNITS_LENGTH[0]:g} ... {UNITS_LENGTH[1]:g} m, unusual for a link; lengths are in m, "
                  "not mm or km",
        "mass": f"outside {UNITS_MASS[0]:g} ... {UNITS_MASS[1]:g} kg, unusual for a link; masses are in kg and mu "
                "in kg/m, not g or t",
        "angle": "beyond 2 pi in magnitude; angles are in radians (90 degrees is 1.5708 rad)",
    }
    out = []
    for kind, fields in found.items():
        if fields:
            more = f" (and {len(fields) - 1} more)" if len(fields) > 1 else ""
            out.append(f"{fields[0]}{more}: {advice[kind]}")
    return out


def stop_rows(stops) -> list[tuple[int, str]]:
    """One Jacobian row (k, "theta") per joint that has a stop, in joint order."""
    return [(k, "theta") for k in sorted({k for k, _ in stops})]


# ---------------------------------------------------------------------------
# numeric forward kinematics (for validating initial states and for plots)
# ---------------------------------------------------------------------------
def frames(scene: Scene, q: np.ndarray) -> list[np.ndarray]:
    """^{ref}R_k for k = -1..n (n + 2 matrices), with the scene's twists."""
    R = np.eye(3)
    out = []
    for k, T in enumerate(scene.all_twists):
        R = R @ np.array(T) @ rot_z(q[k])
        out.append(R)
    return out


def contact_points(scene: Scene, q: np.ndarray) -> np.ndarray:
    """Positions of O_1..O_{n+1} in the reference frame, shape (n + 1, 3); of several chains (codegen.scene.Chains, q
    their stacked full layouts), every chain's points in global order."""
    q = np.asarray(q, dtype=float)
    if not isinstance(scene, Scene):
        return np.concatenate([contact_points(chain, q[scene.state_offset(k):scene.state_offset(k) + chain.nq])
                               for k, chain in enumerate(scene.chains, start=1)])
    Rs = frames(scene, q)
    points = [q[scene.n + 2: scene.n + 5].copy()]
    for i, link in enumerate(scene.links, start=1):
        points.append(points[-1] + link.length * Rs[i + 1][:, 0])
    return np.array(points)


# ---------------------------------------------------------------------------
# built-in scenes
# ---------------------------------------------------------------------------
def default_planar_state(n: int) -> tuple[float, ...]:
    """A planar closed-polygon start: theta_-1 = -pi/2, theta_0 = 0, link 1 at pi - pi/n from +X1,
    every later link turned by -2 pi / n.  For n = 4 this is the paper's case 1 square."""
    thetas = [math.pi / 2 - math.pi / n] + [-2 * math.pi / n] * (n - 1)
    return (-math.pi / 2, 0.0, *thetas, 0.0, 0.0, 0.0)


def default_scene(n: int) -> Scene:
    """The built-in scene for `--links N`: N links with Table 1 parameters (l = 1 m, mu = 1 kg/m),
    planar, closed-polygon start at rest, in a rectangle that is the paper's 3 m x 2 m one for
    N <= 4 and grows to hold longer chains.  For N = 4 it is the paper's case study 1."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise SceneError(f"links: n must be an integer >= 1, got {n!r}")
    links = tuple(LineLink(1.0, 1.0, PAPER_J) for _ in range(n))
    q = list(default_planar_state(n))
    probe = Scene(name=f"chain{n}", links=links, q0=tuple(q))
    pts = contact_points(probe, np.array(q))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    width = max(3.0, hi[0] - lo[0] + 1.5)
    height = max(2.0, hi[1] - lo[1] + 0.5)
    q[n + 2] = round(width / 2 - (lo[0] + hi[0]) / 2, 12)   # rounding hides the polygon's round-off
    q[n + 3] = round(0.3 - lo[1], 12)
    walls = (Wall("x1_min", 0.0), Wall("x1_max", width), Wall("x2_min", 0.0), Wall("x2_max", height))
    return Scene(name=f"chain{n}", links=links, walls=walls, q0=tuple(q),
                 description=f"{n}-link planar chain, Table 1 parameters, closed-polygon start")


def _shipped_scene_path(name: str) -> Path:
    return Path(__file__).resolve().parent / "scenes" / f"{name}.toml"


def shipped_scene_names() -> list[str]:
    folder = Path(__file__).resolve().parent / "scenes"
    return sorted(p.stem for p in folder.glob("*.toml"))


# ---------------------------------------------------------------------------
# loading from TOML / JSON
# ---------------------------------------------------------------------------
TOP_KEYS = ("name", "description", "gravity", "gravity_direction", "links", "urdf", "urdf_tip_length", "walls",
            "restitution", "friction", "friction_velocity", "contacts", "initial", "inputs", "base", "obstacles")
BASE_KEYS = ("kind", "joint", "point", "axis", "angles", "rotation")
JOINT_KEYS = ("stiffness", "rest_angle", "damping", "lower", "upper", "limit_restitution")
LINE_KEYS = ("length", "mu", "J", "radius", "twist", "twist_matrix", "count") + JOINT_KEYS
RIGID_KEYS = ("length", "mass", "com", "inertia", "radius", "twist", "twist_matrix", "count") + JOINT_KEYS
INITIAL_KEYS = ("q", "qd")
BOX_KEYS = ("gravity", "gravity_direction", "walls", "restitution", "friction", "friction_velocity", "obstacles")


def scene_file(source: str | Path) -> Path:
    """The absolute path of the file a scene source names: a .toml/.json path, else a shipped scene."""
    if not isinstance(source, (str, Path)):
        raise SceneError(f"scene: expected a shipped scene name or a path to a .toml/.json/.urdf file, got "
                         f"{source!r} ({type(source).__name__})")
    if not str(source).strip():
        raise SceneError("scene: empty name; expected a .toml/.json scene file, a .urdf file or a shipped scene name")
    path = Path(source)
    if not path.exists():
        shipped = _shipped_scene_path(str(source)) if re.fullmatch(r"[A-Za-z0-9_-]+", str(source)) else None
        if shipped is not None and shipped.exists():
            path = shipped
        else:
            raise SceneError(f"scene: no file {str(source)!r} and no shipped scene of that name; "
                             f"shipped scenes: {', '.join(shipped_scene_names())}")
    if path.is_dir():
        raise SceneError(f"scene: {path} is a directory; give a .toml or .json scene file")
    return path.absolute()


URDF_BOX_MARGIN = 0.25     # m: the default box around a URDF chain is this much wider than its reach
URDF_RESTITUTION = 0.7     # e of the default box's walls


def urdf_scene(path: str | Path) -> Scene:
    """A scene for a URDF file alone: its serial chain (codegen.urdf) at rest with every joint at 0 (at the
    middle of its limits where 0 is outside them) and the base frame unturned, falling under gravity (-X2) from
    the centre of a box of six walls (e = URDF_RESTITUTION) that holds the chain in any orientation: half-width
    its reach from its centre plus URDF_BOX_MARGIN.  For other walls or a start of your own, write a scene file
    with ``urdf = "FILE"`` (docs/scenes.md)."""
    path = Path(path)
    folder, name = path.absolute().parent, re.sub(r"\W", "_", path.stem)[:48] or "urdf"
    if not re.match(r"[A-Za-z_]", name):
        name = f"urdf_{name}"[:48]
    tables, base = _chain_tables({"urdf": path.name}, folder)
    links, twists, joints = _links_from_data(tables)
    n = len(links)
    angles = []
    for joint in (joints if n > 1 else ()):
        lower = -math.inf if joint.lower is None else joint.lower
        upper = math.inf if joint.upper is None else joint.upper
        angles.append(0.0 if lower <= 0.0 <= upper else
                      0.5 * (lower + upper) if math.isfinite(lower + upper) else (lower if lower > 0 else upper))
    if base is not None:
        if base["kind"] == "pinned":                 # theta_1 too: the URDF angle 0 of the joint that holds the root
            angles = [urdf_mount_offset(path.read_text()), *angles]
        return _urdf_mounted_scene(path, name, links, twists, joints, _base_from_data(base), angles)
    q = [0.0, 0.0, 0.0, *angles, 0.0, 0.0, 0.0]
    probe = Scene(name=name, links=links, twists=twists if n > 1 else (), joints=joints if n > 1 else (),
                  q0=tuple(q))
    points = contact_points(probe, np.array(q))
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    reach = float(np.linalg.norm(points - centre, axis=1).max())
    half = reach + URDF_BOX_MARGIN
    q[n + 2: n + 5] = [round(float(v), 12) for v in (half - centre)]      # the chain's centre at (half, half, half)
    walls = tuple(Wall(f"x{axis}_{side}", 0.0 if side == "min" else round(2 * half, 12), URDF_RESTITUTION)
                  for axis in (1, 2, 3) for side in ("min", "max"))
    return Scene(name=name, links=links, twists=probe.twists, joints=probe.joints, walls=walls, q0=tuple(q),
                 description=f"{path.name} at rest in a {2 * half:.3g} m box (the default box of a URDF file)")


def _urdf_mounted_scene(path: Path, name: str, links, twists, joints, base: Base, angles) -> Scene:
    """urdf_scene of a chain fixed or pinned to the world: at rest with its joints as there (angles: the
    coordinates the base leaves), in a box of six walls centred on O_1 whose half-width is the length of the whole
    chain plus URDF_BOX_MARGIN (every point stays within it)."""
    half = sum(link.length for link in links) + URDF_BOX_MARGIN
    walls = tuple(Wall(f"x{axis}_{side}", round(base.point[axis - 1] + (-half if side == "min" else half), 12),
                       URDF_RESTITUTION) for axis in (1, 2, 3) for side in ("min", "max"))
    return Scene(name=name, links=links, twists=twists, joints=joints, walls=walls, q0=tuple(angles), base=base,
                 description=f"{path.name} {'fixed' if base.kind == 'fixed' else 'pinned'} to the world at rest in a "
                             f"{2 * half:.3g} m box (the default box of a URDF file)")


def load_scene(source: str | Path) -> "Scene | Chains":
    """Load a scene from a .toml or .json file, a shipped scene by name (e.g. 'paper-case1'), or a URDF file
    (.urdf: its chain in a default box, urdf_scene)."""
    path = scene_file(source)
    if path.suffix.lower() == ".urdf":
        return urdf_scene(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SceneError(f"scene: cannot read {path}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(f"scene: {path} is not UTF-8 text (byte {exc.start}: {raw[exc.start:exc.start + 1]!r}); "
                         "a scene file is TOML or JSON text") from None
    if path.suffix == ".json":
        data = _parse_json(text, path)
    else:
        data = _parse_toml(text, path)
    return scene_from_dict(data, default_name=path.stem.replace("-", "_"), folder=path.parent)


def _parse_json(text: str, path: Path) -> dict:
    """JSON with every key given once (json.loads would keep the last of repeated keys silently)."""
    def unique(pairs):
        table = {}
        for key, value in pairs:
            if key in table:
                raise SceneError(f"scene: {path}: key {key!r} is given twice in one object; give it once")
            table[key] = value
        return table
    try:
        return json.loads(text, object_pairs_hook=unique)
    except json.JSONDecodeError as exc:
        raise SceneError(f"scene: cannot parse {path} as JSON: {exc}") from None


def _parse_toml(text: str, path: Path) -> dict:
    """TOML, with a repeated key named by its dotted field name and line."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        where = re.search(r"at line (\d+)", message)
        if where and "overwrite" in message:
            line = int(where.group(1))
            field = _toml_field_at(text, line)
            raise SceneError(f"scene: {path} line {line}: {field} is given twice; "
                             "TOML allows each key once per table") from None
        raise SceneError(f"scene: cannot parse {path} as TOML: {message}") from None


def _toml_field_at(text: str, line: int) -> str:
    """The dotted name of the key assigned on ``line`` (1-based) of a TOML text: [table] or [[array]]
    headers above it give the prefix."""
    lines = text.splitlines()
    key = lines[line - 1].split("=", 1)[0].strip().strip('"') if line <= len(lines) else "a key"
    for previous in reversed(lines[:line - 1]):
        header = re.match(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?", previous)
        if header:
            return f"{header.group(1)}.{key}"
    return key


def scene_from_dict(data: dict, default_name: str = "scene", folder: str | Path | None = None) -> "Scene | Chains":
    """Build a Scene from the plain-data form used by the TOML/JSON files (see docs/scenes.md); with [[chains]], a
    Chains.  ``urdf``: a URDF
    file (relative to ``folder``, the scene file's) whose serial chain gives the links (codegen.urdf)."""
    if isinstance(data, dict) and "chains" in data:          # several chains in one box: Chains
        return chains_from_dict(data, default_name, folder, BOX_KEYS)
    _check_keys(data, TOP_KEYS, "scene")
    tables, base = _chain_tables(data, folder)
    links, twists, joints = _links_from_data(tables)
    n = len(links)
    restitution = data.get("restitution", 1.0)
    contacts = data.get("contacts", {})           # points per wall, and the link pairs (links) that may strike
    pairs = contacts.get("links") if isinstance(contacts, dict) else None
    if isinstance(contacts, dict):
        contacts = {name: points for name, points in contacts.items() if name != "links"}
    friction = data.get("friction", 0.0)
    walls = _walls_from_data(data.get("walls", {}), restitution, contacts, friction)
    link_e = None                       # two capsule links meeting: restitution.links, else the scene's default
    if isinstance(restitution, dict) and "links" in restitution:
        link_e = restitution["links"]
    elif any(link.radius > 0.0 for link in links):
        link_e = restitution.get("default", 1.0) if isinstance(restitution, dict) else restitution
    default_e = restitution.get("default", 1.0) if isinstance(restitution, dict) else restitution
    initial = data.get("initial", {})
    _check_keys(initial, INITIAL_KEYS, "initial")
    return Scene(
        name=data.get("name", default_name),
        description=str(data.get("description", "")),
        links=links,
        twists=twists if n > 1 else (),
        gravity=data.get("gravity", DEFAULT_GRAVITY),
        gravity_direction=_gravity_direction_from_data(data),
        walls=walls,
        q0=tuple(initial["q"]) if "q" in initial else (),
        qd0=tuple(initial["qd"]) if "qd" in initial else (),
        joints=joints if n > 1 else (),
        inputs=data.get("inputs", ()),
        friction_velocity=data.get("friction_velocity", 1e-3),
        link_restitution=link_e,
        link_friction=friction.get("links", 0.0) if isinstance(friction, dict) else 0.0,
        contact_pairs=pairs,
        base=_base_from_data({} if base is None else base),
        obstacles=_obstacles_from_data(data.get("obstacles", [])),
        obstacle_restitution=default_e,
    )


def _gravity_direction_from_data(data: dict):
    """The gravity_direction key: a vector, or "urdf" (with a urdf file): gravity along the URDF world's -z, which
    the import takes as the box frame unturned, so (0, 0, -1); absent: -X2."""
    value = data.get("gravity_direction", DEFAULT_GRAVITY_DIRECTION)
    if isinstance(value, str):
        if value != "urdf" or "urdf" not in data:
            raise SceneError(f"gravity_direction: expected a unit vector [d1, d2, d3], or \"urdf\" in a scene with a "
                             f"urdf file (gravity along the URDF world's -z), got {value!r}")
        return URDF_GRAVITY_DIRECTION
    return value


def _obstacles_from_data(items) -> tuple[Obstacle, ...]:
    """The [[obstacles]] tables (docs/scenes.md, "Obstacles"): each checked by Scene."""
    if not isinstance(items, list):
        raise SceneError(f"obstacles: expected a list of tables ([[obstacles]]), got {items!r}")
    out = []
    for k, item in enumerate(items, start=1):
        where = f"obstacles[{k}]"
        if not isinstance(item, dict):
            raise SceneError(f"{where}: expected a table, got {item!r}")
        _check_keys(item, OBSTACLE_KEYS, where)
        if "name" not in item:
            raise SceneError(f"{where}.name: required")
        kind = item.get("kind", "sphere")
        if kind not in OBSTACLE_KINDS:
            raise SceneError(f"{where}.kind: one of {', '.join(repr(k) for k in OBSTACLE_KINDS)}, got {kind!r}")
        fields = OBSTACLE_FIELDS[kind]
        shaped = kind in ("box", "plane")
        for key in (("center", "a", "b", "radius") if shaped else ()) + ("half_extents", "rotation", "point", "normal"):
            if key in item and key not in fields:
                raise SceneError(f"{where}.{key}: a {kind} takes {', '.join(fields)}, not {key}")
        for key in fields if shaped else ("radius",):
            if key not in item and key != "rotation":
                raise SceneError(f"{where}.{key}: required" + (f" for a {kind}" if shaped else ""))
        if shaped:
            out.append(Obstacle(item["name"], kind, item.get("center", item.get("point")), None, 0.0,
                                item.get("restitution"), item.get("links"), item.get("half_extents"),
                                item.get("rotation"), item.get("normal"), item.get("friction", 0.0)))
            continue
        if kind == "sphere":
            if "a" in item or "b" in item:
                raise SceneError(f"{where}.{'a' if 'a' in item else 'b'}: a sphere takes center; give kind = "
                                 "'capsule' for a bar from a to b")
            if "center" not in item:
                raise SceneError(f"{where}.center: required for a sphere (its centre [X1, X2, X3], m)")
            a, b = item["center"], None
        else:
            if "center" in item:
                raise SceneError(f"{where}.center: a capsule takes its end points a and b (m), not a center")
            for key in ("a", "b"):
                if key not in item:
                    raise SceneError(f"{where}.{key}: required for a capsule (a bar from a to b, m)")
            a, b = item["a"], item["b"]
        out.append(Obstacle(item["name"], kind, a, b, item["radius"], item.get("restitution"), item.get("links"),
                            friction=item.get("friction", 0.0)))
    return tuple(out)


def _base_from_data(table) -> Base:
    """The [base] table (docs/scenes.md, "The base"); absent: a free base."""
    _check_keys(table, BASE_KEYS, "base")
    if "kind" not in table and table:
        raise SceneError(f"base.kind: required with other base fields; one of {', '.join(repr(k) for k in BASE_KINDS)}")
    rotation = table.get("rotation")
    return Base(table.get("kind", "free"), table.get("joint"), table.get("point"), table.get("axis"),
                table.get("angles"), rotation)


def _link_tables(data: dict, folder) -> list:
    """The [[links]] tables, given or read from the URDF file the scene names."""
    return _chain_tables(data, folder)[0]


def _chain_tables(data: dict, folder) -> tuple[list, dict | None]:
    """The [[links]] tables and the [base] table (None: none), given or read from the URDF file the scene names."""
    if "urdf" not in data:
        if "urdf_tip_length" in data:
            raise SceneError("urdf_tip_length: given without a urdf file")
        return data.get("links"), data.get("base")
    if "links" in data:
        raise SceneError("urdf: give either links or a urdf file, not both")
    if not isinstance(data["urdf"], str) or not data["urdf"]:
        raise SceneError(f"urdf: expected the path of a URDF file, got {data['urdf']!r}")
    path = Path(folder or ".") / data["urdf"]
    tip = data.get("urdf_tip_length")
    if tip is not None:
        tip = _in_range(tip, "urdf_tip_length", LENGTH_RANGE, "m")
    try:
        text = path.read_text()
    except OSError as exc:
        raise SceneError(f"urdf: cannot read {path}: {exc.strerror or exc}") from None
    try:
        tables, base = urdf_chain(text, tip)
    except SceneError as exc:
        raise SceneError(f"urdf {path}: {exc}") from None
    if base is not None and "base" in data:
        raise SceneError(f"base: the URDF file {data['urdf']} holds its root link to the world (a "
                         f"{'fixed' if base['kind'] == 'fixed' else 'pinned revolute'} base); give no [base] table")
    return tables, base if base is not None else data.get("base")


def _links_from_data(items) -> tuple[tuple[Link, ...], tuple, tuple]:
    if not isinstance(items, list) or not items:
        raise SceneError("links: a chain needs n >= 1 real links (a non-empty list of link tables), "
                         f"got {items!r}")
    counts = [item.get("count", 1) if isinstance(item, dict) else 1 for item in items]
    if all(isinstance(c, int) and not isinstance(c, bool) for c in counts) and sum(counts) > MAX_LINKS:
        raise SceneError(f"links: {MAX_LINKS_REASON}; got n = {sum(counts)}")
    links, twists, joints = [], [], []
    for j, item in enumerate(items):
        where = f"links[{len(links) + 1}]"
        if not isinstance(item, dict):
            raise SceneError(f"{where}: expected a table, got {item!r}")
        rigid = "mass" in item or "inertia" in item or "com" in item
        _check_keys(item, RIGID_KEYS if rigid else LINE_KEYS, where)
        count = item.get("count", 1)
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise SceneError(f"{where}.count: must be an integer >= 1, got {count!r}")
        for _ in range(count):
            where = f"links[{len(links) + 1}]"
            if rigid:
                for key in ("length", "mass", "com", "inertia"):
                    if key not in item:
                        raise SceneError(f"{where}.{key}: required for a rigid link (mass, com, inertia)")
                link = RigidLink(item["length"], item["mass"], tuple(item["com"]),
                                 tuple(tuple(r) for r in item["inertia"]), item.get("radius", 0.0))
            else:
                for key in ("length", "mu"):
                    if key not in item:
                        raise SceneError(f"{where}.{key}: required")
                link = LineLink(item["length"], item["mu"], tuple(item.get("J", PAPER_J)), item.get("radius", 0.0))
            link.validate(where)
            index = len(links) + 1
            if "twist" in item and "twist_matrix" in item:
                raise SceneError(f"{where}: give either twist (angle about x, rad) or twist_matrix, not both")
            if index == 1 and ("twist" in item or "twist_matrix" in item):
                raise SceneError(f"{where}.twist: T_1 is fixed by the frame convention; "
                                 "twists can be given for links 2..n")
            if index == 1 and any(key in item for key in JOINT_KEYS):
                key = next(key for key in JOINT_KEYS if key in item)
                raise SceneError(f"{where}.{key}: theta_1 orients the base (link 1 has no parent link), so "
                                 "springs, dampers and limits can be given for the joints of links 2..n")
            if index > 1:
                joint = Joint(item.get("stiffness"), item.get("rest_angle", 0.0), item.get("damping"),
                              item.get("lower"), item.get("upper"), item.get("limit_restitution", 0.0))
                joint.validate(where)
                joints.append(joint)
                if "twist" in item:
                    twists.append(twist_about_x(_number(item["twist"], f"{where}.twist")))
                elif "twist_matrix" in item:
                    twists.append(_clean_rotation(item["twist_matrix"], f"{where}.twist_matrix"))
                else:
                    twists.append(IDENTITY)
            links.append(link)
    return tuple(links), tuple(twists), tuple(joints)


def _walls_from_data(walls, restitution, contacts, friction=0.0) -> tuple[Wall, ...]:
    _check_keys(walls, WALL_NAMES, "walls")
    if isinstance(restitution, dict):
        _check_keys(restitution, WALL_NAMES + ("default", "links"), "restitution")
        for name in restitution:
            if name not in ("default", "links") and name not in walls:
                raise SceneError(f"restitution.{name}: there is no such wall in [walls]")
    if isinstance(friction, dict):
        _check_keys(friction, WALL_NAMES + ("default", "links"), "friction")
        for name in friction:
            if name not in ("default", "links") and name not in walls:
                raise SceneError(f"friction.{name}: there is no such wall in [walls]")
    _check_keys(contacts, WALL_NAMES + ("links",), "contacts")
    for name in contacts:
        if name not in walls:
            raise SceneError(f"contacts.{name}: there is no such wall in [walls]")
    out = []
    for name in WALL_NAMES:
        if name not in walls:
            continue
        if isinstance(restitution, dict):
            if name in restitution:
                e = restitution[name]
            elif "default" in restitution:
                e = restitution["default"]
            else:
                raise SceneError(f"restitution.{name}: missing (give it, or a 'default')")
        else:
            e = restitution
        e = _number(e, f"restitution.{name}" if isinstance(restitution, dict) else "restitution")
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"restitution{'.' + name if isinstance(restitution, dict) else ''}: "
                             f"must be in [0, 1], got {e!r}")
        points = contacts.get(name, ())
        if not isinstance(points, (list, tuple)) or (name in contacts and not points):
            raise SceneError(f"contacts.{name}: expected a non-empty list of point indices "
                             f"(O_1 is 1), got {points!r}")
        if isinstance(friction, dict):
            c_f, where = friction.get(name, friction.get("default", 0.0)), f"friction.{name}"
        else:
            c_f, where = friction, "friction"
        c_f = _number(c_f, where)
        if not 0.0 <= c_f <= FRICTION_MAX:
            raise SceneError(f"{where}: the Coulomb coefficient must be in [0, {FRICTION_MAX:g}], got {c_f!r}")
        out.append(Wall(name, _number(walls[name], f"walls.{name}"), e, tuple(points), c_f))
    return tuple(out)

# ---------------------------------------------------------------------------
# several chains in one box
# ---------------------------------------------------------------------------
# A ``Chains`` holds one-chain scenes (codegen.scene.Scene) that share the box: its walls, gravity, restitution,
# friction and obstacles; each chain has its own links, base, initial state and contact keys.  The model is the
# chains' models side by side (codegen.combine): q = [q_1, q_2, ...], qd likewise, the flight inertia block-diagonal.
# What the combined model numbers globally:
#
# * **points**: chain 1's O_1..O_(n1+1), then chain 2's, ...: chain k's O_j is global point ``point_offset(k) + j``;
# * **links**: a link is named by its first point, so chain k's link j is global link ``point_offset(k) + j`` (link i
#   spans the global points O_i, O_(i+1), as in a one-chain model; the number after a chain's last link is no link);
# * **coordinates**: the full layout is the chains' full layouts one after the other, each named with its chain's
#   prefix ('c2.theta_1');
# * **parameters**: the box's (g, the walls' positions, e and friction, the obstacles' e) once, in chain 1's order,
#   then each chain's own (links, joints) with its prefix: 'c1.l_1', 'c2.mu_1', 'c2.e_limit_2';
# * **inputs**: each chain's, one after the other, with its prefix ('c1.theta_2', 'c2.theta_1').
#
# Capsule links of different chains strike each other (every pair whose radii add up to more than 0), with the box's
# ``restitution.links``.  Within a chain nothing changes (docs/scenes.md, "Several chains").
BOX_KINDS = ("g", "wall", "friction", *OBSTACLE_GEOMETRY_KINDS)      # parameters of the box, shared by every chain (and every e but e_limit)
MAX_CHAINS = 16


def _box_value(chain: Scene, field: str):
    """What a chain has of the box's ``field``: its walls without the points each chain chooses, its obstacles
    without the links."""
    if field == "walls":
        return tuple((w.name, w.position, w.restitution, w.friction) for w in chain.walls)
    if field == "obstacles":
        return tuple((o.name, o.kind, o.segment, o.radius, o.restitution, o.friction) for o in chain.obstacles)
    return getattr(chain, field)


def chain_prefix(k: int) -> str:
    """The prefix of chain k's (1-based) own names: 'c2.'."""
    return f"c{k}."


def is_box_parameter(name: str) -> bool:
    """Whether a one-chain scene's parameter belongs to the box (shared by every chain) rather than to the chain."""
    kind = split_parameter_name(name)[0]
    return kind in BOX_KINDS or kind == "e"


@dataclass(frozen=True)
class Chains:
    """Several one-chain scenes in one box (see the module's docstring).  Construction checks that they share the
    box and that the model can be built (SceneError naming the field)."""

    name: str
    chains: tuple[Scene, ...]
    description: str = ""
    link_restitution: float = 1.0         # e of two capsule links of different chains meeting
    link_friction: float = 0.0            # their Coulomb coefficient (friction.links)

    def __post_init__(self):
        chains = tuple(self.chains)
        if not 2 <= len(chains) <= MAX_CHAINS:
            raise SceneError(f"chains: several chains means 2..{MAX_CHAINS} of them, got {len(chains)}")
        for k, chain in enumerate(chains, start=1):
            if not isinstance(chain, Scene):
                raise SceneError(f"chains[{k}]: expected a Scene, got {chain!r}")
        object.__setattr__(self, "chains", chains)
        first = chains[0]
        for k, chain in enumerate(chains[1:], start=2):
            for field in ("gravity", "gravity_direction", "walls", "obstacles", "friction_velocity"):
                if _box_value(chain, field) != _box_value(first, field):
                    raise SceneError(f"chains[{k}].{field}: the chains share the box's {field} (chain 1's), "
                                     f"got a different one")
        e = float(self.link_restitution)
        if not 0.0 <= e <= 1.0:
            raise SceneError(f"restitution.links: must be in [0, 1], got {e!r}")
        object.__setattr__(self, "link_restitution", e)
        c_f = _number(self.link_friction, "friction.links")
        if not 0.0 <= c_f <= FRICTION_MAX:
            raise SceneError(f"friction.links: the Coulomb coefficient must be in [0, {FRICTION_MAX:g}], got {c_f!r}")
        object.__setattr__(self, "link_friction", float(c_f))
        self._check_apart()

    def _check_apart(self) -> None:
        """No two chains' capsules overlap at the start (a gap below 0 would be an impact already passed)."""
        ends = [contact_points(chain, np.asarray(chain.q0, dtype=float)) for chain in self.chains]
        for (k, a), (l, b) in ((x, y) for x in enumerate(ends, 1) for y in enumerate(ends, 1) if x[0] < y[0]):
            for i in range(len(a) - 1):
                for j in range(len(b) - 1):
                    r = self.chains[k - 1].links[i].radius + self.chains[l - 1].links[j].radius
                    if r > 0.0 and segment_distance(a[i], a[i + 1], b[j], b[j + 1]) < r:
                        raise SceneError(f"chains[{l}].initial.q: link {j + 1} of chain {l} overlaps link {i + 1} of "
                                         f"chain {k} as capsules at the start (their segments are closer than their "
                                         f"radii {r:g} m together)")

    # -- sizes and numbering ---------------------------------------------------
    @property
    def n(self) -> int:
        """The real links of all the chains together."""
        return sum(chain.n for chain in self.chains)

    @property
    def nq(self) -> int:
        """The full layout's length: every chain's n + 5."""
        return sum(chain.nq for chain in self.chains)

    @property
    def npoint(self) -> int:
        return sum(chain.n + 1 for chain in self.chains)

    def point_offset(self, k: int) -> int:
        """Chain k's (1-based) O_j is global point point_offset(k) + j."""
        return sum(chain.n + 1 for chain in self.chains[:k - 1])

    def state_offset(self, k: int) -> int:
        """Where chain k's full layout starts in the combined full layout."""
        return sum(chain.nq for chain in self.chains[:k - 1])

    def chain_of_link(self, i: int) -> tuple[int, int]:
        """(chain k, its link j) of global link i (named by its first point); SceneError if i is no link."""
        for k, chain in enumerate(self.chains, start=1):
            j = i - self.point_offset(k)
            if 1 <= j <= chain.n:
                return k, j
        raise SceneError(f"link {i}: no link starts at global point O_{i} (links are numbered by their first point: "
                         f"{', '.join(f'chain {k}: {self.point_offset(k) + 1}..{self.point_offset(k) + c.n}' for k, c in enumerate(self.chains, 1))})")

    def capsule_radius(self, i: int) -> float:
        """The capsule radius (m) of global link i."""
        k, j = self.chain_of_link(i)
        return self.chains[k - 1].links[j - 1].radius

    def point_radius(self, p: int) -> float:
        """The radius global point O_p touches a wall with (Scene.point_radius of its chain)."""
        for k, chain in enumerate(self.chains, start=1):
            j = p - self.point_offset(k)
            if 1 <= j <= chain.n + 1:
                return chain.point_radius(j)
        raise SceneError(f"point {p}: no such point (1..{self.npoint})")

    def full_coordinate_names(self) -> list[str]:
        """The combined full layout's names: each chain's, with its prefix."""
        return [chain_prefix(k) + name for k, chain in enumerate(self.chains, start=1)
                for name in coordinate_names(chain.n)]

    # -- what the box shares -----------------------------------------------------
    @property
    def links(self) -> tuple:
        """Every chain's links, one after the other (their order, not the global link numbers)."""
        return tuple(link for chain in self.chains for link in chain.links)

    @property
    def walls(self):
        return self.chains[0].walls

    @property
    def obstacles(self):
        return self.chains[0].obstacles

    @property
    def gravity(self) -> float:
        return self.chains[0].gravity

    @property
    def gravity_direction(self):
        return self.chains[0].gravity_direction

    @property
    def friction_velocity(self) -> float:
        return self.chains[0].friction_velocity

    @property
    def inputs(self) -> tuple:
        """Each chain's inputs, one after the other, named with its prefix ('c2.theta_2'): u = [u_1, u_2, ...]."""
        return tuple(chain_prefix(k) + name for k, chain in enumerate(self.chains, start=1) for name in chain.inputs)

    def input_coordinates(self) -> list[int]:
        """The combined full layout's index of each input's coordinate."""
        return [self.state_offset(k) + i for k, chain in enumerate(self.chains, start=1)
                for i in chain.input_coordinates()]

    @property
    def nu(self) -> int:
        return sum(chain.nu for chain in self.chains)

    @property
    def driven(self) -> bool:
        """Whether anything but gravity acts in flight on some chain: inputs, springs or dampers."""
        return any(chain.driven for chain in self.chains)

    @property
    def q0(self) -> tuple:
        return tuple(x for chain in self.chains for x in chain.q0)

    @property
    def qd0(self) -> tuple:
        return tuple(x for chain in self.chains for x in chain.qd0)

    @property
    def base_twists(self):
        """The base chart of the one chain whose theta_0 may move (codegen.combine allows one at most), else
        chain 1's."""
        return self.chains[0].base_twists

    @property
    def all_twists(self) -> tuple:
        return tuple(T for chain in self.chains for T in chain.all_twists)

    @property
    def warnings(self) -> list[str]:
        return [f"chain {k}: {w}" for k, chain in enumerate(self.chains, start=1) for w in chain.warnings]

    # -- parameters ----------------------------------------------------------------
    def parameter_map(self, k: int) -> list[int]:
        """Chain k's parameter vector gathered from the combined one: p_k[i] = p[parameter_map(k)[i]]."""
        names = self.parameter_names()
        return [names.index(self.combined_name(k, name)) for name in self.chains[k - 1].parameter_names()]

    def combined_name(self, k: int, name: str) -> str:
        """Chain k's parameter ``name`` in the combined vector: a box's as it is, the chain's own with its prefix."""
        return name if is_box_parameter(name) else chain_prefix(k) + name

    def stop_parameter_index(self, kind: str, joint: int) -> int:
        """The index in p of a joint stop's parameter (kind 'e_limit', 'lower', 'upper') of the combined layout's
        joint ``joint`` (chain k's joint j is state_offset(k) + j, as the combined layout numbers its stops)."""
        for k, chain in reversed(list(enumerate(self.chains, start=1))):
            if joint > self.state_offset(k):
                return self.parameter_names().index(chain_prefix(k) + parameter_name(kind, joint - self.state_offset(k)))
        raise SceneError(f"joint {joint}: no such joint")

    def parameter_names(self) -> list[str]:
        box = [name for name in self.chains[0].parameter_names() if is_box_parameter(name)]
        own = [chain_prefix(k) + name for k, chain in enumerate(self.chains, start=1)
               for name in chain.parameter_names() if not is_box_parameter(name)]
        return box + own

    def parameter_vector(self) -> np.ndarray:
        values = dict(zip(self.chains[0].parameter_names(), self.chains[0].parameter_vector().tolist()))
        for k, chain in enumerate(self.chains, start=1):
            values.update((chain_prefix(k) + name, value)
                          for name, value in zip(chain.parameter_names(), chain.parameter_vector().tolist())
                          if not is_box_parameter(name))
        return np.array([values[name] for name in self.parameter_names()], dtype=float)

    def parameter_index(self, kind: str, owner: int | str | None = None) -> int:
        """The index in p of parameter ``kind`` of ``owner``: a box's by its name ('g', 'wall' of 'x1_min'), a
        link's or joint's by its place among all the chains' links (1..n, chain 1's first)."""
        name = parameter_name(kind, owner)
        if isinstance(owner, int) and not isinstance(owner, bool):
            for k, chain in enumerate(self.chains, start=1):
                if owner <= chain.n:
                    name = chain_prefix(k) + parameter_name(kind, owner)
                    break
                owner -= chain.n
        names = self.parameter_names()
        if name not in names:
            raise SceneError(f"{name}: this scene has no such parameter (it has {', '.join(names)})")
        return names.index(name)

    # -- contacts after the kernels' ---------------------------------------------------
    def cross_link_pairs(self) -> list[LinkPair]:
        """Every pair of links of different chains that can strike each other as capsules (radii adding up to more
        than 0), in global link numbers."""
        pairs = []
        for k, a in enumerate(self.chains, start=1):
            for l in range(k + 1, len(self.chains) + 1):
                b = self.chains[l - 1]
                for i, link_i in enumerate(a.links, start=1):
                    for j, link_j in enumerate(b.links, start=1):
                        r = link_i.radius + link_j.radius
                        if r > 0.0:
                            pairs.append(LinkPair(self.point_offset(k) + i, self.point_offset(l) + j, r,
                                                  self.link_restitution, self.link_friction))
        return pairs

    def rowless_contacts(self) -> list:
        """Each chain's link pairs, then the pairs across chains, their end contacts (pair_ends), then each chain's
        links on the obstacles (global link numbers): the model's table after the kernels' walls and stops."""
        pairs, obstacles = [], []
        for k, chain in enumerate(self.chains, start=1):
            shift = self.point_offset(k)
            pairs += [LinkPair(c.i + shift, c.j + shift, c.radius, c.restitution, c.friction)
                      for c in chain.link_contacts()]
            obstacles += [ObstacleContact(c.i + shift, c.obstacle, c.index, c.radius, c.end)
                          for c in chain.obstacle_contacts()]
        pairs += self.cross_link_pairs()
        return pairs + pair_ends(pairs, self.capsule_radius) + obstacles


def chains_from_dict(data: dict, default_name: str, folder, box_keys: tuple[str, ...]) -> Chains:
    """A scene file's [[chains]] (docs/scenes.md, "Several chains"): each entry with the keys of a one-chain scene's
    chain (CHAIN_KEYS), the rest of the file (``box_keys``) the box's, given to every chain."""
    items = data["chains"]
    if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
        raise SceneError("chains: expected an array of tables [[chains]], one per chain")
    extra = sorted(set(data) - set(box_keys) - {"chains", "name", "description"})
    if extra:
        raise SceneError(f"{extra[0]}: a scene with [[chains]] gives it per chain ([[chains]] {extra[0]}), or not at "
                         f"all (top-level keys allowed with chains: {', '.join(('name', 'description', 'chains') + box_keys)})")
    name = data.get("name", default_name)
    box = {key: data[key] for key in box_keys if key in data}
    scenes = []
    for k, item in enumerate(items, start=1):
        unknown = sorted(set(item) - set(CHAIN_KEYS))
        if unknown:
            raise SceneError(f"chains[{k}].{unknown[0]}: unknown key (a chain has {', '.join(CHAIN_KEYS)}; the box's "
                             "keys go at the top of the file)")
        if "links" not in item:
            raise SceneError(f"chains[{k}].links: each chain needs its [[chains.links]]")
        merged = dict(box, **item, name=f"{name}_c{k}" if isinstance(name, str) else name)
        assert set(merged) <= set(TOP_KEYS)
        try:
            scenes.append(scene_from_dict(merged, default_name=f"{default_name}_c{k}", folder=folder))
        except SceneError as exc:
            if str(exc).startswith(tuple(box_keys)):        # the box's own field: named as it is
                raise
            raise SceneError(f"chains[{k}].{exc}") from None
    restitution = data.get("restitution", 1.0)
    e = restitution.get("links", restitution.get("default", 1.0)) if isinstance(restitution, dict) else restitution
    friction = data.get("friction", 0.0)
    c_f = friction.get("links", 0.0) if isinstance(friction, dict) else 0.0
    return Chains(name=name, chains=tuple(scenes), description=str(data.get("description", "")), link_restitution=e,
                  link_friction=c_f)


CHAIN_KEYS = ("links", "initial", "base", "contacts", "inputs")
