"""Chains to and from URDF (the Unified Robot Description Format of ROS).

A URDF serial chain maps onto the paper's chain as follows.  The root link (the one that is no joint's child)
is link 1, floating: its pose is the base chart (theta_-1, theta_0, theta_1, X1, X2, X3).  Each revolute or
continuous joint is joint k = 2..n, with its URDF angle as theta_k (same zero, same sign).  The link frames of
the model are the URDF link frames turned by a constant rotation A_k (same origins):

    x_k  towards the next joint's origin (link k's length l_k is the distance to it; for the last link, to the
         origin of a fixed child link such as a tool tip, or the given tip length along the last link's x)
    z_k  the axis of joint k (for the root link, the axis of joint 2 where it is normal to x_1)

so that the twist of joint k is T_k = A_(k-1)^T E_k A_k (E_k: the joint origin's rpy rotation), each link's
centre of mass is A_k^T (c - s_k a_k) and its inertia about it A_k^T R I R^T A_k (c, R, I: the URDF <inertial>).
A next joint offset along a joint's axis is taken up by sliding the joint's origin O_k along its axis by s_k (the
common normal of Denavit-Hartenberg, from the tip down): the kinematics and the inertia stay the URDF's, and the
contact point O_k is that point of the joint's axis.  Refused are trees, prismatic, planar or floating joints, mimic joints and joint friction (not in this model).  A root
held to a link named ``world`` by a fixed joint is a fixed base (codegen.scene.Base): O_1 at the joint's origin, link
1's frame E A_1 (E: the joint's rpy); by a floating joint, a free one; by a revolute or continuous joint, a pinned
revolute base: its axis E a (a: the joint's <axis> in the root's frame) is the root's z_1, O_1 the point of that axis
where the root reaches the next joint normal to it (slid along the axis as the other joints are), and theta_1 the
joint's URDF angle plus a constant, codegen.scene.urdf_mount_offset (theta_1 counts from the base chart's zero direction about the
axis, the URDF angle from the root's x at the joint's origin); such a joint may not have stops or a damper (the model's
base has neither).
<limit lower upper> become the joint's stops, <dynamics damping> its damper; effort and velocity limits
describe actuators and are not part of the dynamics.

``urdf_links`` gives the link tables of a scene file ([[links]] entries); ``scene_to_urdf`` writes a scene's
chain as URDF.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from .errors import SceneError

PERPENDICULAR_TOL = 1e-9      # |cos| between a joint axis and the direction to the next joint
SNAP = 1e-14                  # twist entries this close to 0 or +-1 are made exact (planar chains stay planar)


# ---------------------------------------------------------------------------------------------------
# rotations
# ---------------------------------------------------------------------------------------------------
def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def matrix_rpy(R) -> tuple[float, float, float]:
    """roll, pitch, yaw of a rotation matrix (inverse of rpy_matrix; at pitch = +-90 degrees yaw = 0), checked by
    rebuilding R (ValueError for a matrix that is not a rotation)."""
    R = np.asarray(R, dtype=float)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) > 1e-9:
        roll, yaw = math.atan2(R[2, 1], R[2, 2]), math.atan2(R[1, 0], R[0, 0])
    else:
        roll, yaw = math.atan2(-R[1, 2], R[1, 1]), 0.0
    if np.max(np.abs(rpy_matrix(roll, pitch, yaw) - R)) >= 1e-12:
        raise ValueError("matrix_rpy: not a rotation")
    return roll, pitch, yaw


def _snap(M: np.ndarray) -> np.ndarray:
    M = M.copy()
    for value in (0.0, 1.0, -1.0):
        M[np.abs(M - value) < SNAP] = value
    return M


def _frame(x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The rotation with columns x, z x x, z (x and z unit and normal)."""
    return np.column_stack([x, np.cross(z, x), z])


# ---------------------------------------------------------------------------------------------------
# URDF -> link tables
# ---------------------------------------------------------------------------------------------------
def _floats(element, attribute: str, default: str, where: str, count: int = 3) -> np.ndarray:
    text = default if element is None else element.get(attribute, default)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise SceneError(f"{where}: {attribute}={text!r}: expected {count} finite numbers")
    return np.array(values)


def _origin(element, where: str) -> tuple[np.ndarray, np.ndarray]:
    origin = element.find("origin")
    return (_floats(origin, "xyz", "0 0 0", f"{where} <origin>"),
            rpy_matrix(*_floats(origin, "rpy", "0 0 0", f"{where} <origin>")))


def _inertial(link, where: str) -> tuple[float, np.ndarray, np.ndarray]:
    """mass, centre of mass and inertia about it, in the URDF link frame."""
    inertial = link.find("inertial")
    if inertial is None:
        raise SceneError(f"{where}: no <inertial>; every link of the chain needs a mass and an inertia")
    mass = _floats(inertial.find("mass"), "value", "", f"{where} <mass>", 1)[0]
    c, R = _origin(inertial, f"{where} <inertial>")
    tensor = inertial.find("inertia")
    if tensor is None:
        raise SceneError(f"{where}: <inertial> has no <inertia>")
    values = {key: _floats(tensor, key, "", f"{where} <inertia>", 1)[0]
              for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    I = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                  [values["ixy"], values["iyy"], values["iyz"]],
                  [values["ixz"], values["iyz"], values["izz"]]])
    return float(mass), c, R @ I @ R.T


WORLD = "world"      # the link a URDF names for the world: a root fixed to it is a fixed base


MOUNTS = ("fixed", "floating", "revolute", "continuous")     # the joints that may hold the root to the world


def _chain(robot) -> tuple[list, list, object, object]:
    """The links root..last and the revolute/continuous joints between them, the fixed tip joint (or None), and the
    fixed, revolute or continuous joint that holds the root to a link named ``world`` (or None: the root floats)."""
    links = {link.get("name"): link for link in robot.findall("link")}
    joints = robot.findall("joint")
    children: dict[str, list] = {}
    parents = set()
    for joint in joints:
        name = joint.get("name")
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            raise SceneError(f"urdf joint {name!r}: needs <parent link=...> and <child link=...>")
        if child.get("link") in parents:
            raise SceneError(f"urdf link {child.get('link')!r}: child of two joints")
        parents.add(child.get("link"))
        children.setdefault(parent.get("link"), []).append(joint)
    roots = [name for name in links if name not in parents]
    if len(roots) != 1:
        raise SceneError(f"urdf: expected one root link (a link that is no joint's child), found {roots}")
    mount = None
    if roots[0] == WORLD:
        below = children.get(WORLD, [])
        if len(below) != 1:
            raise SceneError(f"urdf link {WORLD!r}: has {len(below)} child joints; it holds one root link")
        mount = below[0]
        if mount.get("type") not in MOUNTS:
            raise SceneError(f"urdf joint {mount.get('name')!r}: holds the root to the world by a "
                             f"{mount.get('type')!r} joint; read are 'fixed' (a fixed base), 'floating' (a free "
                             "base) and 'revolute' or 'continuous' (a pinned revolute base)")
        roots = [mount.find("child").get("link")]
        mount = mount if mount.get("type") != "floating" else None
    chain, revolute, tip = [links[roots[0]]], [], None
    while True:
        below = children.get(chain[-1].get("name"), [])
        moving = [j for j in below if j.get("type") != "fixed"]
        fixed = [j for j in below if j.get("type") == "fixed"]
        if len(moving) > 1 or (moving and fixed) or len(fixed) > 1:
            raise SceneError(f"urdf link {chain[-1].get('name')!r}: has {len(below)} child joints; the model is a "
                             "serial chain (one revolute joint per link, or one fixed tip at its end)")
        if fixed:
            tip = fixed[0]
            if children.get(tip.find("child").get("link")):
                raise SceneError(f"urdf joint {tip.get('name')!r}: a fixed joint is allowed only as the chain's tip "
                                 "(with nothing below it)")
            return chain, revolute, tip, mount
        if not moving:
            return chain, revolute, None, mount
        joint = moving[0]
        kind = joint.get("type")
        if kind not in ("revolute", "continuous"):
            raise SceneError(f"urdf joint {joint.get('name')!r}: type {kind!r}; the chain's joints are revolute or "
                             "continuous (its base floats freely: give the root link, not a floating joint)")
        if joint.find("mimic") is not None:
            raise SceneError(f"urdf joint {joint.get('name')!r}: <mimic> couples joints; not in this model")
        revolute.append(joint)
        chain.append(links[joint.find("child").get("link")])


def urdf_links(text: str, tip_length: float | None = None) -> list[dict]:
    """The [[links]] tables of a scene (rigid links with their twists, stops and dampers) for the serial chain of
    a URDF text.  ``tip_length`` (m): the last link's length when the URDF has no fixed tip link."""
    return urdf_chain(text, tip_length)[0]


def urdf_chain(text: str, tip_length: float | None = None) -> tuple[list[dict], dict | None]:
    """The [[links]] tables (urdf_links) and the [base] table of a URDF chain: a root held to a ``world`` link by a
    fixed joint is a fixed base (O_1 at the joint's origin, link 1's model frame turned by its rpy), by a revolute or
    continuous joint a pinned revolute base (its axis in the world, O_1 on it), else None (a free base)."""
    tables, base, _ = _read(text, tip_length)
    return tables, base


def urdf_mount_frame(text: str, tip_length: float | None = None) -> np.ndarray | None:
    """Link 1's model frame in the world (columns x_1, y_1, z_1) at the URDF angle 0 of the revolute or continuous
    joint holding the root to ``world``, E A_1 (E: the joint's rpy); None for any other base.  At URDF angle phi it is
    E Rot(a, phi) A_1 = E A_1 Rz(phi), since A_1 turns z onto the joint's axis a (codegen.scene.urdf_mount_offset)."""
    return _read(text, tip_length)[2]


def _read(text: str, tip_length: float | None) -> tuple[list[dict], dict | None, np.ndarray | None]:
    """urdf_chain's tables and base, and urdf_mount_frame."""
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        raise SceneError(f"urdf: not well-formed XML: {exc}") from None
    if robot.tag != "robot":
        raise SceneError(f"urdf: the root element is <{robot.tag}>, expected <robot>")
    chain, joints, tip, mount = _chain(robot)
    n = len(chain)
    # joint k (k = 2..n) in its child's frame: axis a_k; its origin in the parent's frame: xyz, rpy E_k
    axes = [None] + [_floats(j.find("axis"), "xyz", "1 0 0", f"urdf joint {j.get('name')!r} <axis>")
                     for j in joints]
    origins = [_origin(j, f"urdf joint {j.get('name')!r}") for j in joints]
    for k, a in enumerate(axes[1:], start=2):
        if np.linalg.norm(a) == 0.0:
            raise SceneError(f"urdf joint {joints[k - 2].get('name')!r} <axis>: the zero vector")
        axes[k - 1] = a / np.linalg.norm(a)
    pinned = mount is not None and mount.get("type") in ("revolute", "continuous")
    if pinned:                                        # the base's axis, in the root's frame, is the root's z_1
        axes[0] = _mount_axis(mount)
    # the offset from each link's joint to the next joint (or the tip), in that link's URDF frame
    offsets = [xyz for xyz, _ in origins]
    if tip is not None:
        offsets.append(_origin(tip, f"urdf joint {tip.get('name')!r}")[0])
    elif tip_length is not None:
        offsets.append(None)
    else:
        raise SceneError(f"urdf: the last link {chain[-1].get('name')!r} has no fixed tip link; give its length "
                         "(urdf_tip_length in the scene file) or add a fixed joint to a tip link at its end")
    # a joint's origin O_k may sit anywhere on its axis: each is slid along it by s_k to where the link before it
    # reaches it normal to that link's own axis (the common normal of Denavit-Hartenberg), from the tip (which stays)
    # to joint 2, and to the root's origin on a revolute mount's axis (a free or fixed root's origin stays, its z is
    # free): s_k = (next point - joint k's origin) . a_k
    shift = [0.0] * (n + 1)
    for k in range(n - 1, -1 if pinned else 0, -1):
        if offsets[k] is not None:
            ahead = offsets[k] + (shift[k + 1] * (origins[k][1] @ axes[k + 1]) if k + 1 < n else 0.0)
            shift[k] = float(ahead @ axes[k])
    for k in range(n):
        if offsets[k] is not None:
            ahead = offsets[k] + (shift[k + 1] * (origins[k][1] @ axes[k + 1]) if k + 1 < n else 0.0)
            offsets[k] = ahead - (shift[k] * axes[k] if axes[k] is not None else 0.0)
    # the model's frame of each link: A_k with x_k towards the next joint, z_k the joint's axis
    A = []
    for k in range(n):
        where = f"urdf link {chain[k].get('name')!r}"
        if k == 0:
            if pinned:
                z = axes[0]                                        # the mount's axis
            elif n > 1:
                z = origins[0][1] @ axes[1]                        # joint 2's axis in the root frame
            else:
                z = np.array([0.0, 0.0, 1.0])
        else:
            z = axes[k]
        d = offsets[k]
        if d is None:                                              # the given tip length along x
            x = np.array([1.0, 0.0, 0.0]) - z[0] * z
            if np.linalg.norm(x) < 1e-6:
                x = np.array([0.0, 1.0, 0.0]) - z[1] * z
            length = float(tip_length)
        else:
            length = float(np.linalg.norm(d))
            if length == 0.0:
                raise SceneError(f"{where}: the next joint (or tip) sits at the joint itself; a link needs a length")
            x = d / length
            cosine = float(x @ z)
            if abs(cosine) > PERPENDICULAR_TOL:
                if k == 0 and not pinned:                          # the root's z is free: any normal to x
                    z = z - cosine * x
                    if np.linalg.norm(z) < 1e-6:
                        z = np.cross(x, [1.0, 0.0, 0.0]) if abs(x[0]) < 0.9 else np.cross(x, [0.0, 1.0, 0.0])
                else:
                    raise SceneError(
                        f"{where}: the next joint's origin is not normal to this joint's axis (angle "
                        f"{math.degrees(math.acos(max(-1.0, min(1.0, cosine)))):.6g} degrees, needs 90): the "
                        "model's links reach the next joint along x, normal to the joint axis z")
        z = z / np.linalg.norm(z)
        x = (x - (x @ z) * z) / np.linalg.norm(x - (x @ z) * z)
        A.append((_frame(x, z), length))
    tables = []
    for k in range(n):
        Ak, length = A[k]
        mass, c, I = _inertial(chain[k], f"urdf link {chain[k].get('name')!r}")
        com = Ak.T @ (c - (shift[k] * axes[k] if axes[k] is not None else 0.0))    # about O_k, slid along the axis
        inertia = Ak.T @ I @ Ak
        table = {"length": length, "mass": mass, "com": [float(v) for v in com],
                 "inertia": [[float(v) for v in row] for row in 0.5 * (inertia + inertia.T)]}
        if k >= 1:
            joint = joints[k - 1]
            where = f"urdf joint {joint.get('name')!r}"
            twist = _snap(A[k - 1][0].T @ origins[k - 1][1] @ Ak)
            table["twist_matrix"] = [[float(v) for v in row] for row in twist]
            if joint.get("type") == "revolute":
                limit = joint.find("limit")
                if limit is None:
                    raise SceneError(f"{where}: a revolute joint needs <limit lower upper> (URDF); use type "
                                     "continuous for a joint without stops")
                lower = _floats(limit, "lower", "0", f"{where} <limit>", 1)[0]
                upper = _floats(limit, "upper", "0", f"{where} <limit>", 1)[0]
                if not lower < upper:
                    raise SceneError(f"{where} <limit>: lower = {lower!r} must be < upper = {upper!r} rad")
                table["lower"], table["upper"] = float(lower), float(upper)
            dynamics = joint.find("dynamics")
            if dynamics is not None:
                if _floats(dynamics, "friction", "0", f"{where} <dynamics>", 1)[0] != 0.0:
                    raise SceneError(f"{where} <dynamics friction>: joint friction is not in this model; give 0 or "
                                     "leave it out")
                damping = _floats(dynamics, "damping", "0", f"{where} <dynamics>", 1)[0]
                if damping != 0.0:
                    table["damping"] = float(damping)
        tables.append(table)
    if mount is None:
        return tables, None, None
    xyz, E = _origin(mount, f"urdf joint {mount.get('name')!r}")
    rotation = _snap(E @ A[0][0])                                    # the model's frame of link 1 in the world
    if not pinned:
        return tables, {"kind": "fixed", "point": [float(v) for v in xyz],
                        "rotation": [[float(v) for v in row] for row in rotation]}, None
    axis = _snap(E @ axes[0])
    point = xyz + E @ (shift[0] * axes[0])                           # O_1: slid along the axis
    return tables, {"kind": "pinned", "joint": "revolute", "point": [float(v) for v in point],
                    "axis": [float(v) for v in axis]}, rotation


def _mount_axis(mount) -> np.ndarray:
    """The unit axis (root frame) of the revolute or continuous joint holding the root to the world, refused with
    stops or a damper (the model's base has neither)."""
    where = f"urdf joint {mount.get('name')!r}"
    a = _floats(mount.find("axis"), "xyz", "1 0 0", f"{where} <axis>")
    if np.linalg.norm(a) == 0.0:
        raise SceneError(f"{where} <axis>: the zero vector")
    limit = mount.find("limit")
    if mount.get("type") == "revolute" and limit is not None:
        lower = _floats(limit, "lower", "0", f"{where} <limit>", 1)[0]
        upper = _floats(limit, "upper", "0", f"{where} <limit>", 1)[0]
        if lower != upper:
            raise SceneError(f"{where} <limit>: lower = {float(lower)!r}, upper = {float(upper)!r} rad are stops of the joint that "
                             "holds the root to the world; the model's pinned base has no stops (use type continuous)")
    dynamics = mount.find("dynamics")
    if dynamics is not None:
        for attribute in ("damping", "friction"):
            if _floats(dynamics, attribute, "0", f"{where} <dynamics>", 1)[0] != 0.0:
                raise SceneError(f"{where} <dynamics {attribute}>: the model's pinned base has no {attribute}; give "
                                 "0 or leave it out")
    return a / np.linalg.norm(a)



# ---------------------------------------------------------------------------------------------------
# scene -> URDF
# ---------------------------------------------------------------------------------------------------
def _num(value) -> str:
    return repr(float(value))


def _numbers(values) -> str:
    return " ".join(_num(v) for v in values)


def link_inertial(link) -> tuple[float, np.ndarray, np.ndarray]:
    """mass, centre of mass and inertia about it (link frame) of a line or rigid link (codegen.scene)."""
    if link.kind == "line":
        l, mu, J = float(link.length), float(link.mu), [float(v) for v in link.J]
        m = mu * l
        return m, np.array([l / 2, 0.0, 0.0]), np.diag([l * J[0], m * l * l / 12 + l * J[1], m * l * l / 12 + l * J[2]])
    return float(link.mass), np.array(link.com, dtype=float), np.array(link.inertia, dtype=float)


def scene_to_urdf(scene) -> tuple[str, list[str]]:
    """A scene's (codegen.scene.Scene) chain as URDF (root link1 floating, or held to a link ``world`` by a fixed
    joint for a fixed base, by a continuous joint about its z for a pinned revolute one; revolute or continuous joints
    theta_2..theta_n about z, a fixed tip link at the end of link n), and notes on what URDF cannot hold (springs,
    the restitution of stops)."""
    notes = []
    parts = [f'<robot name="{scene.name}">']
    for i, link in enumerate(scene.links, start=1):
        m, c, I = link_inertial(link)
        parts.append(f'  <link name="link{i}"><inertial><origin xyz="{_numbers(c)}" rpy="0.0 0.0 0.0"/>'
                     f'<mass value="{_num(m)}"/><inertia ixx="{_num(I[0, 0])}" iyy="{_num(I[1, 1])}" izz="{_num(I[2, 2])}" '
                     f'ixy="{_num(I[0, 1])}" ixz="{_num(I[0, 2])}" iyz="{_num(I[1, 2])}"/></inertial></link>')
    for k in range(2, scene.n + 1):
        joint = scene.joints[k - 2]
        stops = joint.lower is not None and joint.upper is not None
        if (joint.lower is None) != (joint.upper is None):
            notes.append(f"theta_{k}: a single stop has no URDF form (a revolute joint has both limits); written as "
                         "continuous")
        if joint.stiffness is not None:
            notes.append(f"theta_{k}: the spring (K = {joint.stiffness!r} N m/rad, rest angle {joint.rest_angle!r} "
                         "rad) has no URDF element; left out")
        if stops and joint.limit_restitution != 0.0:
            notes.append(f"theta_{k}: the stops' restitution {joint.limit_restitution!r} has no URDF element")
        limit = (f'<limit lower="{_num(joint.lower)}" upper="{_num(joint.upper)}" effort="0.0" velocity="0.0"/>'
                 if stops else "")
        damping = f'<dynamics damping="{_num(joint.damping)}"/>' if joint.damping is not None else ""
        length = scene.links[k - 2].length
        parts.append(f'  <joint name="theta_{k}" type="{"revolute" if stops else "continuous"}">'
                     f'<parent link="link{k - 1}"/><child link="link{k}"/>'
                     f'<origin xyz="{_num(length)} 0.0 0.0" rpy="{_numbers(matrix_rpy(scene.twists[k - 2]))}"/>'
                     f'<axis xyz="0.0 0.0 1.0"/>{limit}{damping}</joint>')
    if scene.base.kind == "fixed":                   # link 1's model frame is its URDF frame: held by the world
        R1 = np.eye(3)
        for T, angle in zip(scene.base_twists, scene.q0[:3]):      # ^{ref}R_1 = T_-1 Rz T_0 Rz T_1 Rz
            c, s = math.cos(angle), math.sin(angle)
            R1 = R1 @ np.array(T) @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        parts.append('  <link name="world"/>')
        parts.append(f'  <joint name="mount" type="fixed"><parent link="world"/><child link="link1"/>'
                     f'<origin xyz="{_numbers(scene.base.point)}" rpy="{_numbers(matrix_rpy(R1))}"/></joint>')
    elif scene.base.kind == "pinned" and scene.base.joint == "revolute":
        # held by a continuous joint about link 1's z whose origin is the base chart's frame at theta_1 = 0, so that
        # the URDF angle is theta_1 (codegen.scene.urdf_mount_offset 0)
        R1 = np.eye(3)
        for T, angle in zip(scene.base_twists[:2], scene.q0[:2]):
            c, s = math.cos(angle), math.sin(angle)
            R1 = R1 @ np.array(T) @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        R1 = R1 @ np.array(scene.base_twists[2])
        parts.append('  <link name="world"/>')
        parts.append(f'  <joint name="mount" type="continuous"><parent link="world"/><child link="link1"/>'
                     f'<origin xyz="{_numbers(scene.base.point)}" rpy="{_numbers(matrix_rpy(R1))}"/>'
                     '<axis xyz="0.0 0.0 1.0"/></joint>')
    elif scene.base.kind == "pinned":
        notes.append(f"base: a {scene.base.label} base has no URDF form read back here; link1 written floating")
    parts.append('  <link name="tip"/>')
    parts.append(f'  <joint name="tip" type="fixed"><parent link="link{scene.n}"/><child link="tip"/>'
                 f'<origin xyz="{_num(scene.links[-1].length)} 0.0 0.0" rpy="0.0 0.0 0.0"/></joint>')
    parts.append("</robot>")
    return "\n".join(parts) + "\n", notes
