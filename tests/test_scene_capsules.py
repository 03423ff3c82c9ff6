"""Capsule links (a radius about the segment O_i -> O_{i+1}): the scene field, the radius a joint point touches a
wall with, and every bad value refused naming its field."""
import copy
import re
import math

import pytest

from codegen.artifact import scene_hash
from codegen.scene import LineLink, RigidLink, Scene, SceneError, Wall, scene_from_dict

GOOD = {
    "name": "capsules",
    "gravity": 9.81,
    "restitution": 0.5,
    "links": [{"length": 1.0, "mu": 1.0, "radius": 0.02},
              {"length": 1.0, "mu": 1.0, "radius": 0.05},
              {"length": 0.5, "mass": 2.0, "com": [0.25, 0.0, 0.0],
               "inertia": [[1e-3, 0, 0], [0, 2e-2, 0], [0, 0, 2e-2]]}],
    "walls": {"x2_min": 0.0, "x1_min": -5.0, "x1_max": 5.0},
    "initial": {"q": [-math.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0]},
}


def mutated(link, key, value):
    data = copy.deepcopy(GOOD)
    data["links"][link][key] = value
    return data


def test_radius_is_read_and_a_joint_point_takes_the_larger():
    scene = scene_from_dict(GOOD)
    assert [link.radius for link in scene.links] == [0.02, 0.05, 0.0]
    assert [scene.point_radius(p) for p in range(1, 5)] == [0.02, 0.05, 0.05, 0.0]
    assert [scene.radius_owner(p) for p in range(1, 5)] == [1, 2, 2, None]


def test_a_zero_radius_keeps_the_scene_hash():
    """Radius 0 is the segment of every scene before capsules: its hash, so its generated text, is unchanged."""
    links = (LineLink(1.0, 1.0), LineLink(0.5, 2.0))
    zero = Scene(name="h", links=tuple(LineLink(l.length, l.mu, l.J, 0.0) for l in links))
    assert scene_hash(Scene(name="h", links=links)) == scene_hash(zero)
    assert scene_hash(Scene(name="h", links=(LineLink(1.0, 1.0, radius=0.1), links[1]))) != scene_hash(zero)


@pytest.mark.parametrize("link, value, words", [
    (0, -0.01, "links[1].radius: must be in [1e-09, 1e+09] m (or 0: a segment of no thickness), got -0.01"),
    (1, "thick", "links[2].radius: expected a number, got 'thick'"),
    (2, float("nan"), "links[3].radius: must be a finite number"),
    (0, 1e-12, "links[1].radius: must be in [1e-09"),
    (1, 2e9, "links[2].radius: must be within"),
])
def test_bad_radius_names_the_field(link, value, words):
    with pytest.raises(SceneError) as info:
        scene_from_dict(mutated(link, "radius", value))
    assert words in str(info.value)


def test_a_capsule_may_touch_a_rough_wall():
    """Its friction acts at the end points' centres (docs/simulation.md, "Capsules"), as a rough obstacle's or link
    pair's acts on the capsules' axes."""
    data = copy.deepcopy(GOOD)
    data["friction"] = {"x2_min": 0.4}
    scene = scene_from_dict(data)
    assert scene.wall("x2_min").friction == 0.4 and 1 in scene.wall("x2_min").points and scene.links[0].radius > 0


def test_a_start_whose_capsule_crosses_a_wall_is_refused():
    data = copy.deepcopy(GOOD)
    data["initial"]["q"] = [-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 0.0, 0.01, 0.0]    # the chain flat at X2 = 0.01
    with pytest.raises(SceneError) as info:
        scene_from_dict(data)
    assert "O_1 has X2 = 0.01, outside the wall x2_min = 0 (its capsule's radius 0.02 m included); allowed X2 >= 0.02" \
        in str(info.value)
    data["initial"]["q"][6] = 0.05                                                        # touching: allowed
    scene_from_dict(data)


def test_rigid_links_take_a_radius_too():
    link = RigidLink(1.0, 1.0, (0.5, 0.0, 0.0), ((1e-3, 0, 0), (0, 0.1, 0), (0, 0, 0.1)), 0.03)
    scene = Scene(name="r", links=(link,), walls=(Wall("x2_min", -1.0),))
    assert scene.point_radius(1) == scene.point_radius(2) == 0.03


def test_contacts_links_chooses_the_link_pairs():
    """[contacts] links names the link pairs that are contacts (in any order, each once); [] leaves them all out; a
    scene without it keeps every possible pair and its hash; a pair that cannot strike, or not a pair, is refused
    naming contacts.links."""
    data = copy.deepcopy(GOOD)
    data["links"].append({"length": 0.5, "mu": 1.0, "radius": 0.03})
    data["initial"]["q"] = data["initial"]["q"][:5] + [0.0] + data["initial"]["q"][5:]
    every = scene_from_dict(data)
    assert every.link_pairs() == every.possible_link_pairs() == [(1, 3), (1, 4), (2, 4)]
    assert every.contact_pairs is None
    data["contacts"] = {"links": [[4, 1], [1, 4], [1, 3]]}
    chosen = scene_from_dict(data)
    assert chosen.link_pairs() == [(1, 3), (1, 4)] and chosen.contact_pairs == ((1, 3), (1, 4))
    assert [pair.name for pair in chosen.link_contacts()] == ["L1-L3", "L1-L4"]
    data["contacts"] = {"links": [], "x2_min": [1, 2]}
    none = scene_from_dict(data)
    assert none.link_pairs() == [] and none.walls == tuple(w if w.name != "x2_min" else
                                                          Wall("x2_min", 0.0, 0.5, (1, 2)) for w in every.walls)
    assert len({scene_hash(every), scene_hash(chosen), scene_hash(none)}) == 3
    assert scene_hash(every) == scene_hash(Scene(**{f: getattr(every, f) for f in every.__dataclass_fields__
                                                    if f != "contact_pairs"}))
    for pairs, words in (([[1, 2]], "links 1 and 2 cannot strike each other (allowed: the pairs of links 1..n, not "
                                    "adjacent, with radii adding up to more than 0: [1, 3], [1, 4], [2, 4]), got [1, 2]"),
                         ([[1, 3, 4]], "expected pairs of link numbers [i, j], got [1, 3, 4]"),
                         ("1-3", "expected a list of link pairs [i, j], got '1-3'")):
        data["contacts"] = {"links": pairs}
        with pytest.raises(SceneError, match=re.escape(f"contacts.links: {words}")):
            scene_from_dict(data)
