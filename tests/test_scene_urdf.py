"""Chains from and to URDF (codegen.urdf): a URDF chain's forward kinematics, computed here directly from the XML
(joint origins, rpy, axis rotations by Rodrigues' formula), against the scene's own kinematics; its kinetic
energy (URDF inertials, velocities by central differences) against the generated model's; the round trip
scene -> URDF -> scene; every refused construct named."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from codegen.scene import SceneError, contact_points, frames, load_scene, scene_from_dict
from codegen.urdf import matrix_rpy, rpy_matrix, scene_to_urdf, urdf_chain, urdf_links
from studies.reference import random_rotation
from conftest import quick_model


# ---------------------------------------------------------------------------------------------------
# an independent reading of a URDF chain
# ---------------------------------------------------------------------------------------------------
def rodrigues(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def numbers(element, attribute, default):
    return np.array([float(v) for v in (element.get(attribute, default) if element is not None else default).split()])


def urdf_fk(text, angles):
    """World poses (root at the origin, unrotated) of every link of a serial URDF chain, with its joint angles:
    [(origin, rotation, com, mass, inertia in the world frame)], and the tip's origin."""
    robot = ET.fromstring(text)
    links = {link.get("name"): link for link in robot.findall("link")}
    by_parent = {j.find("parent").get("link"): j for j in robot.findall("joint")}
    child_names = {j.find("child").get("link") for j in robot.findall("joint")}
    name = next(n for n in links if n not in child_names)
    p, R, out, k = np.zeros(3), np.eye(3), [], 0
    while True:
        inertial = links[name].find("inertial")
        if inertial is not None:
            o = inertial.find("origin")
            Rc = rpy_matrix(*numbers(o, "rpy", "0 0 0"))
            t = inertial.find("inertia")
            I = np.array([[float(t.get("ixx")), float(t.get("ixy")), float(t.get("ixz"))],
                          [float(t.get("ixy")), float(t.get("iyy")), float(t.get("iyz"))],
                          [float(t.get("ixz")), float(t.get("iyz")), float(t.get("izz"))]])
            out.append((p, R, p + R @ numbers(o, "xyz", "0 0 0"), float(inertial.find("mass").get("value")),
                        R @ Rc @ I @ Rc.T @ R.T))
        joint = by_parent.get(name)
        if joint is None:
            return out, None
        o = joint.find("origin")
        p = p + R @ numbers(o, "xyz", "0 0 0")
        R = R @ rpy_matrix(*numbers(o, "rpy", "0 0 0"))
        if joint.get("type") == "fixed":
            return out, p
        R = R @ rodrigues(numbers(joint.find("axis"), "xyz", "1 0 0"), angles[k])
        k += 1
        name = joint.find("child").get("link")


def kabsch(P, Q):
    """The rotation U minimising |U P_i - Q_i| (rows), and the residual."""
    H = P.T @ Q
    u, _, vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    U = vt.T @ np.diag([1, 1, d]) @ u.T
    return U, np.abs(P @ U.T - Q).max()


ARM = """<robot name="arm">
  <link name="base"><inertial><origin xyz="0.05 0.01 -0.02" rpy="0.1 0.2 0.3"/><mass value="2.0"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.025" ixy="0.001" ixz="-0.002" iyz="0.0015"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0.0 0.0 0.2" rpy="0 0 0"/><mass value="1.2"/>
    <inertia ixx="0.012" iyy="0.011" izz="0.002" ixy="0" ixz="0" iyz="0.0003"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.15 0.0 0.0" rpy="0 0.3 0"/><mass value="0.8"/>
    <inertia ixx="0.001" iyy="0.006" izz="0.0065" ixy="0.0002" ixz="0" iyz="0"/></inertial></link>
  <link name="hand"><inertial><origin xyz="0 0.03 0" rpy="0 0 0"/><mass value="0.3"/>
    <inertia ixx="0.0004" iyy="0.0003" izz="0.0005" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0.3 0.0 0.0" rpy="0.4 -0.2 0.7"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.2" effort="10" velocity="3"/><dynamics damping="0.05"/></joint>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.0 0.0 0.4" rpy="0 0 0.5"/><axis xyz="0 0 1"/></joint>
  <joint name="wrist" type="revolute"><parent link="fore"/><child link="hand"/>
    <origin xyz="0.3 0.0 0.0" rpy="0.2 0 0"/><axis xyz="0 0.6 0.8"/><limit lower="-0.5" upper="0.5"/></joint>
  <joint name="tool" type="fixed"><parent link="hand"/><child link="tool"/><origin xyz="0.1 0 0"/></joint>
</robot>
"""


def arm_scene(text=ARM, tip=None):
    data = {"name": "arm", "links": urdf_links(text, tip),
            "walls": {"x2_min": -5.0}, "initial": {"q": [0.2, -0.3, 0.4, 0.3, -0.6, 0.2, 0.0, 1.0, 0.0],
                                                    "qd": [0.0] * 9}}
    return scene_from_dict(data)


def test_rpy_rebuilds_every_rotation():
    rng = np.random.default_rng(3)
    for R in [random_rotation(rng) for _ in range(50)] + [np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0.0]]),
                                                           np.array([[0, 0, -1], [0, 1, 0], [1, 0, 0.0]])]:
        roll, pitch, yaw = matrix_rpy(R)           # matrix_rpy() checks the round trip itself
        assert all(math.isfinite(a) for a in (roll, pitch, yaw))


def test_links_are_read_as_the_urdf_says():
    tables = urdf_links(ARM)
    assert [t["length"] for t in tables] == pytest.approx([0.3, 0.4, 0.3, 0.1], abs=1e-15)
    assert [t["mass"] for t in tables] == [2.0, 1.2, 0.8, 0.3]
    assert (tables[1]["lower"], tables[1]["upper"], tables[1]["damping"]) == (-1.5, 1.2, 0.05)
    assert "lower" not in tables[2] and "damping" not in tables[2]            # continuous, no dynamics
    assert (tables[3]["lower"], tables[3]["upper"]) == (-0.5, 0.5)


@pytest.mark.parametrize("seed", range(5))
def test_kinematics_and_inertia_agree_with_the_urdf(seed):
    """Points, centres of mass and inertias of the scene built from the URDF, at random angles, against the URDF's
    own forward kinematics (its root pose found by fitting the joint origins)."""
    rng = np.random.default_rng(seed)
    scene = arm_scene()
    q = np.array(scene.q0)
    q[:scene.n + 2] = rng.uniform(-1.2, 1.2, scene.n + 2)
    q[scene.n + 2:] = rng.uniform(-1, 1, 3)
    poses, tip = urdf_fk(ARM, q[3:scene.n + 2])
    points = contact_points(scene, q)
    P = np.array([pose[0] for pose in poses] + [tip])
    U, residual = kabsch(P, points - points[0])
    assert residual < 1e-13
    Rs = frames(scene, q)
    for i, link in enumerate(scene.links):
        origin, R, com, mass, inertia = poses[i]
        ours_com = points[i] + Rs[i + 2] @ np.array(link.com)
        assert np.abs(ours_com - (points[0] + U @ com)).max() < 1e-13
        assert link.mass == mass
        ours_inertia = Rs[i + 2] @ np.array(link.inertia) @ Rs[i + 2].T
        assert np.abs(ours_inertia - U @ inertia @ U.T).max() < 1e-15
        # the joint axis: z of the model's frame is the URDF joint's axis, in the world
        if i >= 1:
            axis = numbers(ET.fromstring(ARM).findall("joint")[i - 1].find("axis"), "xyz", "1 0 0")
            assert np.abs(Rs[i + 2][:, 2] - U @ R @ (axis / np.linalg.norm(axis))).max() < 1e-13


def test_kinetic_energy_agrees_with_the_urdf():
    """T of the generated model at random states against the URDF's: sum of m |v_c|^2 / 2 + w . I w / 2, the
    velocities of the URDF's links by central differences of its kinematics along the same motion."""
    scene = arm_scene()
    model = quick_model(scene, specialise=False)
    rng = np.random.default_rng(7)
    n = scene.n
    for _ in range(3):
        q = np.array(scene.q0)
        q[:n + 2] = rng.uniform(-1.2, 1.2, n + 2)
        qd = rng.uniform(-1, 1, n + 5)

        def world(t):
            """Each link's centre of mass and rotation in the world, and its inertia in its own frame."""
            qt = q + t * qd
            poses, tip = urdf_fk(ARM, qt[3:n + 2])
            points = contact_points(scene, qt)
            U, _ = kabsch(np.array([p[0] for p in poses] + [tip]), points - points[0])
            return [(points[0] + U @ com, U @ R, R.T @ inertia @ R) for _, R, com, _, inertia in poses]
        h = 1e-5
        T = 0.0
        for (cp, Rp, _), (cm, Rm, _), (_, R0, I_body), link in zip(world(h), world(-h), world(0.0), scene.links):
            v = (cp - cm) / (2 * h)
            W = (Rp - Rm) / (2 * h) @ R0.T
            w = np.array([W[2, 1], W[0, 2], W[1, 0]])
            T += 0.5 * link.mass * v @ v + 0.5 * w @ (R0 @ I_body @ R0.T) @ w
        assert model.energy(q, qd)[0] == pytest.approx(T, rel=1e-8)


def test_round_trip_scene_urdf_scene():
    """A shipped scene and a 3D rigid chain written as URDF and read back: the same links, twists, stops and
    dampers (line links come back as the rigid links they are)."""
    from codegen.urdf import link_inertial
    for scene in (load_scene("paper-case1"), arm_scene(), load_scene("driven-fold")):
        text, notes = scene_to_urdf(scene)
        tables = urdf_links(text)
        assert len(tables) == scene.n
        for k, (link, table) in enumerate(zip(scene.links, tables), start=1):
            m, c, I = link_inertial(link)
            assert table["length"] == pytest.approx(link.length, abs=1e-15)
            assert table["mass"] == pytest.approx(m, rel=1e-15)
            assert np.abs(np.array(table["com"]) - c).max() < 1e-15
            assert np.abs(np.array(table["inertia"]) - I).max() < 1e-15
            if k >= 2:
                assert np.abs(np.array(table["twist_matrix"]) - np.array(scene.twists[k - 2])).max() < 1e-15
                joint = scene.joints[k - 2]
                assert table.get("damping") == joint.damping
                if joint.lower is not None and joint.upper is not None:
                    assert (table["lower"], table["upper"]) == (joint.lower, joint.upper)
        if scene.name == "driven_fold":
            assert any("spring" in note for note in notes) and any("restitution" in note for note in notes)


def test_a_planar_urdf_chain_stays_planar(tmp_path):
    """Parallel joint axes normal to the links give twists about z only: the model is specialised as planar."""
    text, _ = scene_to_urdf(load_scene("paper-case1"))
    (tmp_path / "square.urdf").write_text(text)
    scene_file = tmp_path / "square.toml"
    scene_file.write_text('name = "square"\nurdf = "square.urdf"\n'
                          '[walls]\nx1_min = 0.0\nx1_max = 3.0\nx2_min = 0.0\nx2_max = 2.0\n'
                          '[initial]\nq = ' + str(list(load_scene("paper-case1").q0)) + '\n')
    scene = load_scene(scene_file)
    from codegen.specialise import layout_for
    assert layout_for(scene).planar_normal is not None
    assert np.abs(contact_points(scene, np.array(scene.q0))
                  - contact_points(load_scene("paper-case1"), np.array(scene.q0))).max() < 1e-15


def replace(old, new):
    assert old in ARM
    return ARM.replace(old, new)


NO_TIP = replace('<joint name="tool" type="fixed"><parent link="hand"/><child link="tool"/><origin xyz="0.1 0 0"/>'
                 '</joint>', '').replace('<link name="tool"/>', '')


@pytest.mark.parametrize("text, message", [
    (replace('type="continuous"', 'type="prismatic"'), "type 'prismatic'"),
    (replace('<origin xyz="0.0 0.0 0.4" rpy="0 0 0.5"/>', '<origin xyz="0.0 0.4 0.0" rpy="0 0 0.5"/>'),
     "sits at the joint itself"),
    (replace('<dynamics damping="0.05"/>', '<dynamics damping="0.05" friction="0.2"/>'), "joint friction"),
    (replace('<limit lower="-0.5" upper="0.5"/>', ''), "needs <limit lower upper>"),
    (replace('<limit lower="-0.5" upper="0.5"/>', '<limit lower="0.5" upper="0.5"/>'), "must be < upper"),
    (NO_TIP, "no fixed tip link"),
    (replace('<link name="tool"/>', '<link name="tool"/><link name="extra"/>'), "one root link"),
    (replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><mimic joint="shoulder"/>'), "<mimic>"),
    (replace('<mass value="0.8"/>', '<mass value="heavy"/>'), "expected 1 finite numbers"),
    ("<robot><link", "not well-formed XML"),
])
def test_what_the_model_cannot_hold_is_refused_by_name(text, message):
    with pytest.raises(SceneError, match=message.replace("(", r"\(").replace("<", "<")):
        arm_scene(text)


def test_tip_length_for_a_chain_without_a_tip():
    scene = arm_scene(NO_TIP, tip=0.25)
    assert scene.links[-1].length == 0.25
    with pytest.raises(SceneError, match="urdf_tip_length: given without a urdf file"):
        scene_from_dict({"name": "x", "links": [{"length": 1.0, "mu": 1.0}], "urdf_tip_length": 0.2})


# ---------------------------------------------------------------------------------------------------
# a root fixed to the world: a fixed base
# ---------------------------------------------------------------------------------------------------
MOUNT_XYZ, MOUNT_RPY = np.array([0.4, 1.1, -0.3]), np.array([0.3, -0.5, 1.2])


def mounted_arm(kind="fixed", text=ARM):
    return text.replace('<link name="tool"/>', '<link name="tool"/><link name="world"/>'
                       f'<joint name="mount" type="{kind}"><parent link="world"/><child link="base"/>'
                       f'<origin xyz="{" ".join(map(str, MOUNT_XYZ))}" rpy="{" ".join(map(str, MOUNT_RPY))}"/></joint>')


def test_root_fixed_to_the_world_is_a_fixed_base(tmp_path):
    """The points of the mounted chain are the URDF's own (urdf_fk of the free arm, carried by the mount's pose) at
    random joint angles, with no fitted rotation: the base's point and orientation are the URDF's."""
    (tmp_path / "mounted.urdf").write_text(mounted_arm())
    (tmp_path / "mounted.toml").write_text('name = "mounted"\nurdf = "mounted.urdf"\n[initial]\nq = [0.1, 0.2, 0.3]\n')
    scene = load_scene(tmp_path / "mounted.toml")
    assert scene.base.kind == "fixed" and scene.base.point == tuple(MOUNT_XYZ)
    E = rpy_matrix(*MOUNT_RPY)
    rng = np.random.default_rng(4)
    for _ in range(5):
        angles = rng.uniform(-0.5, 0.5, 3)
        q = np.array(scene.q0)
        q[3:6] = angles
        links, tip = urdf_fk(ARM, angles)
        expected = np.array([MOUNT_XYZ + E @ p for p, *_ in links] + [MOUNT_XYZ + E @ tip])
        assert np.abs(contact_points(scene, q) - expected).max() < 1e-13
    # alone, in a default box around its base; with a [base] table of its own, refused
    alone = load_scene(tmp_path / "mounted.urdf")
    assert alone.base == scene.base and all(w.position != 0.0 for w in alone.walls)
    (tmp_path / "twice.toml").write_text('name = "twice"\nurdf = "mounted.urdf"\n[base]\nkind = "free"\n')
    with pytest.raises(SceneError, match=r"base: the URDF file mounted.urdf holds its root link to the world \(a fixed base\)"):
        load_scene(tmp_path / "twice.toml")


def test_gravity_along_the_urdf_worlds_minus_z(tmp_path, derived):
    """gravity_direction = "urdf": gravity along the URDF world's -z (the import takes the world as the box frame,
    unturned), so the mounted arm's potential energy is g sum m_i z_i, its centres of mass z_i from the URDF's own
    kinematics; without a urdf file the word is refused."""
    (tmp_path / "mounted.urdf").write_text(mounted_arm())
    (tmp_path / "mounted.toml").write_text('name = "mounted"\nurdf = "mounted.urdf"\ngravity_direction = "urdf"\n'
                                           '[initial]\nq = [0.1, 0.2, 0.3]\n')
    scene = load_scene(tmp_path / "mounted.toml")
    assert scene.gravity_direction == (0.0, 0.0, -1.0)
    model = derived(scene)
    E, g = rpy_matrix(*MOUNT_RPY), scene.gravity
    rng = np.random.default_rng(5)
    for _ in range(3):
        angles = rng.uniform(-0.5, 0.5, 3)
        links, _ = urdf_fk(ARM, angles)
        V = sum(g * mass * (MOUNT_XYZ + E @ com)[2] for _, _, com, mass, _ in links)
        assert model.energy(angles, np.zeros(3))[1] == pytest.approx(V, rel=1e-12, abs=1e-12)
    with pytest.raises(SceneError, match=r'gravity_direction: expected a unit vector .*"urdf" in a scene with a urdf'):
        scene_from_dict({"name": "x", "links": [{"length": 1.0, "mu": 1.0}], "gravity_direction": "urdf"})


def test_world_joints_other_than_fixed_or_floating_are_refused(tmp_path):
    (tmp_path / "slider.urdf").write_text(mounted_arm("prismatic"))
    with pytest.raises(SceneError, match=r"holds the root to the world by a 'prismatic' joint; read are 'fixed'"):
        load_scene(tmp_path / "slider.urdf")
    (tmp_path / "floating.urdf").write_text(mounted_arm("floating"))
    assert load_scene(tmp_path / "floating.urdf").base.kind == "free"


def test_fixed_base_round_trip(tmp_path):
    """The shipped mounted-arm written as URDF (a world link holding link1) and read back: the same base pose."""
    scene = load_scene("mounted-arm")
    text, notes = scene_to_urdf(scene)
    (tmp_path / "arm.urdf").write_text(text)
    back = load_scene(tmp_path / "arm.urdf")
    assert back.base.kind == "fixed" and back.base.point == scene.base.point
    assert np.abs(frames(back, np.array(back.q0))[2] - frames(scene, np.array(scene.q0))[2]).max() < 1e-15


def test_offsets_along_the_joint_axes_slide_the_joint_points():
    """Next joints offset along a joint's axis (shoulder: 0.1 m along its y axis to the elbow; elbow: 0.05 m along its
    z axis to the wrist; the tool 0.02 m along the wrist's axis): on a world mount, at random angles, each model
    point O_k lies on URDF joint k's axis, the tip is the URDF's, and the centres of mass, inertias and joint axes
    are the URDF's, all in the world frame with no fitted rotation."""
    free_text = ARM.replace('<origin xyz="0.0 0.0 0.4" rpy="0 0 0.5"/>', '<origin xyz="0.0 0.1 0.4" rpy="0 0 0.5"/>')
    free_text = free_text.replace('<origin xyz="0.3 0.0 0.0" rpy="0.2 0 0"/>', '<origin xyz="0.3 0.0 0.05" rpy="0.2 0 0"/>')
    free_text = free_text.replace('<origin xyz="0.1 0 0"/>', '<origin xyz="0.1 0.012 0.016"/>')
    text = mounted_arm(text=free_text)
    scene = scene_from_dict({"name": "offset", "links": urdf_chain(text)[0], "base": urdf_chain(text)[1],
                             "initial": {"q": [0.0, 0.0, 0.0]}})
    E = rpy_matrix(*MOUNT_RPY)
    robot = ET.fromstring(free_text)
    axes = [numbers(j.find("axis"), "xyz", "1 0 0") for j in robot.findall("joint") if j.get("type") != "fixed"]
    rng = np.random.default_rng(12)
    for _ in range(5):
        angles = rng.uniform(-0.5, 0.5, 3)
        q = np.array(scene.q0)
        q[3:6] = angles
        poses, tip = urdf_fk(free_text, angles)
        points, Rs = contact_points(scene, q), frames(scene, q)
        assert np.abs(points[-1] - (MOUNT_XYZ + E @ tip)).max() < 1e-13
        for i, link in enumerate(scene.links):
            origin, R, com, mass, inertia = poses[i]
            if i >= 1:
                axis = E @ R @ (axes[i - 1] / np.linalg.norm(axes[i - 1]))
                assert np.abs(np.cross(points[i] - (MOUNT_XYZ + E @ origin), axis)).max() < 1e-13
                assert np.abs(Rs[i + 2][:, 2] - axis).max() < 1e-13
            assert np.abs(points[i] + Rs[i + 2] @ np.array(link.com) - (MOUNT_XYZ + E @ com)).max() < 1e-13
            assert np.abs(Rs[i + 2] @ np.array(link.inertia) @ Rs[i + 2].T - E @ inertia @ E.T).max() < 1e-15


# ---------------------------------------------------------------------------------------------------
# a root held to the world by a revolute or continuous joint: a pinned revolute base
# ---------------------------------------------------------------------------------------------------
PENDULUM = """<robot name="pendulum">
  <link name="world"/>
  <link name="upper"><inertial><origin xyz="0.25 0.02 0.01" rpy="0 0 0"/><mass value="1.5"/>
    <inertia ixx="0.002" iyy="0.03" izz="0.031" ixy="0.001" ixz="0" iyz="0.0002"/></inertial></link>
  <link name="lower"><inertial><origin xyz="0.2 0 -0.01" rpy="0 0 0"/><mass value="0.8"/>
    <inertia ixx="0.001" iyy="0.012" izz="0.0125" ixy="0" ixz="0.0003" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="pivot" type="MOUNT"><parent link="world"/><child link="upper"/>
    <origin xyz="1.0 1.5 0.0" rpy="1.5707963267948966 0 0"/><axis xyz="0 1 0"/>LIMIT</joint>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="lower"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 1 0"/></joint>
  <joint name="tip" type="fixed"><parent link="lower"/><child link="tip"/><origin xyz="0.4 0 0"/></joint>
</robot>
"""
# The same double pendulum written as a scene: the pivot's rpy turns the root's y (its joint axis) onto X3 and its x
# onto X1; the model's link frames are (x, y, z) = (URDF x, -URDF z, URDF y), so each centre of mass (c_x, c_y, c_z)
# becomes (c_x, -c_z, c_y) and the inertias are turned alike; theta_1 = 0 points link 1 along +X2 (the chart of an
# axis along X3), where the URDF angle 0 points it along +X1: theta_1 = URDF angle - pi/2.
PENDULUM_SCENE = {
    "name": "pendulum_scene",
    "base": {"kind": "pinned", "joint": "revolute", "point": [1.0, 1.5, 0.0], "axis": [0.0, 0.0, 1.0]},
    "links": [{"length": 0.5, "mass": 1.5, "com": [0.25, -0.01, 0.02],
               "inertia": [[0.002, 0.0, 0.001], [0.0, 0.031, -0.0002], [0.001, -0.0002, 0.03]]},
              {"length": 0.4, "mass": 0.8, "com": [0.2, 0.01, 0.0],
               "inertia": [[0.001, -0.0003, 0.0], [-0.0003, 0.0125, 0.0], [0.0, 0.0, 0.012]]}],
    "initial": {"q": [0.3, -0.2]},
}


def pendulum(mount="continuous", limit=""):
    return PENDULUM.replace("MOUNT", mount).replace("LIMIT", limit)


@pytest.fixture(scope="module")
def pendulums(tmp_path_factory):
    """The URDF pendulum on a continuous world joint (read from a scene file) and the same chain written as a scene
    with a pinned revolute base, their models built once."""
    folder = tmp_path_factory.mktemp("pendulum")
    (folder / "pendulum.urdf").write_text(pendulum())
    (folder / "pendulum.toml").write_text('name = "pendulum_urdf"\nurdf = "pendulum.urdf"\n[initial]\nq = [0.3, -0.2]\n')
    from_urdf = load_scene(folder / "pendulum.toml")
    written = scene_from_dict(PENDULUM_SCENE)
    return from_urdf, written, quick_model(from_urdf), quick_model(written)


def test_root_on_a_revolute_world_joint_is_a_pinned_revolute_base(pendulums):
    from_urdf, written, *_ = pendulums
    assert from_urdf.base == written.base
    assert from_urdf.base.kind == "pinned" and from_urdf.base.joint == "revolute"
    for a, b in zip(from_urdf.links, written.links):
        assert a.length == pytest.approx(b.length, abs=1e-15) and a.mass == b.mass
        assert np.abs(np.array(a.com) - np.array(b.com)).max() < 1e-15
        assert np.abs(np.array(a.inertia) - np.array(b.inertia)).max() < 1e-15
    assert np.abs(np.array(from_urdf.twists) - np.array(written.twists)).max() < 1e-15
    # revolute with the limits URDF requires but no stops (lower = upper) reads the same; a type revolute with stops,
    # or a damper on the pivot, is refused by name
    assert urdf_chain(pendulum("revolute", '<limit effort="1" velocity="1"/>'))[1] == urdf_chain(pendulum())[1]
    with pytest.raises(SceneError, match=r"urdf joint 'pivot' <limit>: lower = -1.0, upper = 1.0 rad are stops of "
                                         r"the joint that holds the root to the world"):
        urdf_chain(pendulum("revolute", '<limit lower="-1" upper="1" effort="1" velocity="1"/>'))
    with pytest.raises(SceneError, match=r"urdf joint 'pivot' <dynamics damping>: the model's pinned base has no "
                                         r"damping"):
        urdf_chain(pendulum("continuous", '<dynamics damping="0.1"/>'))


def test_pinned_urdf_pendulum_has_the_written_scenes_dynamics(pendulums):
    """Mass matrix and forward dynamics of the two models agree to 1e-12 at random states."""
    *_, a, b = pendulums
    assert a.nq == b.nq == 2
    rng = np.random.default_rng(29)
    for _ in range(20):
        q, qd = rng.uniform(-math.pi, math.pi, 2), rng.uniform(-3.0, 3.0, 2)
        assert np.abs(a.mass_matrix(q) - b.mass_matrix(q)).max() < 1e-12
        assert np.abs(a.forward_dynamics(q, qd) - b.forward_dynamics(q, qd)).max() < 1e-12


def test_pinned_urdf_pendulum_points_are_the_urdfs(pendulums):
    """The model's points at theta_1 = URDF angle + urdf_mount_offset are the URDF's (urdf_fk of the chain below the
    pivot, turned by the pivot's angle and carried by its origin), also on a pivot whose axis the root reaches off its
    origin (O_1 slides along the axis to where link 1 reaches joint 2 normal to it)."""
    from codegen.scene import urdf_mount_offset
    from_urdf = pendulums[0]
    assert urdf_mount_offset(pendulum()) == pytest.approx(-math.pi / 2, abs=1e-15)
    shifted = pendulum().replace('<origin xyz="0.5 0 0"/>', '<origin xyz="0.5 0.07 0"/>')
    offset_scene = scene_from_dict({"name": "shifted", "links": urdf_chain(shifted)[0], "base": urdf_chain(shifted)[1],
                                    "initial": {"q": [0.0, 0.0]}})
    assert offset_scene.base.point == pytest.approx((1.0, 1.5, 0.07), abs=1e-15)
    E = rpy_matrix(math.pi / 2, 0.0, 0.0)
    rng = np.random.default_rng(7)
    for scene, text in ((from_urdf, pendulum()), (offset_scene, shifted)):
        offset = urdf_mount_offset(text)
        free_text = "\n".join(line for line in text.splitlines() if "world" not in line and "pivot" not in line
                              and "1.5707963267948966" not in line)
        for _ in range(5):
            phi, elbow = rng.uniform(-math.pi, math.pi, 2)
            q = np.array(scene.q0)
            q[2], q[3] = phi + offset, elbow
            links, tip = urdf_fk(free_text, [elbow])
            turn = E @ rodrigues([0.0, 1.0, 0.0], phi)
            expected = np.array([[1.0, 1.5, 0.0] + turn @ p for p, *_ in links[1:]] + [[1.0, 1.5, 0.0] + turn @ tip])
            points = contact_points(scene, q)
            assert np.abs(points[1:] - expected).max() < 1e-13
            assert np.abs(points[0][:2] - [1.0, 1.5]).max() < 1e-15          # O_1 on the pivot's axis (along X3)


def test_pinned_revolute_base_round_trip(tmp_path):
    """The written pendulum scene as URDF (a continuous joint from a world link, about link1's z) and read back: the
    same base, links and twists, and the URDF angle is theta_1 (offset 0)."""
    from codegen.scene import urdf_mount_offset
    scene = scene_from_dict(PENDULUM_SCENE)
    text, notes = scene_to_urdf(scene)
    assert '<joint name="mount" type="continuous">' in text and not any("base" in note for note in notes)
    (tmp_path / "back.urdf").write_text(text)
    (tmp_path / "back.toml").write_text('name = "back"\nurdf = "back.urdf"\n[initial]\nq = [0.3, -0.2]\n')
    back = load_scene(tmp_path / "back.toml")
    assert back.base == scene.base and urdf_mount_offset(text) == 0.0
    for a, b in zip(back.links, scene.links):
        assert a.length == pytest.approx(b.length, abs=1e-15) and a.mass == pytest.approx(b.mass, rel=1e-15)
        assert np.abs(np.array(a.com) - np.array(b.com)).max() < 1e-15
        assert np.abs(np.array(a.inertia) - np.array(b.inertia)).max() < 1e-15
    assert np.abs(np.array(back.twists) - np.array(scene.twists)).max() < 1e-15
    assert np.abs(contact_points(back, np.array(back.q0)) - contact_points(scene, np.array(scene.q0))).max() < 1e-15


def test_pinned_urdf_alone_starts_at_its_zero_pose(tmp_path):
    """A URDF file alone with a revolute world joint: the pinned base, at rest at the URDF's zero angles (theta_1 =
    urdf_mount_offset), in the default box around O_1."""
    from codegen.scene import urdf_mount_offset
    (tmp_path / "pendulum.urdf").write_text(pendulum())
    scene = load_scene(tmp_path / "pendulum.urdf")
    assert scene.base == scene_from_dict(PENDULUM_SCENE).base
    assert scene.q0[2:4] == (urdf_mount_offset(pendulum()), 0.0) and not any(scene.qd0)
    assert contact_points(scene, np.array(scene.q0))[-1] == pytest.approx([1.9, 1.5, 0.0], abs=1e-15)
