"""Scene validation: every bad value is rejected with a message naming the field and the range."""
import copy
import json
import math

import numpy as np
import pytest

from codegen.scene import (LineLink, RigidLink, Scene, SceneError, Wall, contact_points, default_scene,
                           load_scene, scene_from_dict)

GOOD = {
    "name": "ok",
    "gravity": 9.81,
    "restitution": 0.8,
    "links": [{"length": 1.0, "mu": 1.0, "J": [1e-5, 1e-5, 1e-5], "count": 2},
              {"length": 0.5, "mass": 2.0, "com": [0.25, 0.0, 0.0],
               "inertia": [[1e-3, 0, 0], [0, 2e-2, 0], [0, 0, 2e-2]], "twist": 0.4}],
    "walls": {"x2_min": 0.0, "x1_min": -5.0, "x1_max": 5.0},
    "contacts": {"x2_min": [1, 4]},
    "initial": {"q": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0], "qd": [0.0] * 8},
}


def mutated(path, value):
    data = copy.deepcopy(GOOD)
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


def test_good_scene_loads():
    scene = scene_from_dict(GOOD)
    assert scene.n == 3 and scene.nq == 8
    assert [w.name for w in scene.walls] == ["x1_min", "x1_max", "x2_min"]
    assert scene.wall("x2_min").points == (1, 4) and scene.wall("x1_min").points == (1, 2, 3, 4)
    assert scene.wall("x1_max").restitution == 0.8
    assert np.allclose(np.array(scene.twists[1]), [[1, 0, 0], [0, math.cos(0.4), -math.sin(0.4)],
                                                   [0, math.sin(0.4), math.cos(0.4)]])


@pytest.mark.parametrize("path,value,field", [
    (("links", 0, "length"), -1.0, "links[1].length"),
    (("links", 0, "length"), 0.0, "links[1].length"),
    (("links", 0, "length"), float("nan"), "links[1].length"),
    (("links", 0, "mu"), 0.0, "links[1].mu"),
    (("links", 0, "mu"), float("nan"), "links[1].mu"),
    (("links", 0, "J"), [1e-5, -1e-5, 0.0], "links[1].J"),
    (("links", 1, "mass"), -2.0, "links[3].mass"),
    (("links", 1, "mass"), 0.0, "links[3].mass"),
    (("links", 1, "mass"), float("nan"), "links[3].mass"),
    (("links", 1, "inertia"), [[1, 0, 0], [0, 1, 0], [0, 0, 5]], "links[3].inertia"),
    (("links", 1, "twist_matrix"), [[2, 0, 0], [0, 1, 0], [0, 0, 1]], "links[3]"),
    (("links", 0, "twist"), 0.3, "links[1].twist"),
    (("links",), [], "links"),
    (("restitution",), 1.5, "restitution"),
    (("restitution",), -0.1, "restitution"),
    (("restitution",), {"x2_min": 2.0, "default": 1.0}, "restitution.x2_min"),
    (("restitution",), {"x2_min": 0.5}, "restitution.x1_min"),
    (("walls", "x1_max"), -6.0, "walls.x1_max"),
    (("walls", "x4_min"), 0.0, "walls"),
    (("contacts", "x2_min"), [0], "contacts.x2_min"),
    (("contacts", "x2_min"), [6], "contacts.x2_min"),
    (("contacts", "x3_min"), [1], "contacts.x3_min"),
    (("gravity",), "down", "gravity"),
    (("gravity_direction",), [0.0, 0.0, 0.0], "gravity_direction"),
    (("gravity_direction",), [0.0, -2.0, 0.0], "gravity_direction"),
    (("gravity_direction",), [0.0, -1.0], "gravity_direction"),
    (("gravity_direction",), [0.0, float("inf"), 0.0], "gravity_direction[1]"),
    (("gravity_direction",), [0.0, "down", 0.0], "gravity_direction[1]"),
    (("initial", "q"), [0.0] * 5, "initial.q"),
    (("initial", "q"), [0.0, math.pi / 2, 0, 0, 0, 0, 0.5, 0.0], "initial.q[1]"),
    (("initial", "X"), [0.0], "initial"),
    (("colour",), "red", "scene"),
    (("links", 0, "colour"), "red", "links[1]"),
    (("name",), "1bad name", "name"),
])
def test_bad_values_name_the_field(path, value, field):
    with pytest.raises(SceneError) as info:
        scene_from_dict(mutated(path, value))
    assert str(info.value).startswith(field), str(info.value)


def test_gravity_direction_is_a_unit_vector_and_keeps_default_scenes_hashes():
    """gravity_direction: a unit vector (length 1 within 1e-9; the error gives the normalised one); the default -X2
    leaves a scene's hash (its generated text and compiled model) as it was, any other direction changes it."""
    from codegen.artifact import scene_hash
    with pytest.raises(SceneError, match=r"gravity_direction: must be a unit vector .*normalised: \[0\.6, -0\.8, 0\.0\]"):
        scene_from_dict(mutated(("gravity_direction",), [3.0, -4.0, 0.0]))
    tilt = [math.sin(0.4), -math.cos(0.4), 0.0]
    assert scene_from_dict(mutated(("gravity_direction",), tilt)).gravity_direction == tuple(tilt)
    assert scene_from_dict(mutated(("gravity_direction",), [0.0, -1.0 + 5e-10, 0.0])).gravity_direction[1] < -0.999
    default = scene_from_dict(GOOD)
    assert default.gravity_direction == (0.0, -1.0, 0.0)
    assert scene_hash(scene_from_dict(mutated(("gravity_direction",), [0, -1, -0.0]))) == scene_hash(default)
    assert scene_hash(scene_from_dict(mutated(("gravity_direction",), tilt))) != scene_hash(default)



def test_a_planar_chain_stays_a_planar_model_only_with_gravity_in_its_plane():
    from codegen.specialise import planar_normal
    planar = mutated(("links", 1, "twist"), 0.0)
    planar["initial"]["q"][0] = -math.pi / 2                  # joint axes along X3: the X1-X2 plane
    assert planar_normal(scene_from_dict(planar)) == (2, "")
    planar["gravity_direction"] = [math.sin(0.4), -math.cos(0.4), 0.0]
    assert planar_normal(scene_from_dict(planar)) == (2, "")
    planar["gravity_direction"] = [0.0, -math.cos(0.4), math.sin(0.4)]
    assert planar_normal(scene_from_dict(planar)) == (None, "gravity (gravity_direction) has a component along X3, "
                                                            "out of the plane")


def test_initial_contact_point_outside_the_box_is_rejected():
    data = mutated(("initial", "q"), [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.0])   # O_1 below the floor
    with pytest.raises(SceneError, match=r"initial.q: contact point O_1 has X2 = -0.5.*x2_min"):
        scene_from_dict(data)
    # chain along +X1 from X1 = 4 (theta_-1 = theta_1 = -pi/2): O_3 and O_4 lie beyond x1_max = 5
    data = mutated(("initial", "q"), [-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 4.0, 0.5, 0.0])
    with pytest.raises(SceneError, match=r"contact point O_\d has X1 .* outside the wall x1_max"):
        scene_from_dict(data)


def test_zero_links_is_rejected():
    with pytest.raises(SceneError, match="n >= 1"):
        Scene(name="empty", links=())
    with pytest.raises(SceneError, match="links: n must be an integer >= 1"):
        default_scene(0)


def test_dataclass_construction_validates_too():
    with pytest.raises(SceneError, match=r"links\[1\].length: must be in \[1e-09, 1e\+09\] m"):
        Scene(name="x", links=(LineLink(-1.0, 1.0),))
    with pytest.raises(SceneError, match=r"restitution.x2_min: must be in \[0, 1\]"):
        Scene(name="x", links=(LineLink(1.0, 1.0),), walls=(Wall("x2_min", -1.0, 1.2),))
    with pytest.raises(SceneError, match=r"links\[1\].inertia: must be symmetric"):
        RigidLink(1.0, 1.0, (0, 0, 0), ((1, 0.5, 0), (0, 1, 0), (0, 0, 1))).validate("links[1]")


def test_json_and_toml_give_the_same_scene(tmp_path):
    path = tmp_path / "s.json"
    path.write_text(json.dumps(GOOD))
    assert load_scene(path) == scene_from_dict(GOOD)
    toml = tmp_path / "bad.toml"
    toml.write_text("name = \n")
    with pytest.raises(SceneError, match="cannot parse"):
        load_scene(toml)


def test_paper_scenes_start_as_in_the_paper():
    case1 = load_scene("paper-case1")
    points = contact_points(case1, np.array(case1.q0))
    assert np.allclose(points[0], points[-1])                # O_1 and O_5 coincide: the square
    assert np.allclose(points[:, 0], [1.5, 1.5 - 0.5 ** 0.5, 1.5, 1.5 + 0.5 ** 0.5, 1.5])
    assert np.allclose(points[:, 2], 0.0)                    # planar in X1-X2
    case2 = load_scene("paper-case2")
    points = contact_points(case2, np.array(case2.q0))
    # R_1 = Ry(pi/6) Rz(0) Rx(pi/6) T_1: the link direction is Ry(pi/6) (0, cos 30, sin 30)
    s, c = 0.5, math.sqrt(3) / 2
    assert np.allclose(points[1] - points[0], 0.5 * np.array([s * s, c, s * c]))


def test_default_scene_for_four_links_is_case_one():
    default, case1 = default_scene(4), load_scene("paper-case1")
    assert default.links == case1.links and default.walls == case1.walls
    assert np.allclose(default.q0, case1.q0, atol=1e-12)
    for n in (1, 2, 3, 8, 32):
        scene = default_scene(n)                                 # always starts inside its box
        assert scene.n == n


@pytest.mark.parametrize("name", ["paper-case1", "driven-fold", "rough-floor", "urdf-arm"])
def test_parameter_names_compose_and_split_back(name):
    """Every parameter name is codegen.scene.parameter_name(kind, owner), and split_parameter_name reads it back."""
    from codegen.scene import parameter_name, split_parameter_name
    scene = load_scene(name)
    for index, pname in enumerate(scene.parameter_names()):
        kind, owner = split_parameter_name(pname)
        assert parameter_name(kind, owner) == pname and scene.parameter_index(kind, owner) == index
    with pytest.raises(SceneError, match="friction_x2_max: this scene has no such parameter"):
        scene.parameter_index("friction", "x2_max")
