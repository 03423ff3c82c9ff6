"""A plane as a fixed obstacle (gac_obstacle.c): a three-link chain (capsules) thrown upward in a box with a
floor, under a slanted roof, the half-space above the plane through ROOF_POINT of unit normal ROOF_N (pointing
down, into the free side).  It strikes the roof and the floor again and again: no link's capsule crosses the roof
by more than 1e-6 m at the samples and impacts (the independent gap: the lower end's distance n . (x - point) less
the radius), Newton's law holds on each roof strike's normal velocity, and the energy is kept at e = 1."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene, Wall
from runtime import load_model, simulate
from studies.reference import reference_of

TOL = dict(rtol=1e-10, atol=1e-12)
POSITION_TOL = 1e-6
RADIUS = 0.03
ROOF_POINT = (0.0, 1.9, 0.0)
ROOF_N = tuple(np.array([0.35, -1.0, 0.0]) / np.linalg.norm([0.35, -1.0, 0.0]))


@pytest.fixture(scope="module")
def model():
    links = tuple(LineLink(l, mu, radius=RADIUS) for l, mu in ((0.6, 1.0), (0.5, 2.0), (0.7, 0.8)))
    scene = Scene(name="obstacle_roof", links=links, gravity=9.81, walls=(Wall("x2_min", 0.0, 1.0, (1, 2, 3, 4)),),
                  q0=(-math.pi / 2, 0.0, 1.2, 0.8, -0.5, 0.0, 0.6, 0.0),
                  obstacles=(Obstacle.plane("roof", ROOF_POINT, ROOF_N),), obstacle_restitution=1.0, contact_pairs=())
    return load_model(scene)


def roof_gaps(points) -> np.ndarray:
    """Independent: each link's lower end's signed distance from the roof, less the link's radius."""
    d = (points - np.array(ROOF_POINT)) @ np.array(ROOF_N)
    return np.minimum(d[:-1], d[1:]) - RADIUS


@pytest.mark.parametrize("qd0", [(0.0, 0.0, 3.0, -4.0, 5.0, 1.5, 7.5, 0.0),
                                 (0.0, 0.0, -2.0, 6.0, -3.0, -1.0, 8.0, 0.0)])
def test_a_chain_thrown_at_a_slanted_roof_bounces_without_crossing_it(model, qd0):
    reference = reference_of(model.scene)
    q0 = model.q0
    assert roof_gaps(reference.points(model.layout.expand(q0))).min() > 0.0
    r = simulate(model, 3.0, qd0=qd0, **TOL)
    assert r.status == 0, r.message
    roof = [i for i in r.impacts if any(c.kind == "obstacle" for c in i.contacts)]
    assert len(roof) >= 3, "the chain barely reached the roof"
    assert any(c.kind != "obstacle" for i in r.impacts for c in i.contacts)      # the floor too
    worst = min(roof_gaps(reference.points(q)).min() for q in [*r.q, *(i.q for i in r.impacts)])
    assert worst >= -POSITION_TOL
    assert all(abs(roof_gaps(reference.points(i.q)).min()) <= 1e-9 for i in roof)      # struck at the touch
    assert r.energy_final == pytest.approx(r.energy_initial, rel=1e-8)
    index = {c.name: k for k, (_, c) in enumerate(model.contacts)}
    for impact in roof:
        q, qd_m, qd_p = (model.layout.reduce(x) for x in (impact.q, impact.qd_before, impact.qd_after))
        assert impact.energy_after == pytest.approx(impact.energy_before, rel=1e-11)
        if len(impact.contacts) == 1:
            row = model.contact_normal(q, index[impact.contacts[0].wall])
            assert row @ qd_p == pytest.approx(-(row @ qd_m), rel=1e-9, abs=1e-12)
            assert impact.contacts[0].impulse > 0.0


@pytest.mark.parametrize("qd0, t_end", [((0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 7.0, 0.0), 0.12),
                                         ((0.0, 0.0, 1.0, -1.0, 2.0, 0.5, 7.0, 0.0), 0.15)])
def test_sensitivities_through_a_roof_strike(model, qd0, t_end):
    """The chain's tip strikes the roof alone (O_4, the plane's constant normal): the sensitivities go through it
    and match central differences of whole runs; the joints between the links strike it next, each one contact
    (a plane's contacts are the joint points), and the sensitivities go through those too, to 0.3 s."""
    from tests.test_sim_sensitivities import central_differences
    tangent = load_model(model.scene, tangent=True)
    p = tangent.parameters({"e_roof": 0.8})
    q0, qd0 = np.array(model.scene.q0, dtype=float), np.array(qd0)
    directions = ["qd0[X1]", "g", "q0[theta_2]", "qd0[theta_3]", "l_2", "e_roof"]
    r = simulate(tangent, t_end, p=p, qd0=qd0, sensitivities=directions, **TOL)
    assert [[c.label for c in i.contacts] for i in r.impacts] == [["O4/roof"]]
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    central_differences(tangent, t_end, p, q0, qd0, directions, r.sensitivities.matrix, **TOL)
    tight = dict(rtol=1e-12, atol=1e-14)                          # five impacts: the differences' noise below 1e-5
    r = simulate(tangent, 0.3, p=p, qd0=qd0, sensitivities=directions, **tight)
    struck = [c.label for i in r.impacts for c in i.contacts]
    assert all(len(i.contacts) == 1 for i in r.impacts) and {"O2/roof", "O3/roof"} <= set(struck)
    assert r.sensitivities.valid and r.sensitivities.n_impacts == len(r.impacts) >= 4, r.sensitivity_message
    central_differences(tangent, 0.3, p, q0, qd0, directions, r.sensitivities.matrix, **tight)
