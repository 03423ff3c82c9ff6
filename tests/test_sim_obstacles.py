"""Fixed obstacles in the box (gac_link.c, contacts of kind GAC_CONTACT_OBSTACLE): the gap of a link and a sphere or a
bar against an independent segment distance and J^T n against finite differences of that gap on random states, the
obstacle's e as the runtime parameter e_<name>, and a tumbling spatial chain striking a ball and a bar: no
penetration at the samples, Newton's law on the struck contact's normal velocity, the momentum balance of every
impact with pushing impulses only, and the energy kept at e = 1."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, ObstacleContact, Scene
from runtime import load_model, simulate
from studies import fuzz
from studies.reference import reference_of

TOL = dict(rtol=1e-10, atol=1e-12)
POSITION_TOL = 1e-6          # m: a contact's gap must stay above -POSITION_TOL at the samples
RADII = (0.05, 0.0, 0.04)    # link 2 a bare segment: only the obstacle's radius keeps it off
BALL = Obstacle.sphere("ball", (0.4, 1.2, 0.1), 0.25)
BAR = Obstacle.bar("bar", (-1.5, 0.8, -1.0), (-1.4, 0.9, 1.0), 0.06, restitution=1.0)
TWISTS = (((1.0, 0, 0), (0, 0.0, -1.0), (0, 1.0, 0.0)), ((1.0, 0, 0), (0, 0.6, -0.8), (0, 0.8, 0.6)))


@pytest.fixture(scope="module")
def model():
    """A spatial three-link chain (twisted joints), no walls, no gravity, a ball and a bar in its reach (links 1 and 3
    pass through each other: the contacts are the obstacles' alone)."""
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), r) for l, mu, r in zip((1.0, 0.7, 0.9), (1.0, 2.0, 0.5), RADII))
    scene = Scene(name="obstacle_chain", links=links, twists=TWISTS, gravity=0.0, q0=(0.0,) * 8,
                  obstacles=(BALL, BAR), obstacle_restitution=1.0, contact_pairs=())   # obstacles only
    return load_model(scene)


def obstacle_gap(points, contact: ObstacleContact) -> float:
    """Independent: the fuzz study's segment distance of the link (or of a bar's joint point's contact, that point)
    and the obstacle's segment, less the radii."""
    a, b = (np.array(x, dtype=float) for x in contact.obstacle.segment)
    return fuzz.segment_distance(*contact.segment(points), a, b) - contact.radius


def test_the_obstacles_are_contacts_of_the_model(model):
    names = [(point, c.name) for point, c in model.contacts]
    assert names == [(1, "L1/ball"), (2, "L2/ball"), (3, "L3/ball"), (1, "L1/bar"), (2, "L2/bar"), (3, "L3/bar"),
                     (1, "O1/bar"), (1, "O2/bar"), (3, "O3/bar"), (3, "O4/bar")]   # a bar's: the joint points' too
    assert model.parameter_names[-13:-11] == ["e_ball", "e_bar"]         # then the geometry (4 + 7)
    assert model.parameters()[-13:-11].tolist() == [1.0, 1.0]
    assert "e_ball" in model.parameter_problem(model.parameters({"e_ball": 1.5}))


def test_gaps_and_directions_against_an_independent_computation(model):
    """Random states: each contact's gap is the independent segment distance less the radii, gac_obstacle_gap's n
    is the unit vector between the closest points, and J^T n (gac_contact_normal) is the gradient of the
    independent gap (central differences)."""
    reference = reference_of(model.scene)
    rng = np.random.default_rng(5)
    nq = model.nq
    for _ in range(60):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 5), rng.uniform(-0.5, 1.5, 3)])
        q[1] = rng.uniform(-1.2, 1.2)                         # theta_0 away from the base chart's lock
        gaps = model.contact_gaps(q)
        points = reference.points(q)
        for c, (_, contact) in enumerate(model.contacts):
            expected = obstacle_gap(points, contact)
            assert gaps[c] == pytest.approx(expected, abs=1e-12)
            gap, s, t, n = model.contact_geometry(q, c)
            assert gap == gaps[c] and 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
            assert contact.end != 0 or (gap, s, t) == model.obstacle_gap(q, contact.i, contact.obstacle.name)[:3]
            a, b = (np.array(x) for x in contact.obstacle.segment)
            d = points[contact.i - 1] + s * (points[contact.i] - points[contact.i - 1]) - (a + t * (b - a))
            assert n == pytest.approx(d / np.linalg.norm(d), abs=1e-9)
            g = model.contact_normal(q, c)
            h = 1e-6
            fd = np.array([(obstacle_gap(reference.points(q + h * e), contact)
                            - obstacle_gap(reference.points(q - h * e), contact)) / (2 * h) for e in np.eye(nq)])
            assert g == pytest.approx(fd, abs=2e-6 * max(1.0, np.abs(g).max()))


def test_the_obstacle_restitution_is_a_runtime_parameter(model):
    """e_ball = 0 makes the ball's first strike plastic: the normal velocity after it is 0."""
    q0, qd0 = tumbling_start(4)                               # links 1 and 3 strike the ball
    r = simulate(model, 3.0, q0=q0, qd0=qd0, p={"e_ball": 0.0}, **TOL)
    assert r.status == 0, r.message
    first = next(i for i in r.impacts if [c.wall for c in i.contacts] in (["L1/ball"], ["L2/ball"], ["L3/ball"]))
    c = model.contacts.index(next(x for x in model.contacts if x[1].name == first.contacts[0].wall))
    q, qd_p = model.layout.reduce(first.q), model.layout.reduce(first.qd_after)
    assert abs(model.contact_normal(q, c) @ qd_p) <= 1e-9 * np.abs(model.layout.reduce(first.qd_before)).max()


def tumbling_start(seed: int):
    """Random joint angles and fast joint rates, the chain drifting towards the ball and the bar."""
    rng = np.random.default_rng(seed)
    q0 = np.zeros(8)
    q0[3:5] = rng.uniform(-2.0, 2.0, 2)
    q0[5:8] = (-0.6, 0.1, 0.0)
    qd0 = np.concatenate([rng.uniform(-1.0, 1.0, 3), rng.choice([-1, 1], 2) * rng.uniform(3.0, 6.0, 2),
                          (0.2, 0.0, 0.0)])
    return q0, qd0


@pytest.mark.parametrize("seed", [12, 23])      # the bare link 2 strikes the bar; both obstacles
def test_a_tumbling_chain_strikes_the_obstacles_without_penetrating(model, seed):
    q0, qd0 = tumbling_start(seed)
    assert model.contact_gaps(q0).min() > 0.0
    r = simulate(model, 3.0, q0=q0, qd0=qd0, **TOL)
    assert r.status == 0, r.message
    assert len(r.impacts) >= 3, "the run barely reached the obstacles"
    assert r.energy_final == pytest.approx(r.energy_initial, rel=1e-8)          # e = 1 everywhere
    reference = reference_of(model.scene)
    worst = min(obstacle_gap(reference.points(q), contact) for q in r.q for _, contact in model.contacts)
    assert worst >= -POSITION_TOL
    index = {contact.name: c for c, (_, contact) in enumerate(model.contacts)}
    for impact in r.impacts:
        q, qd_m, qd_p = (model.layout.reduce(x) for x in (impact.q, impact.qd_before, impact.qd_after))
        rows = [model.contact_normal(q, index[c.wall]) for c in impact.contacts]
        assert all(c.impulse >= 0.0 and c.kind == "obstacle" and c.links == (c.point,) for c in impact.contacts)
        # the momentum balance I_f (qd+ - qd-) = sum_a F_a J^T n_a
        change = model.generalized_momentum(q, qd_p - qd_m)
        pushed = sum(c.impulse * g for c, g in zip(impact.contacts, rows))
        assert change == pytest.approx(pushed, abs=1e-10 * np.abs(model.generalized_momentum(q, qd_m)).max())
        assert impact.energy_after == pytest.approx(impact.energy_before, rel=1e-11)
        if len(rows) == 1:                                                      # Newton's law, e = 1
            assert rows[0] @ qd_p == pytest.approx(-(rows[0] @ qd_m), rel=1e-9, abs=1e-12)
