"""The allowed values of a model's runtime parameters, described once.

Every entry p[i] of a parameter vector (layout ``Scene.parameter_names()``) has a range by its kind (a length, a
mass, a restitution, ...): finite, within [lo, hi], and 0 or at least the smallest normal double in magnitude.  A
few entries also have a relation to others: a wall's max lies above its min, a joint's upper limit above its lower
one, and a rigid link's six inertia entries form a physical inertia.  The ranges are the scene loader's
(codegen.scene), so a scene file and a changed parameter vector are held to the same limits.

``parameter_rules`` lists the rules of a scene's vector, one per entry (and, for a generated model, the values it
has built in: ``zero_params`` of its layout, or all of them with ``bake_params``).  From that one list come

* the Python check of a vector, ``check_vector`` (which ``simulate()`` applies to its ``p`` overrides);
* the C check: the table ``NAME_model.parameter_info`` (each parameter's name, range and rule in words) and the
  function ``NAME_check_parameters`` in the generated NAME.c (templates/model.c.j2), which ``gac_sim_init`` and
  the FMU call;
* the FMU's ``min`` and ``max`` of every parameter (codegen/fmu.py).

Plain data: no sympy, no jinja2, no runtime import.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from .scene import (COORDINATE_MAX, FRICTION_MAX, GRAVITY_MAX, INERTIA_MAX, LENGTH_RANGE, MASS_RANGE,
                    OBSTACLE_PARAMETERS, ROTATION_TOL, STIFFNESS_MAX, RigidLink, Scene, SceneError, parameter_name,
                    rotation_defects, split_parameter_name)


@dataclass(frozen=True)
class Range:
    """The values a kind of parameter may take: lo <= value <= hi, in words as messages give them."""

    lo: float
    hi: float
    text: str


_ANGLE = Range(-COORDINATE_MAX, COORDINATE_MAX, f"must be within [-{COORDINATE_MAX:g}, {COORDINATE_MAX:g}] rad")
_POSITION = Range(-COORDINATE_MAX, COORDINATE_MAX, f"must be within [-{COORDINATE_MAX:g}, {COORDINATE_MAX:g}] m")
_RESTITUTION = Range(0.0, 1.0, "restitution must be in [0, 1]")
_INERTIA_PER_LENGTH = Range(0.0, INERTIA_MAX, f"must be >= 0 and <= {INERTIA_MAX:g} kg m")
_MOMENT = Range(0.0, INERTIA_MAX, f"must be >= 0 and <= {INERTIA_MAX:g} kg m^2")
_PRODUCT = Range(-INERTIA_MAX, INERTIA_MAX, f"must be within [-{INERTIA_MAX:g}, {INERTIA_MAX:g}] kg m^2")
_SIZE = Range(*LENGTH_RANGE, f"must be in [{LENGTH_RANGE[0]:g}, {LENGTH_RANGE[1]:g}] m (> 0)")
_DIRECTION = Range(-2.0, 2.0, "must be within [-2, 2]")      # an entry of a rotation or a unit normal

# kind of parameter (parameter_kind) -> its range
RANGES = {
    "g": Range(-GRAVITY_MAX, GRAVITY_MAX, "must be within [-1e6, 1e6] m/s^2"),
    "l": Range(*LENGTH_RANGE, f"must be in [{LENGTH_RANGE[0]:g}, {LENGTH_RANGE[1]:g}] m"),
    "mu": Range(*MASS_RANGE, f"must be in [{MASS_RANGE[0]:g}, {MASS_RANGE[1]:g}] kg/m"),
    "m": Range(*MASS_RANGE, f"must be in [{MASS_RANGE[0]:g}, {MASS_RANGE[1]:g}] kg"),
    "Jxx": _INERTIA_PER_LENGTH, "Jyy": _INERTIA_PER_LENGTH, "Jzz": _INERTIA_PER_LENGTH,
    "cx": _POSITION, "cy": _POSITION, "cz": _POSITION,
    "Ixx": _MOMENT, "Iyy": _MOMENT, "Izz": _MOMENT, "Ixy": _PRODUCT, "Ixz": _PRODUCT, "Iyz": _PRODUCT,
    "wall": _POSITION,
    "e": _RESTITUTION,
    "friction": Range(0.0, FRICTION_MAX, f"the Coulomb coefficient must be in [0, {FRICTION_MAX:g}]"),
    "stiffness": Range(0.0, STIFFNESS_MAX, f"must be >= 0 and <= {STIFFNESS_MAX:g} N m/rad"),
    "rest_angle": _ANGLE,
    "damping": Range(0.0, STIFFNESS_MAX, f"must be >= 0 and <= {STIFFNESS_MAX:g} N m s/rad"),
    "lower": _ANGLE, "upper": _ANGLE,
    "e_limit": _RESTITUTION,
    # an obstacle's geometry (codegen.scene.OBSTACLE_PARAMETERS)
    **{kind: _POSITION for kind in ("center_x", "center_y", "center_z", "a_x", "a_y", "a_z", "b_x", "b_y", "b_z",
                                    "point_x", "point_y", "point_z")},
    **{kind: _SIZE for kind in ("radius", "half_x", "half_y", "half_z")},
    **{kind: _DIRECTION for kind in OBSTACLE_PARAMETERS["box"][6:] + OBSTACLE_PARAMETERS["plane"][3:]},
}
ROTATION_WORDS = f"a proper rotation (orthonormal within {ROTATION_TOL:g}, det +1 within {ROTATION_TOL:g})"
UNIT_WORDS = f"a unit vector (length 1 within {ROTATION_TOL:g})"

SMALLEST_NORMAL = sys.float_info.min          # a nonzero value below this in magnitude is refused
INERTIA_NAMES = RigidLink.param_names[5:]     # Ixx, Iyy, Izz, Ixy, Ixz, Iyz: consecutive in p
INERTIA_WORDS = "a physical inertia (positive semi-definite, principal moments obeying the triangle inequality)"


def parameter_kind(name: str) -> str:
    """The kind of a parameter, the key of RANGES: 'e_x2_min' -> 'e', 'e_limit_3' -> 'e_limit', 'wall_x1_max' ->
    'wall', 'Jxx_2' -> 'Jxx', 'g' -> 'g'."""
    return split_parameter_name(name)[0]


@dataclass(frozen=True)
class Rule:
    """What p[index] may be: its range (lo = hi for a value built into the model), and the relation it is named by
    when that fails: above >= 0, p[index] > p[above]; inertia_of = i > 0, p[index .. index + 5] = Ixx_i .. Iyz_i
    a physical inertia; rotation_of = an obstacle's name, p[index .. index + 8] its rotation (row-major) a proper
    rotation; unit_of = an obstacle's name, p[index .. index + 2] its normal a unit vector."""

    index: int
    name: str
    lo: float
    hi: float
    range_text: str
    above: int = -1
    above_name: str = ""
    inertia_of: int = 0
    rotation_of: str = ""
    unit_of: str = ""

    @property
    def text(self) -> str:
        """The whole rule in words, its relation included (the C table's, the FMU's messages)."""
        words = self.range_text
        if self.above >= 0:
            words += f", and > {self.above_name}"
        if self.inertia_of:
            i = self.inertia_of
            words += f"; {parameter_name('Ixx', i)} .. {parameter_name('Iyz', i)} together {INERTIA_WORDS}"
        if self.rotation_of:
            o = self.rotation_of
            words += f"; {parameter_name('rotation_11', o)} .. {parameter_name('rotation_33', o)} together {ROTATION_WORDS}"
        if self.unit_of:
            o = self.unit_of
            words += f"; {parameter_name('normal_x', o)} .. {parameter_name('normal_z', o)} together {UNIT_WORDS}"
        return words


def parameter_rules(scene: Scene, zero_params=(), bake_params: bool = False, held_params=()) -> list[Rule]:
    """The rule of every entry of the scene's parameter vector, in its order.  ``zero_params``: the parameters a
    generated model has built in as 0 (its layout's); ``bake_params``: the model has every parameter built in as the
    scene's value; ``held_params``: the obstacle geometry a planar model holds at the scene's values (its layout's).
    A built-in value may not change: its range is that value alone."""
    names = scene.parameter_names()
    values = scene.parameter_vector().tolist()
    rules = []
    for index, (name, value) in enumerate(zip(names, values)):
        kind, owner = split_parameter_name(name)
        lo, hi, text = RANGES[kind].lo, RANGES[kind].hi, RANGES[kind].text
        if bake_params:
            lo = hi = value
            text = f"built into this model as a constant ({value!r}; generated with bake_params)"
        elif name in zero_params:
            lo = hi = 0.0
            text = "built into this model as 0 (the scene's value, so its terms were left out; the general model " \
                   "takes other values)"
        elif name in held_params:
            lo = hi = value
            text = (f"held at the scene's value {value!r} by this planar model (the obstacle stays symmetric about "
                    "the chain's plane; the general model takes other values)")
        partner = ""                                # the parameter this one must exceed
        prefix = name.partition(".")[0] + "." if "." in name else ""          # a chain's (codegen.scene.Chains)
        if kind == "wall" and owner.endswith("_max"):
            partner = parameter_name("wall", owner[:-len("_max")] + "_min")     # wall_x1_max > wall_x1_min
        elif kind == "upper":
            partner = prefix + parameter_name("lower", owner)                  # upper_k > lower_k
        if partner in names:
            rules.append(Rule(index, name, lo, hi, text, above=names.index(partner), above_name=partner))
        elif kind == "Ixx":
            rules.append(Rule(index, name, lo, hi, text, inertia_of=owner))
        elif kind == "rotation_11":
            rules.append(Rule(index, name, lo, hi, text, rotation_of=owner))
        elif kind == "normal_x":
            rules.append(Rule(index, name, lo, hi, text, unit_of=owner))
        else:
            rules.append(Rule(index, name, lo, hi, text))
    return rules


def check_vector(rules: list[Rule], p, changed=None) -> None:
    """Raise SceneError naming the first parameter of ``p`` that breaks its rule: every entry in its range, then the
    relations, in the order of the vector (the order NAME_check_parameters checks them in).  ``changed``: the names
    whose values may differ from the scene's (the others were checked when the scene was built; default: all)."""
    p = np.asarray(p, dtype=float)
    if p.shape != (len(rules),):
        raise SceneError(f"p: expected {len(rules)} values ({', '.join(r.name for r in rules)}), got shape {p.shape}")
    value = p.tolist()
    changed = None if changed is None else set(changed)
    for rule in rules:
        if changed is not None and rule.name not in changed:
            continue
        x = value[rule.index]
        if not rule.lo <= x <= rule.hi:
            raise SceneError(f"p[{rule.name}]: {rule.range_text}, got {x!r}")
        if x != 0.0 and abs(x) < SMALLEST_NORMAL:
            raise SceneError(f"p[{rule.name}]: {x!r} is below the smallest normal double ({SMALLEST_NORMAL:.3g}); "
                             "give 0 or a larger magnitude")
    for rule in rules:
        if rule.above >= 0 and not value[rule.index] > value[rule.above]:
            raise SceneError(f"p[{rule.name}]: must be > p[{rule.above_name}] = {value[rule.above]!r}, "
                             f"got {value[rule.index]!r}")
        if rule.rotation_of:
            check_rotation(value[rule.index:rule.index + 9], rule.name.rpartition("rotation_11_")[0], rule.rotation_of)
        if rule.unit_of:
            check_unit(value[rule.index:rule.index + 3], rule.name.rpartition("normal_x_")[0], rule.unit_of)
        if not rule.inertia_of:
            continue
        if changed is None or changed & {parameter_name(key, rule.inertia_of) for key in INERTIA_NAMES}:
            check_inertia(value[rule.index:rule.index + 6], rule.inertia_of)


def check_rotation(entries, prefix: str, obstacle: str) -> None:
    """A box's rotation (row-major) a proper rotation, the scene loader's test (codegen.scene._rotation), or
    SceneError naming its parameters (``prefix``: a chain's, none for one chain)."""
    names = f"p[{prefix}{parameter_name('rotation_11', obstacle)} .. {prefix}{parameter_name('rotation_33', obstacle)}]"
    off, det = rotation_defects(entries)
    if not off <= ROTATION_TOL:
        raise SceneError(f"{names}: the rotation of box {obstacle} must be {ROTATION_WORDS}; R^T R departs from I by "
                         f"{off:.3g}")
    if not abs(det - 1.0) <= ROTATION_TOL:
        raise SceneError(f"{names}: the rotation of box {obstacle} must be {ROTATION_WORDS}; got det {det:.6g} "
                         "(a reflection: swap two columns)")


def check_unit(entries, prefix: str, obstacle: str) -> None:
    """A plane's normal a unit vector (codegen.scene's test), or SceneError naming its parameters."""
    length = float(np.sqrt(sum(x * x for x in entries)))
    if not abs(length - 1.0) <= ROTATION_TOL:
        raise SceneError(f"p[{prefix}{parameter_name('normal_x', obstacle)} .. {prefix}"
                         f"{parameter_name('normal_z', obstacle)}]: the normal of plane {obstacle} must be "
                         f"{UNIT_WORDS}, got length {length:.17g}")


def check_inertia(entries, link: int) -> None:
    """Ixx, Iyy, Izz, Ixy, Ixz, Iyz of ``link`` a physical inertia (RigidLink.validate's test), or SceneError."""
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = entries
    try:
        RigidLink(1.0, 1.0, (0.0, 0.0, 0.0), ((Ixx, Ixy, Ixz), (Ixy, Iyy, Iyz), (Ixz, Iyz, Izz))).validate("")
    except SceneError as exc:
        raise SceneError(f"p[Ixx_{link} .. Iyz_{link}]: the inertia of link {link}{str(exc)[len('.inertia'):]}") \
            from None
