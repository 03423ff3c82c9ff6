"""One link falling onto a fixed ball (a contact of kind GAC_CONTACT_OBSTACLE): it falls without turning under g
from rest, its end point's capsule a height h above the ball, so the strike comes at sqrt(2 h / g); the velocities
after it are those of an independent numpy Newton's law (the mass matrix, the row J^T n as finite differences of
an independent gap); the energy is kept at e = 1 and otherwise loses (1 - e^2) of the normal part's,
v^2 / (2 n I_f^-1 n^T).  The ball's e is the runtime parameter e_ball: one model for every e."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from studies import fuzz
from studies.reference import reference_of

G, H = 9.81, 0.38            # m/s^2, m: the gap at the start
LINK_RADIUS, BALL_RADIUS = 0.02, 0.1
OFFSET = 0.03                # m: the ball's centre beyond the end point along the rod
TOL = dict(rtol=1e-11, atol=1e-13)


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m, horizontal (theta_1 = pi/2: along -X1 from O_1 = (0.2, 1, 0)), a ball below its end point
    O_2 = (-0.8, 1, 0), its centre OFFSET beyond it along the rod (so that the closest point stays at the end, where
    the gap is smooth): the capsules touch when the end is sqrt(r^2 - OFFSET^2) above the centre."""
    q0 = (-math.pi / 2, 0.0, math.pi / 2, 0.2, 1.0, 0.0)
    touch = math.sqrt((LINK_RADIUS + BALL_RADIUS) ** 2 - OFFSET ** 2)
    ball = Obstacle.sphere("ball", (-0.8 - OFFSET, 1.0 - H - touch, 0.0), BALL_RADIUS)
    scene = Scene(name="obstacle_drop", links=(LineLink(1.0, 1.0, radius=LINK_RADIUS),), q0=q0, gravity=G,
                  obstacles=(ball,))
    return load_model(scene)


def independent_gap(model, q) -> float:
    points = reference_of(model.scene).points(model.layout.expand(q))
    a = np.array(model.scene.obstacles[0].a)
    return fuzz.segment_distance(points[0], points[1], a, a) - LINK_RADIUS - BALL_RADIUS


@pytest.mark.parametrize("e", [1.0, 0.6, 0.2])
def test_a_falling_link_strikes_the_ball_by_newtons_law(model, e):
    assert independent_gap(model, model.q0) == pytest.approx(model.contact_gaps(model.q0)[0], abs=1e-12)
    r = simulate(model, 0.3, p={"e_ball": e}, **TOL)
    assert r.status == 0, r.message
    impact = r.impacts[0]
    assert [(c.kind, c.wall, c.point, c.links) for c in impact.contacts] == [("obstacle", "L1/ball", 1, (1,))]
    assert impact.t == pytest.approx(math.sqrt(2 * H / G), rel=1e-9)
    q, qd_m = model.layout.reduce(impact.q), model.layout.reduce(impact.qd_before)
    assert abs(independent_gap(model, q)) <= 1e-9
    # Newton's law, independently: the row as the gap's gradient, the impulse along it
    h = 1e-6
    row = np.array([(independent_gap(model, q + h * d) - independent_gap(model, q - h * d)) / (2 * h)
                    for d in np.eye(model.nq)])
    M = model.mass_matrix(q)
    y = np.linalg.solve(M, row)
    v = row @ qd_m
    falling = np.array([0.0, 0.0, 0.0, 0.0, -G * impact.t, 0.0])   # straight down, not turning (full layout)
    assert np.abs(impact.qd_before - falling).max() <= 1e-9
    F = -(1 + e) * v / (row @ y)
    expected = qd_m + F * y
    qd_p = model.layout.reduce(impact.qd_after)
    assert qd_p == pytest.approx(expected, rel=1e-7, abs=1e-8)
    assert impact.contacts[0].impulse == pytest.approx(F, rel=1e-7)
    assert row @ qd_p == pytest.approx(-e * v, rel=1e-7, abs=1e-9)
    assert impact.qd_after[2] != 0.0                                        # struck at its end, it turns
    # the energy: kept at e = 1, less (1 - e^2) of the normal part's v^2 / (2 n I_f^-1 n^T) otherwise
    lost = impact.energy_before - impact.energy_after
    assert lost == pytest.approx((1 - e * e) * v * v / (2 * (row @ y)), rel=1e-7, abs=1e-12 * impact.energy_before)
    if e == 1.0:
        assert r.energy_final == pytest.approx(r.energy_initial, rel=1e-9)


@pytest.mark.parametrize("e", [0.05, 0.0])
def test_the_end_comes_to_rest_on_the_ball_and_slides_off(model, e):
    """e = 0.05: the end point bounces once, lower, and lands on the ball; e = 0: it lands at the first strike.  Held
    there (the contact's normal J^T n and its bias), the rod pivots about its end under g, pressing on the ball,
    until the force falls through 0 and the contact is released: the gap held at 0 and the force positive in between
    (the constrained dynamics at the samples), the rod clear of the ball at the end, the energy balance closed."""
    r = simulate(model, 0.4, p={"e_ball": e}, t_eval=np.linspace(0.0, 0.4, 401), **TOL)
    assert r.status == 0, r.message
    assert len(r.impacts) == (2 if e > 0.0 else 1)
    assert [(x.kind, x.wall) for x in r.contact_events] == [("rest", "L1/ball"), ("release", "L1/ball")]
    landed, released = (x.t for x in r.contact_events)
    assert landed == pytest.approx(r.impacts[-1].t, abs=1e-12) and released > landed + 0.01
    for t, q, qd in zip(r.t, r.q, r.qd):
        q, qd = model.layout.reduce(q), model.layout.reduce(qd)
        if landed < t < released:
            assert abs(model.contact_gaps(q)[0]) <= 1e-9
            assert model.constrained_dynamics(q, qd, [0])[1][0] > 0.0
    assert model.contact_gaps(model.layout.reduce(r.q_final))[0] > 1e-3 and r.resting_final == []
    assert abs(r.energy_drift) <= 1e-9
