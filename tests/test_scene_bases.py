"""The [base] table of a scene: pinned (spherical, revolute) and fixed bases, how they fill the initial state, and
every bad value rejected with a message naming the field and what is allowed."""
import copy
import math

import numpy as np
import pytest

from codegen.scene import Base, Scene, SceneError, axis_angles, frames, load_scene, rotation_angles, scene_from_dict
from codegen.specialise import layout_for

ARM = {
    "name": "arm",
    "links": [{"length": 0.5, "mu": 1.0}, {"length": 1.0, "mu": 1.0}, {"length": 0.8, "mu": 1.0}],
    "walls": {"x2_min": 0.0, "x1_max": 3.0},
    "base": {"kind": "pinned", "joint": "revolute", "point": [1.0, 0.5, 0.0], "axis": [0.0, 0.0, 2.0]},
    "initial": {"q": [0.3, -0.4, 0.2]},
}


def arm(**changes):
    data = copy.deepcopy(ARM)
    for key, value in changes.items():
        if value is KeyError:
            del data[key]
        else:
            data[key] = value
    return data


def test_revolute_base_fills_the_full_state():
    scene = scene_from_dict(arm())
    assert scene.base == Base("pinned", "revolute", (1.0, 0.5, 0.0), (0.0, 0.0, 1.0))     # axis normalised
    assert scene.q0 == (-math.pi / 2, 0.0, 0.3, -0.4, 0.2, 1.0, 0.5, 0.0)
    assert scene.qd0 == (0.0,) * 8
    # the full layout is accepted too, when it agrees with the base
    again = scene_from_dict(arm(initial={"q": list(scene.q0)}))
    assert again.q0 == scene.q0
    # from Python, numpy arrays too, either length
    assert Scene(name="arm", links=scene.links, base=scene.base, q0=np.array([0.3, -0.4, 0.2])).q0 == scene.q0
    assert Scene(name="arm", links=scene.links, base=scene.base, q0=np.array(scene.q0)).q0 == scene.q0
    # O_1 is held: no wall pairs it by default
    assert all(1 not in w.points for w in scene.walls)
    assert layout_for(scene, False).nq == 3


def test_spherical_and_fixed_bases():
    spherical = scene_from_dict(arm(base={"kind": "pinned", "point": [1.0, 0.5, 0.0]}, initial={"q": [-1.0, 0.2, 0.3, 0.1, 0.0]}))
    assert spherical.base.joint == "spherical" and spherical.q0[5:] == (1.0, 0.5, 0.0)
    assert layout_for(spherical, False).nq == 5
    fixed = scene_from_dict(arm(base={"kind": "fixed", "point": [1.0, 0.5, 0.0], "angles": [-1.0, 0.2, 0.3]},
                                initial={"q": [0.1, 0.0]}))
    assert fixed.q0[:3] == (-1.0, 0.2, 0.3) and layout_for(fixed, True).nq == 2
    assert all(not {1, 2} & set(w.points) for w in fixed.walls)


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, -1), (0.3, -0.5, 0.8), (-0.2, 0.1, -0.9)])
def test_axis_angles_turn_z1_along_the_axis(axis):
    d = np.array(axis, dtype=float) / np.linalg.norm(axis)
    scene = scene_from_dict(arm(base={"kind": "pinned", "joint": "revolute", "point": [1.0, 0.5, 0.0],
                                      "axis": list(axis)}, walls={}))
    q = np.array(scene.q0)
    for theta in (0.0, 1.0, -2.5):
        q[2] = theta
        assert np.allclose(frames(scene, q)[2][:, 2], d, rtol=0, atol=1e-15)
    assert scene.q0[:2] == axis_angles(d)


def test_rotation_angles_recompose(rng=np.random.default_rng(1)):
    from studies.reference import random_rotation
    for _ in range(20):
        R = random_rotation(rng)
        scene = scene_from_dict(arm(base={"kind": "fixed", "point": [1.0, 0.5, 0.0], "rotation": R.tolist()},
                                    initial={"q": [0.0, 0.0]}, walls={}))
        assert np.allclose(frames(scene, np.array(scene.q0))[2], R, rtol=0, atol=1e-12)
        assert scene.q0[:3] == rotation_angles(R)


BAD = [
    ({"base": {"kind": "floating"}}, r"base.kind: must be one of 'free', 'pinned', 'fixed', got 'floating'"),
    ({"base": {"joint": "revolute"}}, r"base.kind: required with other base fields"),
    ({"base": {"kind": "pinned", "joint": "hinge", "point": [0, 1, 0]}},
     r"base.joint: must be one of 'spherical', 'revolute', got 'hinge'"),
    ({"base": {"kind": "pinned"}}, r"base.point: required for a pinned base"),
    ({"base": {"kind": "pinned", "point": [0, 1]}}, r"base.point: expected a list of 3 numbers"),
    ({"base": {"kind": "pinned", "point": [0, 1, float("nan")]}}, r"base.point\[2\]: must be a finite number"),
    ({"base": {"kind": "pinned", "joint": "revolute", "point": [1, 1, 0]}}, r"base.axis: required for joint = "),
    ({"base": {"kind": "pinned", "joint": "revolute", "point": [1, 1, 0], "axis": [0, 0, 0]}},
     r"base.axis: must be a non-zero direction"),
    ({"base": {"kind": "pinned", "point": [1, 1, 0], "axis": [0, 0, 1]}}, r"base.axis: only for joint = 'revolute'"),
    ({"base": {"kind": "pinned", "point": [1, 1, 0], "angles": [0, 0, 0]}},
     r"base.angles: not a field of a pinned base"),
    ({"base": {"kind": "free", "point": [1, 1, 0]}}, r"base.point: not a field of a free base"),
    ({"base": {"kind": "fixed", "point": [1, 1, 0]}}, r"base.angles: a fixed base needs its orientation"),
    ({"base": {"kind": "fixed", "point": [1, 1, 0], "angles": [0, 0, 0], "rotation": np.eye(3).tolist()}},
     r"base.angles: a fixed base needs its orientation"),
    ({"base": {"kind": "fixed", "point": [1, 1, 0], "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}},
     r"base.rotation: must be a proper rotation matrix"),
    ({"base": {"kind": "pinned", "point": [1, 1, 0], "colour": "red"}},
     r"base: unknown key 'colour'; allowed keys: kind, joint, point, axis, angles, rotation"),
    ({"base": {"kind": "pinned", "joint": "revolute", "point": [1, -0.5, 0], "axis": [0, 0, 1]}},
     r"base.point: the pinned \(revolute\) base holds O_1 at X2 = -0.5, outside the wall x2_min = 0"),
    ({"contacts": {"x2_min": [1, 2]}},
     r"contacts.x2_min: O_1 is held in place by the pinned \(revolute\) base and never touches a wall; "
     r"allowed points: 2, 3, 4"),
    ({"inputs": ["theta_2", "X1"]}, r"inputs: X1 is held by the pinned \(revolute\) base .*allowed: theta_1, "
                                    r"theta_2, theta_3$"),
    ({"initial": {"q": [0.1, 0.2]}}, r"initial.q: expected 8 values \(the layout of Eq. 13\) or the 3 coordinates"),
    ({"initial": {"q": [-math.pi / 2, 0.0, 0.3, -0.4, 0.2, 1.0, 0.7, 0.0]}},
     r"initial.q\[6\] \(X2\): the pinned \(revolute\) base holds it at 0.5 \(base.point\), got 0.7"),
    ({"initial": {"q": [0.0, 0.0, 0.3, -0.4, 0.2, 1.0, 0.5, 0.0]}},
     r"initial.q\[0\] \(theta_-1\): the pinned \(revolute\) base holds it at -1.57079632679 \(base.axis\)"),
    ({"initial": {"q": [0.3, -0.4, 0.2], "qd": [0, 0, 0, 0, 0, 0.5, 0, 0]}},
     r"initial.qd\[5\] \(X1\): the pinned \(revolute\) base holds it at 0 \(a held coordinate has no rate\)"),
]


@pytest.mark.parametrize("changes,message", BAD)
def test_bad_base_is_refused_naming_the_field(changes, message):
    with pytest.raises(SceneError, match=message):
        scene_from_dict(arm(**changes))


def test_fixed_base_of_one_link_is_refused():
    with pytest.raises(SceneError, match=r"base.kind: a fixed base welds link 1 to the box, so a chain of n = 1"):
        scene_from_dict(arm(links=[{"length": 1.0, "mu": 1.0}],
                            base={"kind": "fixed", "point": [1, 1, 0], "angles": [0, 0, 0]}, initial=KeyError))


def test_shipped_mounted_arm_scene():
    scene = load_scene("mounted-arm")
    assert scene.base.kind == "fixed" and scene.base.angles == (-math.pi / 2, 0.0, 0.0)
    points = frames(scene, np.array(scene.q0))[2]
    assert np.array_equal(points[:, 0], [0.0, 1.0, 0.0])           # the post stands up

