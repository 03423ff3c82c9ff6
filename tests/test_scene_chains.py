"""A scene of several chains ([[chains]], codegen.scene.Chains): what it reads, the numbering of its points, links and
parameters, and the errors that name the field (no model is built here)."""
import math

import pytest

from codegen.scene import Chains
from codegen.scene import SceneError, load_scene, scene_from_dict
from codegen.specialise import layout_for


def chain(x=0.5, links=None, **extra):
    return dict({"links": links or [{"length": 0.3, "mu": 1.0, "radius": 0.04}],
                 "initial": {"q": [-math.pi / 2, 0.0, 0.3, x, 0.5, 0.0], "qd": [0.0] * 6}}, **extra)


def box(*chains, **extra):
    return dict({"name": "pair", "gravity": 9.81, "walls": {"x1_min": 0.0, "x1_max": 3.0, "x2_min": 0.0},
                 "restitution": {"default": 0.6, "links": 0.8}, "chains": list(chains)}, **extra)


def test_the_shipped_scene_reads_as_two_chains_sharing_the_box():
    scene = load_scene("two-chains")
    assert isinstance(scene, Chains) and [c.n for c in scene.chains] == [3, 2]
    assert scene.npoint == 7 and scene.point_offset(2) == 4
    assert scene.link_restitution == 0.8
    assert all(c.walls[0].position == 0.0 and c.gravity == 9.81 for c in scene.chains)
    # links are numbered by their first point: chain 2's links are 5 and 6; every pair across the chains is a contact
    assert [(p.i, p.j) for p in scene.cross_link_pairs()] == [(i, j) for i in (1, 2, 3) for j in (5, 6)]
    assert scene.chain_of_link(5) == (2, 1)
    with pytest.raises(SceneError, match="link 4: no link starts at global point O_4"):
        scene.chain_of_link(4)


def test_parameters_are_the_boxs_once_then_each_chains_with_its_prefix():
    scene = scene_from_dict(box(chain(0.5), chain(2.0)))
    names = scene.parameter_names()
    assert names[:4] == ["g", "wall_x1_min", "wall_x1_max", "wall_x2_min"]
    assert "c1.l_1" in names and "c2.l_1" in names and "l_1" not in names
    assert scene.parameter_index("l", 2) == names.index("c2.l_1")       # the second link of all: chain 2's first
    assert scene.parameter_vector()[scene.parameter_map(2)].tolist() == scene.chains[1].parameter_vector().tolist()


def test_the_layout_stacks_each_chains_own():
    scene = scene_from_dict(box(chain(0.5), chain(2.0)))
    layout = layout_for(scene)
    own = [layout_for(c) for c in scene.chains]
    assert layout.nq == sum(l.nq for l in own)
    assert layout.free == own[0].free + tuple(6 + i for i in own[1].free)
    assert [p for p, _ in layout.contacts] == [p for p, _ in own[0].contacts] + [2 + p for p, _ in own[1].contacts]


def test_inputs_are_each_chains_with_its_prefix_one_after_the_other():
    scene = scene_from_dict(box(chain(0.5, inputs=["theta_1"]), chain(2.0, inputs=["X1", "theta_1"])))
    assert scene.inputs == ("c1.theta_1", "c2.X1", "c2.theta_1") and scene.nu == 3 and scene.driven
    assert scene.input_coordinates() == [2, 6 + 3, 6 + 2]          # the combined full layout's places


@pytest.mark.parametrize("data, message", [
    (box(chain(0.5), chain(2.0, links=[{"length": -1.0, "mu": 1.0}])), r"chains\[2\]\.links\[1\]"),
    (box(chain(0.5), dict(chain(2.0), colour="red")), r"chains\[2\]\.colour: unknown key"),
    (box(chain(0.5), {"initial": {"q": [0.0] * 6}}), r"chains\[2\]\.links: each chain needs"),
    (box(chain(0.5), chain(2.0), links=[{"length": 1.0, "mu": 1.0}]), r"^links: a scene with \[\[chains\]\]"),
    (box(chain(0.5)), r"chains: several chains means 2\.\."),
    (box(chain(0.5), chain(2.0, inputs=["theta_3"])), r"chains\[2\]\.inputs"),
    (box(chain(0.5), chain(0.52)), r"chains\[2\]\.initial\.q: link 1 of chain 2 overlaps link 1 of chain 1"),
    (box(chain(0.5), dict(chain(2.0), initial={"q": [0.0] * 5})), r"chains\[2\]\.initial\.q"),
    (box(chain(0.5), chain(2.0), restitution={"default": 0.5, "links": 1.5}), r"^restitution\.links"),
    (box(chain(0.5), chain(2.0), walls={"x1_min": 1.0, "x1_max": 0.5}), r"^walls"),
])
def test_errors_name_the_field(data, message):
    with pytest.raises(SceneError, match=message):
        scene_from_dict(data)


def test_what_does_not_compose_yet_is_refused_before_any_derivation():
    from codegen import generate
    from codegen.options import build_options
    planar = scene_from_dict(box(chain(0.5), chain(2.0)))
    with pytest.raises(SceneError, match="^formulation: a scene of several chains"):
        generate(planar, build_options(planar, formulation="lagrange"))


def test_obstacles_are_the_boxs_and_every_chains_links_strike_them():
    from codegen.scene import ObstacleContact
    scene = scene_from_dict(box(chain(0.5), chain(2.0), obstacles=[{"name": "ball", "center": [1.2, 1.5, 0.0],
                                                                    "radius": 0.1, "restitution": 0.4}]))
    assert scene.parameter_names().count("e_ball") == 1
    hits = [c for c in scene.rowless_contacts() if isinstance(c, ObstacleContact)]
    assert [c.name for c in hits] == ["L1/ball", "L3/ball"]          # chain 2's link 1 is global link 3
    assert scene.rowless_contacts()[0].name == "L1-L3"                  # the pair across the chains first
