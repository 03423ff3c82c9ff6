"""The [[obstacles]] of a scene: their keys, defaults and every bad value refused with a SceneError naming the field
and what it allows; the parameter e_<name> of each; the shipped arm-obstacle scene."""
import pytest

from codegen.scene import SceneError, load_scene, scene_from_dict

BASE = {"links": [{"length": 1.0, "mu": 1.0, "radius": 0.05}] * 2, "walls": {"x2_min": -2.0},
        "restitution": {"default": 0.7}, "initial": {"q": [-1.5707963267948966, 0, 0, 0, 0, 0, 0]}}
BALL = {"name": "ball", "center": [0.5, -1.0, 0.0], "radius": 0.2}


def scene(*obstacles):
    return scene_from_dict({**BASE, "obstacles": list(obstacles)})


def test_defaults_the_scenes_restitution_and_every_link():
    s = scene(BALL, {"name": "bar", "kind": "capsule", "a": [0, 2.5, -1], "b": [0, 2.5, 1], "radius": 0.1,
                     "restitution": 0.3, "links": [2]})
    ball, bar = s.obstacles
    assert (ball.kind, ball.segment, ball.restitution, ball.links) == ("sphere", ((0.5, -1.0, 0.0),) * 2, 0.7, (1, 2))
    assert (bar.segment, bar.restitution, bar.links) == (((0.0, 2.5, -1.0), (0.0, 2.5, 1.0)), 0.3, (2,))
    names, values = s.parameter_names(), s.parameter_vector().tolist()
    assert names[-13:-11] == ["e_ball", "e_bar"] and values[-13:-11] == [0.7, 0.3]
    assert names[-11:] == ["center_x_ball", "center_y_ball", "center_z_ball", "radius_ball", "a_x_bar", "a_y_bar",
                           "a_z_bar", "b_x_bar", "b_y_bar", "b_z_bar", "radius_bar"]       # the geometry, after e
    assert values[-11:] == [0.5, -1.0, 0.0, ball.radius, 0.0, 2.5, -1.0, 0.0, 2.5, 1.0, 0.1]
    assert [c.name for c in s.obstacle_contacts()] == ["L1/ball", "L2/ball", "L2/bar", "O2/bar", "O3/bar"]


@pytest.mark.parametrize("change, message", [
    ({"radius": 0.0}, "obstacles[1] (ball).radius: must be in [1e-09, 1e+09] m"),
    ({"radius": -1.0}, "obstacles[1] (ball).radius"),
    ({"center": [0.0, float("nan"), 0.0]}, "obstacles[1] (ball).center[1]: must be a finite number"),
    ({"center": [0.0, 1.0]}, "obstacles[1] (ball).center: expected a list of 3 numbers"),
    ({"kind": "cube"}, "obstacles[1].kind: one of 'sphere', 'capsule'"),
    ({"restitution": 1.5}, "obstacles[1] (ball).restitution: must be in [0, 1]"),
    ({"links": [3]}, "obstacles[1] (ball).links: link numbers must be integers in 1..2"),
    ({"links": [1, 1]}, "obstacles[1] (ball).links: a link is named twice"),
    ({"name": "x2_min"}, "obstacles[1].name: 'x2_min' is taken"),
    ({"name": "post2"}, "obstacles[1].name: 1..24 letters"),
    ({"colour": "red"}, "colour"),
    ({"center": [0.1, 0.5, 0.0]}, "initial.q: link 1 overlaps the obstacle ball"),
    ({"a": [0, 0, 0]}, "obstacles[1].a: a sphere takes center"),
])
def test_bad_obstacles_are_refused_by_field(change, message):
    with pytest.raises(SceneError, match=message.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")
                       .replace("+", r"\+")):
        scene({**BALL, **change})


def test_names_are_unique_and_a_capsule_needs_its_ends():
    with pytest.raises(SceneError, match=r"obstacles\[2\]\.name: 'ball' is given twice"):
        scene(BALL, BALL)
    with pytest.raises(SceneError, match=r"obstacles\[1\]\.b: required for a capsule"):
        scene({"name": "bar", "kind": "capsule", "a": [0, 2, 0], "radius": 0.1})


def test_the_shipped_arm_obstacle_scene():
    s = load_scene("arm-obstacle")
    (ball,) = s.obstacles
    assert s.base.kind == "fixed" and ball.links == (2, 3)      # the post is welded: it strikes nothing
    assert "e_ball" in s.parameter_names()
    with pytest.raises(SceneError, match=r"obstacles\[1\] \(ball\)\.links: link 1 is welded to the box"):
        scene_from_dict({"links": [{"length": 0.6, "mu": 2.0}, {"length": 0.6, "mu": 1.0}],
                         "base": {"kind": "fixed", "point": [1.0, 0.0, 0.0], "angles": [0.0, 0.0, 0.0]},
                         "obstacles": [{**BALL, "center": [2.0, 2.0, 0.0], "links": [1]}]})


BOX = {"name": "block", "kind": "box", "center": [0.5, -1.0, 0.0], "half_extents": [0.3, 0.2, 0.4]}
ROOF = {"name": "roof", "kind": "plane", "point": [0.0, 3.0, 0.0], "normal": [0.6, -0.8, 0.0]}
TURN = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]     # a quarter turn about X3


def test_a_box_and_a_plane_take_their_own_fields():
    s = scene({**BOX, "rotation": TURN, "restitution": 0.4}, ROOF)
    block, roof = s.obstacles
    assert (block.kind, block.a, block.half_extents, block.rotation, block.radius) == (
        "box", (0.5, -1.0, 0.0), (0.3, 0.2, 0.4), tuple(map(tuple, TURN)), 0.0)
    assert block.shape[:7] == (1.0, 0.5, -1.0, 0.0, 0.3, 0.2, 0.4) and block.shape[7:16] == tuple(
        float(x) for row in TURN for x in row)
    assert (roof.kind, roof.a, roof.normal, roof.restitution) == ("plane", (0.0, 3.0, 0.0), (0.6, -0.8, 0.0), 0.7)
    assert roof.shape[:7] == (2.0, 0.0, 3.0, 0.0, 0.6, -0.8, 0.0)
    assert scene(BOX).obstacles[0].box_rotation == ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    assert s.parameter_names()[-23:-21] == ["e_block", "e_roof"]              # then the geometry: 15 + 6 entries
    assert [c.radius for c in s.obstacle_contacts()] == [0.05] * 8      # the links' radii alone
    # a box's contacts are its links' and its joint points', a plane's its joint points' (each on the link that
    # carries it)
    assert [c.name for c in s.obstacle_contacts()] == ["L1/block", "L2/block", "O1/block", "O2/block", "O3/block",
                                                       "O1/roof", "O2/roof", "O3/roof"]
    assert [(c.i, c.end) for c in s.obstacle_contacts()[2:5]] == [(1, 1), (1, 2), (2, 2)]


@pytest.mark.parametrize("obstacle, message", [
    ({**BOX, "half_extents": [0.3, 0.0, 0.4]}, "obstacles[1] (block).half_extents[1]: must be in [1e-09, 1e+09] m"),
    ({**BOX, "half_extents": [0.3, 0.2]}, "obstacles[1] (block).half_extents: expected a list of 3 numbers"),
    ({**BOX, "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}, "obstacles[1] (block).rotation: must be a proper "
                                                              "rotation (det +1 within 1e-09), got det -1"),
    ({**BOX, "rotation": [[1, 0, 0], [0, 1, 1e-6], [0, 0, 1]]}, "obstacles[1] (block).rotation: must be orthonormal"),
    ({**BOX, "rotation": [[1, 0, 0], [0, 1, 0]]}, "obstacles[1] (block).rotation: expected 3 rows of 3 numbers"),
    ({**BOX, "radius": 0.1}, "obstacles[1].radius: a box takes center, half_extents, rotation, not radius"),
    ({**BOX, "normal": [0, 1, 0]}, "obstacles[1].normal: a box takes center, half_extents, rotation, not normal"),
    ({k: v for k, v in BOX.items() if k != "half_extents"}, "obstacles[1].half_extents: required for a box"),
    ({**BOX, "center": [0.1, -0.1, 0.0]}, "initial.q: link 1 overlaps the box block by 0.15 m"),
    ({**ROOF, "normal": [0.6, -0.8, 0.1]}, "obstacles[1] (roof).normal: must be a unit vector (length 1 within "
                                           "1e-09), got [0.6, -0.8, 0.1] of length 1.00498756211208"),
    ({**ROOF, "normal": [0.6, -0.8, 0.1]}, "; normalised: [0.59702231412599349, -0.79602975216799143, 0.0995"),
    ({**ROOF, "normal": [0, 0, 0]}, "obstacles[1] (roof).normal: must be a unit vector"),
    ({**ROOF, "center": [0, 1, 0]}, "obstacles[1].center: a plane takes point, normal, not center"),
    ({k: v for k, v in ROOF.items() if k != "normal"}, "obstacles[1].normal: required for a plane"),
    ({**ROOF, "point": [0.0, 0.5, 0.0]}, "initial.q: O_2 (an end of link 1) overlaps the plane roof by"),
    ({**BALL, "normal": [0, 1, 0]}, "obstacles[1].normal: a sphere takes center, radius, not normal"),
])
def test_bad_boxes_and_planes_are_refused_by_field(obstacle, message):
    with pytest.raises(SceneError, match=message.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")
                       .replace("+", r"\+").replace(".", r"\.")):
        scene(obstacle)


def test_box_and_plane_obstacles_built_in_python_are_checked_alike():
    from codegen.scene import Obstacle, Scene
    links, q0 = scene(BALL).links, scene(BALL).q0
    with pytest.raises(SceneError, match=r"obstacles\[1\] \(block\)\.radius: a box has none"):
        Scene(name="s", links=links, q0=q0, obstacles=(Obstacle("block", "box", (0.5, -1, 0), None, 0.1,
                                                                half_extents=(0.3, 0.2, 0.4)),))
    s = Scene(name="s", links=links, q0=q0, obstacles=(Obstacle.box("block", (0.5, -1.0, 0.0), (0.3, 0.2, 0.4), TURN),
                                                       Obstacle.plane("roof", (0, 3, 0), (0.6, -0.8, 0))))
    assert [o.kind for o in s.obstacles] == ["box", "plane"]
