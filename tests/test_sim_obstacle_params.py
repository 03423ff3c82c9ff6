"""Obstacles' geometry as runtime parameters (center_x_<name> ... radius_<name>, half_x_<name>, rotation_11_<name>
..., point_x_<name>, normal_x_<name>; codegen.scene.OBSTACLE_PARAMETERS): one compiled model run with its sphere, bar,
box and plane moved (and the box and the plane turned) through p gives bit for bit what a model built with them
there gives; the values no obstacle can have are refused by simulate() and by the C parameter check, each naming the
parameter and its range; a planar model holds the geometry that keeps an obstacle symmetric about its plane; the
sensitivities take an obstacle's position and size as directions but not a box's rotation or a plane's normal; the
scene's defaults are the model's p."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene, load_scene
from runtime import load_model, simulate
from runtime.sensitivities import directions

TOL = dict(rtol=1e-10, atol=1e-12)
RADII = (0.05, 0.0, 0.04)
TWISTS = (((1.0, 0, 0), (0, 0.0, -1.0), (0, 1.0, 0.0)), ((1.0, 0, 0), (0, 0.6, -0.8), (0, 0.8, 0.6)))


def turn(axis, angle) -> tuple:
    """The rotation by ``angle`` about unit ``axis`` (Rodrigues), rows as tuples."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    return tuple(tuple(float(x) for x in row) for row in R)


def obstacles(moved: bool) -> tuple:
    """A ball, a bar, a turned box and a slanted plane around a tumbling chain; ``moved``: each one elsewhere (the box
    and the plane turned further, the ball and the bar resized)."""
    d = 0.1 if moved else 0.0
    normal = np.array([0.1, -1.0, 0.05 + d])
    return (Obstacle.sphere("ball", (0.4 - d, 1.2, 0.1 + d), 0.25 + d),
            Obstacle.bar("bar", (-1.5 + d, 0.8, -1.0), (-1.4, 0.9 - d, 1.0), 0.06 + d / 2),
            Obstacle.box("block", (-0.5, -1.0 + d, 0.1), (0.3, 0.2 + d, 0.4), turn((1, 2, 3), 0.4 + d)),
            Obstacle.plane("roof", (0.0, 2.6 - d, 0.0), tuple(normal / np.linalg.norm(normal))))


def chain(moved: bool) -> Scene:
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), r) for l, mu, r in zip((1.0, 0.7, 0.9), (1.0, 2.0, 0.5), RADII))
    return Scene(name="obstacle_moved" if moved else "obstacle_params", links=links, twists=TWISTS, gravity=0.0,
                 q0=tuple(tumbling_start(12)[0]), obstacles=obstacles(moved), obstacle_restitution=0.8, contact_pairs=())


@pytest.fixture(scope="module")
def model():
    return load_model(chain(False))


@pytest.fixture(scope="module")
def moved_model():
    return load_model(chain(True))


def moved_parameters(model) -> np.ndarray:
    """model's p with every obstacle where chain(True) has it, set by name."""
    return model.parameters({name: value for o in obstacles(True)
                             for name, value in zip(o.geometry_names, o.geometry_values)})


def tumbling_start(seed: int):
    rng = np.random.default_rng(seed)
    q0 = np.zeros(8)
    q0[3:5] = rng.uniform(-2.0, 2.0, 2)
    q0[5:8] = (-0.6, 0.1, 0.0)
    qd0 = np.concatenate([rng.uniform(-1.0, 1.0, 3), rng.choice([-1, 1], 2) * rng.uniform(3.0, 6.0, 2),
                          (0.2, 0.0, 0.0)])
    return q0, qd0


def test_the_geometry_is_named_after_e_and_friction_with_the_scenes_values(model):
    names = model.parameter_names
    assert names[names.index("e_roof") + 1:] == [
        "center_x_ball", "center_y_ball", "center_z_ball", "radius_ball",
        "a_x_bar", "a_y_bar", "a_z_bar", "b_x_bar", "b_y_bar", "b_z_bar", "radius_bar",
        "center_x_block", "center_y_block", "center_z_block", "half_x_block", "half_y_block", "half_z_block",
        *(f"rotation_{i}{j}_block" for i in (1, 2, 3) for j in (1, 2, 3)),
        "point_x_roof", "point_y_roof", "point_z_roof", "normal_x_roof", "normal_y_roof", "normal_z_roof"]
    assert model.p[names.index("radius_ball")] == 0.25 and model.p[names.index("rotation_23_block")] == \
        turn((1, 2, 3), 0.4)[1][2]
    assert np.array_equal(moved_parameters(model)[names.index("center_x_ball"):],
                          chain(True).parameter_vector()[names.index("center_x_ball"):])
    for o, kind in enumerate(("sphere", "capsule", "box", "plane")):          # the C library's view of p
        first = names.index(model.scene.obstacles[o].geometry_names[0])
        assert [model.lib.gac_obstacle_parameter(model.ffi.addressof(model.c.model), first + k)
                for k in (-1, 0)] == [o - 1 if o else -1, o] and model.scene.obstacles[o].kind == kind
    shape = np.zeros(16)
    p = moved_parameters(model)
    for o, obstacle in enumerate(obstacles(True)):
        assert model.lib.gac_obstacle_shape(model.ffi.addressof(model.c.model), model._ptr(p), o,
                                            model._ptr(shape)) == model.lib.GAC_OK
        assert shape.tolist() == list(obstacle.shape)


def test_moved_obstacles_give_the_gaps_of_a_model_built_with_them_there(model, moved_model):
    """Every contact's gap and J^T n, bit for bit, on random states: the geometry through p is the geometry built in."""
    p = moved_parameters(model)
    rng = np.random.default_rng(5)
    for _ in range(40):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-1.5, 1.5, 3)])
        assert np.array_equal(model.contact_gaps(q, p), moved_model.contact_gaps(q))
        assert not np.array_equal(model.contact_gaps(q), moved_model.contact_gaps(q))
        for c in range(len(model.contacts)):
            assert np.array_equal(model.contact_normal(q, c, p), moved_model.contact_normal(q, c))


@pytest.mark.parametrize("seed, struck", [(12, {"bar"}), (23, {"ball", "roof"})])
def test_a_run_among_moved_obstacles_is_the_run_of_a_model_built_with_them(model, moved_model, seed, struck):
    q0, qd0 = tumbling_start(seed)
    moved = simulate(model, 2.0, p=moved_parameters(model), q0=q0, qd0=qd0, **TOL)
    built = simulate(moved_model, 2.0, q0=q0, qd0=qd0, **TOL)
    assert moved.status == built.status == 0, (moved.message, built.message)
    assert len(built.impacts) >= 2
    assert {c.wall.partition("/")[2] for i in built.impacts for c in i.contacts} == struck
    assert np.array_equal(moved.q, built.q) and np.array_equal(moved.qd, built.qd)
    assert [(i.t, [c.wall for c in i.contacts]) for i in moved.impacts] == \
        [(i.t, [c.wall for c in i.contacts]) for i in built.impacts]
    unmoved = simulate(model, 2.0, q0=q0, qd0=qd0, **TOL)
    assert not np.array_equal(unmoved.q, built.q)


def test_a_box_and_a_plane_moved_and_turned_are_struck_where_p_puts_them(model, moved_model):
    """A chain thrown down at the box and one up at the plane, from the scene's start."""
    p = moved_parameters(model)
    q0 = model.layout.reduce(model.scene.q0)
    for qd0, name in (((0, 0, 0, 0, 0, 0.0, -2.0, 0.0), "block"), ((0, 0, 0, 0, 0, 0.3, 2.0, 0.0), "roof")):
        moved = simulate(model, 1.5, p=p, q0=q0, qd0=np.array(qd0, float), **TOL)
        built = simulate(moved_model, 1.5, q0=q0, qd0=np.array(qd0, float), **TOL)
        assert moved.status == built.status == 0, (moved.message, built.message)
        assert any(c.wall.endswith("/" + name) for i in built.impacts for c in i.contacts), name
        assert np.array_equal(moved.q, built.q)


BAD = [   # an override, simulate()'s message, the C check's (parameter_problem)
    ({"radius_ball": 0.0}, r"p\[radius_ball\]: must be in \[1e-09, 1e\+09\] m \(> 0\), got 0.0",
     "p[radius_ball]: must be in [1e-09, 1e+09] m (> 0), got 0.0"),
    ({"radius_bar": -0.1}, r"p\[radius_bar\]: must be in \[1e-09, 1e\+09\] m \(> 0\), got -0.1",
     "p[radius_bar]: must be in [1e-09, 1e+09] m (> 0), got -0.1"),
    ({"half_y_block": 0.0}, r"p\[half_y_block\]: must be in \[1e-09, 1e\+09\] m \(> 0\), got 0.0",
     "p[half_y_block]: must be in [1e-09, 1e+09] m (> 0), got 0.0"),
    ({"radius_ball": math.nan}, r"p: expected \d+ finite values", "p[radius_ball]: must be in [1e-09, 1e+09] m (> 0), "
     "got nan"),
    ({"center_x_ball": math.inf}, r"p: expected \d+ finite values",
     "p[center_x_ball]: must be within [-1e+09, 1e+09] m, got inf"),
    ({"rotation_11_block": 0.5}, r"p\[rotation_11_block \.\. rotation_33_block\]: the rotation of box block must be a "
     r"proper rotation \(orthonormal within 1e-09, det \+1 within 1e-09\); R\^T R departs from I by 0.609",
     "p[rotation_11_block]: must be within [-2, 2]; rotation_11_block .. rotation_33_block together a proper rotation "
     "(orthonormal within 1e-09, det +1 within 1e-09), got 0.5"),
    ({"normal_y_roof": -0.9}, r"p\[normal_x_roof \.\. normal_z_roof\]: the normal of plane roof must be a unit vector "
     r"\(length 1 within 1e-09\), got length 0.9",
     "p[normal_x_roof]: must be within [-2, 2]; normal_x_roof .. normal_z_roof together a unit vector (length 1 within "
     "1e-09), got "),
]


@pytest.mark.parametrize("override, message, c_message", BAD)
def test_impossible_geometry_is_refused_naming_the_parameter(model, override, message, c_message):
    p = model.parameters(override)
    with pytest.raises(ValueError, match=message):
        simulate(model, 0.1, p=p)
    assert model.parameter_problem(p).startswith(c_message)            # the C check (NAME_check_parameters)


def test_a_reflection_and_an_overlapping_start_are_refused(model):
    names = model.parameter_names
    p = model.p.copy()
    first = names.index("rotation_11_block")
    p[first:first + 9] = (-np.array(turn((1, 2, 3), 0.4))).ravel()        # orthonormal, det -1
    with pytest.raises(ValueError, match=r"rotation of box block must be a proper rotation .* got det -1"):
        simulate(model, 0.1, p=p)
    assert model.parameter_problem(p).startswith("p[rotation_11_block]:")
    points = model.contact_points(model.layout.reduce(model.scene.q0))
    ball = model.parameters({"center_x_ball": points[1][0], "center_y_ball": points[1][1],
                             "center_z_ball": points[1][2]})           # the ball moved onto joint 2
    with pytest.raises(ValueError, match=r"link 1 overlaps the obstacle ball: .* less than their radii 0.3 m"):
        simulate(model, 0.1, p=ball)


def test_sensitivities_take_an_obstacles_place_and_size_but_not_its_turning(model):
    """A box's rotation entries and a plane's normal entries are refused as directions (each naming itself: no entry
    moves alone); the position and size of every kind are directions."""
    for name in ("rotation_12_block", "normal_y_roof"):
        with pytest.raises(ValueError, match=rf"sensitivities\[1\] = '{name}': a box's rotation entry or a plane's "
                                             r"normal entry is not a direction"):
            directions(model, ["e_ball", name])
    taken = ["e_ball", "radius_ball", "center_x_ball", "a_y_bar", "b_z_bar", "radius_bar", "center_y_block",
             "half_x_block", "point_y_roof"]
    names, _, seed_p = directions(model, taken)
    assert names == taken
    for j, name in enumerate(taken):
        assert seed_p[j, model.parameter_names.index(name)] == 1.0 and seed_p[j].sum() == 1.0


def test_a_planar_model_holds_the_geometry_that_keeps_an_obstacle_in_its_plane():
    """arm-obstacle (planar in X1-X2): its ball's centre_z is held, centre_x and the radius move."""
    planar = load_model(load_scene("arm-obstacle"), specialise=True)
    assert planar.layout.held_params == ("center_z_ball",)
    with pytest.raises(ValueError, match=r"p\[center_z_ball\]: this planar model holds center_z_ball = 0.0"):
        simulate(planar, 0.1, p=planar.parameters({"center_z_ball": 0.01}))
    assert planar.parameter_problem(planar.parameters({"center_z_ball": 0.01})).startswith(
        "p[center_z_ball]: held at the scene's value 0.0 by this planar model")
    near = simulate(planar, 3.0, **TOL)
    far = simulate(planar, 3.0, p=planar.parameters({"center_y_ball": 5.0, "radius_ball": 0.05}), **TOL)
    on_ball = lambda r: [c.wall for i in r.impacts for c in i.contacts if c.wall.endswith("/ball")]
    assert near.status == far.status == 0 and on_ball(near) and not on_ball(far)


def test_a_model_with_baked_parameters_keeps_its_obstacles_as_constants():
    """bake_params: the obstacles' places in p are -1 (the shapes' constants), their ranges the scene's values alone;
    the general model's places are their first parameters' indices."""
    from codegen.cache import generate_cached
    from codegen.options import build_options
    scene = chain(False)
    names = scene.parameter_names()
    firsts = ", ".join(str(names.index(o.geometry_names[0])) for o in scene.obstacles)
    general = generate_cached(scene, build_options(scene, specialise=False, chart_b=False, extended=False))
    baked = generate_cached(scene, build_options(scene, bake_params=True, specialise=False, chart_b=False,
                                                 extended=False))
    assert f"_obstacle_params[4] = {{ {firsts} }};" in general.source
    assert "_obstacle_params[4] = { -1, -1, -1, -1 };" in baked.source
    assert '{ "radius_ball", 0.25, 0.25, "built into this model as a constant (0.25; generated with bake_params)" }' \
        in baked.source
