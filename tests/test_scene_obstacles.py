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
    assert s.parameter_names()[-2:] == ["e_ball", "e_bar"] and s.parameter_vector()[-2:].tolist() == [0.7, 0.3]
    assert [c.name for c in s.obstacle_contacts()] == ["L1/ball", "L2/ball", "L2/bar"]


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
