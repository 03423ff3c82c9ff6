"""Leave out what a scene does not need: the layout of a generated model, decided from the scene.

A :class:`Layout` says which generalised coordinates the model keeps (the rest are held at fixed
values), which (point, wall) contacts and Jacobian rows it has, and which parameters are built in as
zeros.  ``layout_for(scene, specialise=False)`` is the general model: all n + 5 coordinates, every
wall of the scene, every parameter at run time.  With ``specialise=True``:

* **planar scenes** -- every real joint axis parallel to the same box axis X1 or X3 (theta_0 = 0 and
  theta_-1 a multiple of pi/2 with the default base twists; T_2..T_n rotations about z), no link with a
  centre of mass off the plane or a product of inertia coupling the plane to its normal, gravity in the plane, every
  fixed obstacle symmetric about the plane (its push stays in it), and no out-of-plane velocity at the start (as in the paper's case 1): theta_-1, theta_0 and the out-of-plane
  translation are held fixed, n + 2 coordinates instead of n + 5, and walls across the normal are
  dropped (no point ever reaches them);
* **zero parameters** -- g, J components, centre-of-mass offsets or products of inertia that are
  exactly 0 in the scene are built in as 0, so their terms vanish symbolically;
* **walls and points** -- only the (point, wall) pairs of the scene get gap functions and rows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scene import (OBSTACLE_GEOMETRY_KINDS, JointStop, RigidLink, Scene, SceneError, contact_points,
                    coordinate_names, frames, parameter_name, split_parameter_name, stop_rows)

ANGLE_SNAP = 1e-12       # an angle within this of a multiple of pi/2 counts as exactly that multiple


@dataclass(frozen=True)
class Layout:
    free: tuple[int, ...]                       # full-state indices (Eq. 13) kept as coordinates
    fixed: tuple[tuple[int, float], ...]        # (full-state index, value) held constant
    contacts: tuple                             # (point, Wall) pairs with a gap function
    contact_rows: tuple                         # (point, axis) Jacobian rows the contacts need
    zero_params: tuple[str, ...]                # parameters built in as 0
    notes: tuple[str, ...]                      # what was left out and why (--explain)
    planar_normal: int | None = None            # 0 or 2 for a planar model, else None
    held: tuple[int, ...] = ()                  # full-state indices the base holds (scene.base; among ``fixed``)
    held_params: tuple[str, ...] = ()           # obstacle geometry a planar model holds at the scene's values

    @property
    def nq(self) -> int:
        return len(self.free)

    @property
    def nq_full(self) -> int:
        return len(self.free) + len(self.fixed)

    def reduce(self, full) -> np.ndarray:
        """Full-layout vector (n + 5) -> the model's coordinates."""
        return np.asarray(full, dtype=float)[list(self.free)]

    def expand(self, reduced, velocity: bool = False) -> np.ndarray:
        """The model's coordinates -> full layout; fixed entries get their value (0 for velocities)."""
        reduced = np.asarray(reduced, dtype=float)
        if not self.fixed:
            return reduced.copy()
        full = np.zeros(reduced.shape[:-1] + (len(self.free) + len(self.fixed),))
        full[..., self.free] = reduced
        if not velocity:
            for index, value in self.fixed:
                full[..., index] = value
        return full


def layout_for(scene: Scene, specialise: bool = True) -> Layout:
    """The model's layout: the coordinates the base holds (scene.base: a pinned or fixed base) are never coordinates;
    with ``specialise`` the rest of what the scene does not need is left out too (the module's docstring)."""
    if not isinstance(scene, Scene):                  # several chains (codegen.scene.Chains): each chain's, stacked
        return chains_layout(scene, specialise)
    held = scene.base.held(scene.n)
    names = coordinate_names(scene.n)
    base_note = _base_note(scene, held, names)
    if not specialise:
        fixed = tuple(held.items())
        free = tuple(i for i in range(scene.nq) if i not in held)
        return Layout(free, fixed, tuple(scene.contacts()), tuple(scene.contact_rows()), (),
                      base_note + ("general model: no specialisation asked for (every coordinate the base leaves, "
                                   "all walls, every parameter at run time)",), None, tuple(held))
    notes = list(base_note)
    normal, reason = planar_normal(scene)
    n = scene.n
    if normal is None:
        fixed = tuple(held.items())
        free = tuple(i for i in range(scene.nq) if i not in held)
        notes.append(f"kept all {len(free)} coordinates{' the base leaves' if held else ''}: not planar ({reason})")
        walls = scene.walls
    else:
        planar_index = tuple(i for i in (0, 1, n + 2 + normal) if i not in held)
        values = dict(held)
        values.update((i, snap_angle(scene.q0[i]) if i < 2 else scene.q0[i]) for i in planar_index)
        fixed = tuple(sorted(values.items()))
        free = tuple(i for i in range(scene.nq) if i not in values)
        if planar_index:
            notes.append(f"planar: every real joint axis is parallel to X{normal + 1} and nothing starts out of the "
                         f"plane, so {', '.join(names[i] for i in planar_index)} are held at "
                         f"{', '.join(f'{values[i]:.12g}' for i in planar_index)}: {len(free)} coordinates instead of "
                         f"{scene.nq - len(held)} (results are mapped back to the full layout)")
        else:
            notes.append(f"planar: every real joint axis is parallel to X{normal + 1}, and the base already holds "
                         "every out-of-plane coordinate")
        across = [w for w in scene.walls if w.axis == normal]
        walls = tuple(w for w in scene.walls if w.axis != normal)
        if across:
            notes.append(f"walls {', '.join(w.name for w in across)} dropped: every point stays at "
                         f"X{normal + 1} = {scene.q0[n + 2 + normal]:g}, inside them")
    contacts = tuple((p, w) for w in walls for p in w.points)
    tangents = {(p, axis) for p, w in contacts if w.friction > 0.0 for axis in range(3)
                if axis != w.axis and axis != normal}                  # rows of the friction forces
    rows = tuple(sorted({(p, w.axis) for p, w in contacts} | tangents))
    notes.append(f"contacts: {len(contacts)} (point, wall) gap functions and {len(rows)} Jacobian rows, only "
                 "for the walls and points of the scene" + (" (with the tangential rows of the walls with friction)"
                                                            if tangents else ""))
    stops = tuple(scene.stops())
    if stops:
        contacts += stops
        rows += tuple(stop_rows(stops))
        notes.append(f"joint stops: {len(stops)} ({', '.join(stop.name for _, stop in stops)}), after the walls' "
                     "contacts, with a row of the identity each joint")
    library = ("wall", "e", "e_limit", "friction", *OBSTACLE_GEOMETRY_KINDS)     # read by the C library, not kernels
    zero_params = tuple(name for name, value in zip(scene.parameter_names(), scene.parameter_vector())
                        if value == 0.0 and split_parameter_name(name)[0] not in library)
    if zero_params:
        notes.append(f"zero parameters built in (their terms vanish; they cannot be changed at run time): "
                     f"{', '.join(zero_params)}")
    else:
        notes.append("no parameter is zero: all stay in the runtime array p")
    held_params = () if normal is None else planar_obstacle_params(scene, normal)
    if held_params:
        notes.append(f"obstacle geometry held at the scene's values (the obstacles stay symmetric about the chain's "
                     f"plane; the rest of their geometry stays in p): {', '.join(held_params)}")
    return Layout(free, fixed, contacts, rows, zero_params, tuple(notes), normal, tuple(held), held_params)


def planar_obstacle_params(scene: Scene, normal: int) -> tuple[str, ...]:
    """The obstacles' geometry parameters a planar model (normal axis X_normal+1) holds at the scene's values, so
    that every obstacle stays symmetric about the chain's plane (obstacle_in_plane): a sphere's centre and a bar's
    ends along the normal, a box's centre along it and the row and column of its rotation that map an axis of the
    box onto the normal, a plane's normal's component along it."""
    axis = "xyz"[normal]
    names = []
    for o in scene.obstacles:
        if o.kind == "sphere":
            kinds = [f"center_{axis}"]
        elif o.kind == "capsule":
            kinds = [f"a_{axis}", f"b_{axis}"]
        elif o.kind == "box":
            R = np.array(o.box_rotation)
            k = int(np.argmax(np.abs(R[normal])))               # the box's axis along the normal
            kinds = [f"center_{axis}"] + [f"rotation_{normal + 1}{j + 1}" for j in range(3)] \
                + [f"rotation_{i + 1}{k + 1}" for i in range(3) if i != normal]
        else:
            kinds = [f"normal_{axis}"]
        names += [parameter_name(kind, o.name) for kind in kinds]
    return tuple(names)


def _base_note(scene: Scene, held: dict[int, float], names: list[str]) -> tuple[str, ...]:
    """What the base leaves out, for --explain (nothing for a free base)."""
    base = scene.base
    if not held:
        return ()
    kept = scene.nq - len(held)
    where = f"O_1 held at ({', '.join(f'{x:.12g}' for x in base.point)})"
    if base.kind == "pinned" and base.joint == "spherical":
        what = f"{where}, link 1 turning freely about it"
    elif base.kind == "pinned":
        q = np.zeros(scene.nq)
        q[:2] = held[0], held[1]
        zero = frames(scene, q)[2][:, 0]                     # x_1 at theta_1 = 0
        what = (f"{where}, link 1 turning about the axis ({', '.join(f'{x:.6g}' for x in base.axis)}); theta_1 = 0 "
                f"points it along ({', '.join(f'{0.0 if abs(x) < 1e-15 else x:.6g}' for x in zero)})")
    else:
        what = f"{where}, link 1 welded to the box"
    return (f"base {base.label}: {what}, so {', '.join(names[i] for i in held)} are not coordinates (held at "
            f"{', '.join(f'{v:.12g}' for v in held.values())}, zero rates: the base does no work): {kept} coordinates "
            f"instead of {scene.nq}; the points {', '.join(f'O_{p}' for p in base.held_points())} it holds touch no "
            "wall",)


def snap_angle(value: float) -> float:
    quarter = round(value / (math.pi / 2))
    if abs(value - quarter * math.pi / 2) > ANGLE_SNAP:
        raise ValueError(f"angle {value!r} is not a multiple of pi/2")
    return quarter * math.pi / 2


def planar_normal(scene: Scene) -> tuple[int | None, str]:
    """The box axis (0 for X1, 2 for X3) normal to the plane the chain stays in, or (None, reason)."""
    q, qd, n = np.array(scene.q0), np.array(scene.qd0), scene.n
    for k, T in enumerate(scene.twists, start=2):
        if tuple(T[i][2] for i in range(3)) != (0.0, 0.0, 1.0):
            return None, f"the twist T_{k} tilts joint {k} out of the plane"
    for i in (0, 1):
        try:
            snap_angle(q[i])
        except ValueError:
            return None, f"theta_{i - 1} = {q[i]:.6g} is not a multiple of pi/2"
    q_snapped = q.copy()
    q_snapped[:2] = [snap_angle(q[0]), snap_angle(q[1])]
    axis = frames(scene, q_snapped)[2][:, 2]                 # z_1 in the reference frame
    normal = int(np.argmax(np.abs(axis)))
    if abs(abs(axis[normal]) - 1.0) > 1e-12 or normal == 1:
        return None, "the joint axes are not parallel to X1 or X3"
    if qd[0] != 0.0 or qd[1] != 0.0 or qd[n + 2 + normal] != 0.0:
        return None, f"theta_-1, theta_0 or X{normal + 1} has a non-zero initial velocity"
    if scene.gravity_direction[normal] != 0.0:
        return None, f"gravity (gravity_direction) has a component along X{normal + 1}, out of the plane"
    out_of_plane = {"theta_-1", "theta_0", f"X{normal + 1}"} & set(scene.inputs)
    if out_of_plane:
        return None, f"an input drives {', '.join(sorted(out_of_plane))} out of the plane"
    for i, link in enumerate(scene.links, start=1):
        if isinstance(link, RigidLink):
            I = link.inertia
            if link.com[2] != 0.0 or I[0][2] != 0.0 or I[1][2] != 0.0:
                return None, f"link {i} has its centre of mass or a product of inertia off the plane"
    level = float(contact_points(scene, q_snapped)[0, normal])
    for o in scene.obstacles:
        if not obstacle_in_plane(o, normal, level):
            return None, f"the obstacle {o.name} is not symmetric about the chain's plane X{normal + 1} = {level:g}"
    return normal, ""


def obstacle_in_plane(o, normal: int, level: float) -> bool:
    """Whether an obstacle's push on a chain in the plane X_normal = level stays in that plane: a capsule's ends in
    it, a box's centre in it with an axis along its normal, a plane's normal in it."""
    if o.kind == "plane":
        return o.normal[normal] == 0.0
    if o.kind == "box":
        R = np.array(o.box_rotation)
        return o.a[normal] == level and any(abs(abs(R[normal, k]) - 1.0) <= 1e-12 for k in range(3))
    return all(end[normal] == level for end in o.segment)


def check_not_singular(scene: Scene, layout: Layout) -> None:
    """A clear error for models whose inertia matrix is singular by construction (zero inertia)."""
    if layout.planar_normal is not None or not {0, 1, 2} <= set(layout.free):
        return                                              # rotation about the links is not a coordinate
    for i, link in enumerate(scene.links, start=1):
        if link.kind == "line" and link.J[0] == 0.0 and scene.n == 1:
            raise SceneError(f"links[{i}].J: Jxx = 0 leaves the spatial single link's rotation about its own "
                             "axis with no inertia (the inertia matrix is singular); give Jxx > 0 or make the "
                             "scene planar")


def chains_layout(scene, specialise: bool = True) -> Layout:
    """The combined model's layout: each chain's (codegen.specialise.layout_for) shifted into the stacked full
    layout; its contacts' points (walls) and joints (stops) in global numbers."""
    free, fixed, contacts, rows, zeros, notes, held, held_params = [], [], [], [], [], [], [], []
    normals = set()
    for k, chain in enumerate(scene.chains, start=1):
        layout = layout_for(chain, specialise)
        off, poff = scene.state_offset(k), scene.point_offset(k)
        free += [off + i for i in layout.free]
        fixed += [(off + i, v) for i, v in layout.fixed]
        held += [off + i for i in layout.held]
        contacts += [(_shift_contact(point, wall, off, poff)) for point, wall in layout.contacts]
        rows += [(off + point, axis) if axis == "theta" else (poff + point, axis) for point, axis in layout.contact_rows]
        zeros += [scene.combined_name(k, name) for name in layout.zero_params]
        held_params += [scene.combined_name(k, name) for name in layout.held_params]
        notes += [f"chain {k}: {note}" for note in layout.notes]
        normals.add(layout.planar_normal)
    normal = normals.pop() if len(normals) == 1 else None
    return Layout(tuple(free), tuple(fixed), tuple(contacts), tuple(rows), tuple(dict.fromkeys(zeros)), tuple(notes),
                  normal, tuple(held), tuple(dict.fromkeys(held_params)))


def _shift_contact(point, wall, off: int, poff: int):
    """A chain's (point, Wall) contact in global point numbers; a stop's (joint k, JointStop) with k shifted by the
    chain's full-layout offset (theta_k sits at full index k + 1)."""
    return (off + point, wall) if isinstance(wall, JointStop) else (poff + point, wall)
