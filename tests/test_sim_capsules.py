"""Capsule links against the walls: a link of radius r touches a wall with the sphere at either end, so its wall
contacts are its end points with the gap less r (docs/simulation.md, "Capsules").  Checked against closed forms
(a rod falling onto a floor, a rod lying on it) and against an independent numpy computation of the gaps."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall, WALL_NAMES
from runtime import load_model, simulate
from studies.reference import reference_of
from tests.test_sim_link_contact import closest_distance

G, R = 9.81, 0.05


C_F = 0.3


@pytest.fixture(scope="module")
def rod():
    """One capsule rod of length 1 m, radius R, in a planar box with a rough floor at X2 = 0 (e = 0.5, c_f = C_F)."""
    scene = Scene(name="capsule_rod", links=(LineLink(1.0, 1.0, (1e-4, 1e-4, 1e-4), R),),
                  walls=(Wall("x1_min", -5.0, 0.5), Wall("x1_max", 5.0, 0.5), Wall("x2_min", 0.0, 0.5, friction=C_F)),
                  gravity=G, q0=(-math.pi / 2, 0.0, 0.0, 0.0, 1.0, 0.0))
    return load_model(scene)


def test_a_dropped_capsule_strikes_at_the_closed_form_time(rod):
    """Upright, O_1 at height h: its end sphere reaches the floor at t = sqrt(2 (h - R) / g)."""
    for h in (1.0, 0.3):
        result = simulate(rod, 0.5, q0=[-math.pi / 2, 0.0, 0.0, 0.0, h, 0.0], rtol=1e-12, atol=1e-12)
        assert result.impacts, result.message
        assert result.t_first_impact == pytest.approx(math.sqrt(2.0 * (h - R) / G), rel=1e-10, abs=1e-12)
        assert [contact.label for contact in result.impacts[0].contacts] == ["O1/x2_min"]


def test_a_capsule_rod_comes_to_rest_on_the_floor_at_its_radius(rod):
    """Dropped tilted, it bounces, lands and lies flat with both end spheres on the floor: the axis at X2 = R."""
    result = simulate(rod, 3.0, q0=[-math.pi / 2, 0.0, -math.pi / 2 + 0.2, 0.0, 1.0, 0.0])
    assert result.success, result.message
    assert sorted(point for point, wall in result.resting_final) == [1, 2]
    points = rod.contact_points(rod.layout.reduce(result.q_final))
    assert points[:, 1] == pytest.approx([R, R], abs=1e-9)
    assert result.energy_final == pytest.approx(1.0 * G * R, rel=1e-6)        # V = m g R at rest, T = 0


def test_a_rod_lying_at_its_radius_stays_there(rod):
    result = simulate(rod, 1.0, q0=[-math.pi / 2, 0.0, -math.pi / 2, 0.0, R, 0.0])
    assert result.success and not result.impacts, result.message
    points = rod.contact_points(rod.layout.reduce(result.q_final))
    assert points[:, 1] == pytest.approx([R, R], abs=1e-12)


@pytest.mark.parametrize("c_f", [C_F, 0.0])
def test_a_capsule_rod_sliding_flat_on_a_rough_floor_stops_at_the_closed_form_time_and_place(rod, c_f):
    """Lying flat at X2 = R, pushed along X1 at v0: both end spheres slide, friction c_f m g against the sliding (it
    acts at the end points' centres, as at a bare segment's: docs/simulation.md, "Capsules"), so
    x(t) = v0 t - c_f g t^2 / 2 until it sticks; the work of friction is the kinetic energy; without friction
    (c_f = 0 through p) it slides on at v0."""
    v0, t_end = 2.0, 1.0
    p = rod.parameters({"friction_x2_min": c_f})
    result = simulate(rod, t_end, p=p, q0=[-math.pi / 2, 0.0, -math.pi / 2, 0.0, R, 0.0],
                      qd0=[0.0, 0.0, 0.0, v0, 0.0, 0.0], t_eval=np.linspace(0.0, t_end, 41), rtol=1e-12, atol=1e-12)
    assert result.success and not result.impacts, result.message
    x = result.q[:, 3]
    if c_f == 0.0:
        assert x == pytest.approx(v0 * result.t, abs=1e-9)
        return
    # it sticks where its speed falls to friction_velocity v_f (the slide's end, then held): t* = (v0 - v_f) / (c_f g)
    stop = (v0 - rod.scene.friction_velocity) / (c_f * G)
    expected = v0 * np.minimum(result.t, stop) - 0.5 * c_f * G * np.minimum(result.t, stop) ** 2
    assert x == pytest.approx(expected, abs=1e-9)
    assert result.q[:, 4] == pytest.approx(R, abs=1e-12) and result.q[:, 2] == pytest.approx(-math.pi / 2, abs=1e-12)
    assert result.loss_friction == pytest.approx(0.5 * v0 ** 2, rel=1e-6)          # m = 1 kg


def test_gaps_against_an_independent_computation():
    """A spatial three-link chain of capsules (radii 0.02, 0.07, 0: the joint point takes the larger) in a box of six
    walls: the generated gaps against wall - point - radius from the reference model's points."""
    radii = (0.02, 0.07, 0.0)
    links = tuple(LineLink(l, 1.0, (1e-3, 2e-3, 2e-3), r) for l, r in zip((0.8, 0.5, 0.6), radii))
    walls = tuple(Wall(name, -3.0 - k if name.endswith("min") else 3.0 + k, 0.7)
                  for k, name in enumerate(WALL_NAMES))
    scene = Scene(name="capsule_gaps", links=links, walls=walls, twists=(((1.0, 0, 0), (0, 0, -1.0), (0, 1.0, 0)),) * 2,
                  q0=(0.1, 0.2, 0.3, 0.4, 0.5, 0.0, 0.0, 0.0))
    model = load_model(scene)
    reference = reference_of(scene)
    point_radius = [max(radii[i] for i in (p - 1, p) if 0 <= i < 3) for p in range(4)]
    assert point_radius == [scene.point_radius(p) for p in range(1, 5)]
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = np.concatenate([rng.uniform(-1.2, 1.2, 5), rng.uniform(-1.0, 1.0, 3)])
        points = reference.points(q)
        expected = [w.normal_sign * (points[p - 1, w.axis] - w.position) - point_radius[p - 1]
                    for p, w in model.layout.contacts]
        # then the link pair (1, 3) of capsules 0.02 + 0: its segments' distance less 0.02, then its ends' (O_1, O_2
        # against link 3, O_3, O_4 against link 1): a point's distance from the other segment
        expected.append(closest_distance(*(points[k] for k in (0, 1, 2, 3))) - 0.02)
        for point, (a, b) in ((0, (2, 3)), (1, (2, 3)), (2, (0, 1)), (3, (0, 1))):
            expected.append(closest_distance(points[point], points[point], points[a], points[b]) - 0.02)
        assert model.contact_gaps(model.layout.reduce(q)) == pytest.approx(expected, abs=1e-13)


def test_the_shipped_capsule_chain_lands_at_its_radius():
    model = load_model("capsule-chain")
    result = simulate(model, 8.0, t_eval=[])
    assert result.success, result.message
    assert sorted(point for point, wall in result.resting_final) == [1, 2, 3, 4]
    points = model.contact_points(model.layout.reduce(result.q_final))
    assert points[:, 1] == pytest.approx([0.05] * 4, abs=1e-9)
