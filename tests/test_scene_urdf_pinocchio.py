"""A ROS-style URDF arm imported by codegen.urdf against Pinocchio, an independent rigid-body dynamics library that
reads the same file: the mass matrix (CRBA) and the forward dynamics (ABA) at random states.

The arm is held to ``world`` by a fixed joint (a fixed base) and has six revolute joints whose next joints sit off
their axes and partly along them (the importer slides those joint points along their axes; wrist_1 reaches wrist_2
purely along its axis, as on a UR arm, and gets its length from wrist_2's slide), joint origins turned by rpy, and
inertias about turned centres of mass with off-diagonal terms.  Coordinates map without fitting: a fixed
base holds theta_-1, theta_0, theta_1 and X1..X3, so the model's coordinates are theta_2..theta_7, and theta_k is
URDF joint k-1's angle (same zero, same sign; codegen.urdf), which is Pinocchio's q for a revolute joint; the
velocities likewise.  Gravity: the model's acts along -X2 of the box, and the URDF's world frame is the box's (the
fixed joint's origin and rpy are the base's point and orientation), so Pinocchio's gravity is set to (0, -g, 0).
"""
from __future__ import annotations

import numpy as np
import pytest

pinocchio = pytest.importorskip("pinocchio", reason="Pinocchio is not installed (the pinocchio extra: pip install -e '.[pinocchio]')")

from codegen.scene import load_scene          # noqa: E402  (after the skip)
from conftest import quick_model              # noqa: E402

TOLERANCE = 1e-10          # relative, on the accelerations and on the mass matrix

ARM6 = """<?xml version="1.0"?>
<robot name="arm6">
  <link name="world"/>
  <joint name="world_joint" type="fixed">
    <parent link="world"/><child link="base_link"/>
    <origin xyz="0.1 0.8 -0.2" rpy="-1.5707963267948966 0.0 0.0"/>
  </joint>
  <link name="base_link">
    <inertial><origin xyz="0.0 0.0 0.05" rpy="0 0 0"/><mass value="4.0"/>
      <inertia ixx="0.0061" iyy="0.0059" izz="0.0072" ixy="0.0002" ixz="-0.0001" iyz="0.0003"/></inertial>
  </link>
  <joint name="shoulder_pan_joint" type="revolute">
    <parent link="base_link"/><child link="shoulder_link"/>
    <origin xyz="0.0 0.0 0.1273" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="150" velocity="3.15"/>
  </joint>
  <link name="shoulder_link">
    <inertial><origin xyz="0.003 -0.02 0.01" rpy="0.1 -0.2 0.3"/><mass value="3.7"/>
      <inertia ixx="0.0103" iyy="0.0102" izz="0.0067" ixy="0.0004" ixz="-0.0003" iyz="0.0006"/></inertial>
  </link>
  <joint name="shoulder_lift_joint" type="revolute">
    <parent link="shoulder_link"/><child link="upper_arm_link"/>
    <origin xyz="0.02 0.1358 0.015" rpy="0.0 1.5707963267948966 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-3.1" upper="3.1" effort="150" velocity="3.15"/>
  </joint>
  <link name="upper_arm_link">
    <inertial><origin xyz="0.01 0.02 0.306" rpy="0 0.15 0"/><mass value="8.39"/>
      <inertia ixx="0.2269" iyy="0.2271" izz="0.0151" ixy="0.0011" ixz="-0.0042" iyz="0.0023"/></inertial>
  </link>
  <joint name="elbow_joint" type="revolute">
    <parent link="upper_arm_link"/><child link="forearm_link"/>
    <origin xyz="0.0 -0.1197 0.612" rpy="0.05 0.0 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-3.1" upper="3.1" effort="150" velocity="3.15"/>
  </joint>
  <link name="forearm_link">
    <inertial><origin xyz="0.004 0.01 0.285" rpy="-0.1 0 0.2"/><mass value="2.28"/>
      <inertia ixx="0.0494" iyy="0.0496" izz="0.0041" ixy="-0.0003" ixz="0.0012" iyz="-0.0008"/></inertial>
  </link>
  <joint name="wrist_1_joint" type="revolute">
    <parent link="forearm_link"/><child link="wrist_1_link"/>
    <origin xyz="0.03 0.0 0.5723" rpy="0.0 1.5707963267948966 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-3.1" upper="3.1" effort="28" velocity="3.2"/>
  </joint>
  <link name="wrist_1_link">
    <inertial><origin xyz="0.0 0.11 0.01" rpy="0 0 0"/><mass value="1.22"/>
      <inertia ixx="0.0021" iyy="0.0019" izz="0.0022" ixy="0.0001" ixz="0.00005" iyz="-0.0002"/></inertial>
  </link>
  <joint name="wrist_2_joint" type="revolute">
    <parent link="wrist_1_link"/><child link="wrist_2_link"/>
    <origin xyz="0.0 0.093 0.0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="28" velocity="3.2"/>
  </joint>
  <link name="wrist_2_link">
    <inertial><origin xyz="0.002 0.003 0.1" rpy="0.2 0.1 0"/><mass value="1.22"/>
      <inertia ixx="0.0020" iyy="0.0021" izz="0.0018" ixy="-0.0001" ixz="0.0002" iyz="0.00007"/></inertial>
  </link>
  <joint name="wrist_3_joint" type="revolute">
    <parent link="wrist_2_link"/><child link="wrist_3_link"/>
    <origin xyz="0.015 0.0 0.1157" rpy="0.3 0.0 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-3.1" upper="3.1" effort="28" velocity="3.2"/>
  </joint>
  <link name="wrist_3_link">
    <inertial><origin xyz="0.001 0.07 0.002" rpy="0 0 0.4"/><mass value="0.19"/>
      <inertia ixx="0.00013" iyy="0.00018" izz="0.00012" ixy="0.00001" ixz="-0.00002" iyz="0.00001"/></inertial>
  </link>
  <joint name="tool0_joint" type="fixed">
    <parent link="wrist_3_link"/><child link="tool0"/>
    <origin xyz="0.02 0.0922 0.01" rpy="-1.5707963267948966 0 0"/>
  </joint>
  <link name="tool0"/>
</robot>
"""


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    """The URDF file, the scene the importer reads from it (alone: the fixed base, at rest in a box), its model
    (built once), and Pinocchio's model and data from the same file, with the model's gravity."""
    path = tmp_path_factory.mktemp("arm6") / "arm6.urdf"
    path.write_text(ARM6)
    scene = load_scene(path)
    peer = pinocchio.buildModelFromUrdf(str(path))
    peer.gravity.linear = np.array([0.0, -scene.gravity, 0.0])          # -g along X2, the URDF world's y
    return scene, quick_model(scene), peer, peer.createData()


def test_coordinates_map_one_to_one(arm):
    """The model's coordinates are theta_2..theta_7 (the fixed base holds the rest), in the URDF's joint order, as
    are Pinocchio's: one angle per revolute joint, named as in the file."""
    scene, model, peer, _ = arm
    assert scene.base.kind == "fixed" and scene.n == 7
    assert model.layout.free == tuple(range(3, 3 + 6))                  # theta_2 .. theta_7 of the full state
    assert list(peer.names)[1:] == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
                                    "wrist_2_joint", "wrist_3_joint"]
    assert peer.nq == peer.nv == model.nq == 6
    assert all(peer.joints[j].nq == 1 for j in range(1, 7))


def states(count=20, seed=11):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield rng.uniform(-3.0, 3.0, 6), rng.uniform(-2.0, 2.0, 6)


def relative(ours, theirs) -> float:
    return float(np.abs(ours - theirs).max() / np.abs(theirs).max())


def test_mass_matrix_is_pinocchios_crba(arm):
    _, model, peer, data = arm
    worst = 0.0
    for q, _ in states():
        M = pinocchio.crba(peer, data, q)
        M = np.triu(M) + np.triu(M, 1).T                                 # crba fills the upper triangle
        worst = max(worst, relative(model.mass_matrix(q), M))
    assert worst < TOLERANCE


def test_forward_dynamics_is_pinocchios_aba(arm):
    """qdd at u = 0 (gravity, Coriolis and centrifugal terms) against pinocchio.aba with tau = 0."""
    _, model, peer, data = arm
    worst = 0.0
    for q, qd in states():
        worst = max(worst, relative(model.forward_dynamics(q, qd), pinocchio.aba(peer, data, q, qd, np.zeros(6))))
    assert worst < TOLERANCE
