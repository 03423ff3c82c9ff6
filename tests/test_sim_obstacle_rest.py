"""A link at rest on fixed obstacles (contacts of kind GAC_CONTACT_OBSTACLE held like a wall's, by their normal
g = J^T n and its bias dg(qd) . qd): a rod dropped flat onto a box's top face bounces (e = 0.3), lands and rests
there on both ends (the box's joint points' contacts), their gaps held and each end's force m g / 2 (the
constrained dynamics at the final state, independently); a rod dropped across two bars lands on both and rests
there, each holding half its weight, the energy balance closed; sensitivities go through the landing on the face
and the rest on it (each end a point's contact), against central differences of whole runs."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate

G, M, R_LINK = 9.81, 1.0, 0.02
TOP = 0.4                                    # m: the slab's top face
BAR_Y, BAR_X, BAR_R = 0.5, (2.7, 3.3), 0.03  # the bars along X3 at X2 = BAR_Y, X1 = BAR_X, radius BAR_R
OBSTACLES = (
    Obstacle.box("slab", (0.0, TOP / 2, 0.0), (0.8, TOP / 2, 0.5)),
    Obstacle.bar("bar_a", (BAR_X[0], BAR_Y, -0.5), (BAR_X[0], BAR_Y, 0.5), BAR_R),
    Obstacle.bar("bar_b", (BAR_X[1], BAR_Y, -0.5), (BAR_X[1], BAR_Y, 0.5), BAR_R),
)
RUN = dict(rtol=1e-10, atol=1e-12, h_max=0.005)


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m, 1 kg, horizontal (theta_1 = pi/2: along -X1 from O_1), with the tangent kernels."""
    scene = Scene(name="obstacle_rest", links=(LineLink(1.0, M, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 0.5, 1.0, 0.0), obstacles=OBSTACLES)
    return load_model(scene, tangent=True)


def label(model, name: str) -> int:
    """The index of the contact named `name` in the model's table."""
    return [contact.name for _, contact in model.contacts].index(name)


def drop(model, centre_x: float, height: float, t_end: float, **kwargs):
    """The rod from rest, its centre over X1 = centre_x, its axis `height` above where it touches."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, centre_x + 0.5, height, 0.0])
    samples = np.linspace(0.0, t_end, 401)
    return simulate(model, t_end, q0=q0, qd0=np.zeros(6), t_eval=samples,
                    p={"e_slab": 0.3, "e_bar_a": 0.3, "e_bar_b": 0.3}, **RUN, **kwargs)


def test_a_rod_dropped_flat_on_a_box_bounces_lands_and_rests(model):
    r = drop(model, 0.0, TOP + R_LINK + 0.1, 1.5)
    assert r.status == 0, r.message
    ends = ["O1/slab", "O2/slab"]                       # level: both ends strike at once
    assert len(r.impacts) >= 2 and all(sorted(c.wall for c in i.contacts) == ends for i in r.impacts)
    first = r.impacts[0]
    assert first.qd_after[4] == pytest.approx(-0.3 * first.qd_before[4], rel=1e-9)   # Newton's law, e = 0.3
    landed = [e for e in r.contact_events if e.kind == "rest"]
    assert sorted(e.wall for e in landed) == ends and landed[0].t < 0.5
    assert sorted(r.resting_final) == [(1, "O1/slab"), (1, "O2/slab")]
    # held on the face for the last second: gaps within the position tolerance, not moving, not turning
    held = r.t >= landed[-1].t + 1e-9
    assert r.t[held][-1] - r.t[held][0] >= 1.0 - 1e-9
    index = [label(model, name) for name in ends]
    gaps = np.array([model.contact_gaps(model.layout.reduce(q))[index] for q in r.q[held]])
    assert np.abs(gaps).max() <= 1e-9
    assert np.abs(r.qd[held]).max() <= 1e-9 and np.abs(r.q[held][:, 2] - math.pi / 2).max() <= 1e-12
    # each end holds half the rod's weight
    q, qd = model.layout.reduce(r.q_final), model.layout.reduce(r.qd_final)
    qdd, lam = model.constrained_dynamics(q, qd, index)
    assert lam == pytest.approx([M * G / 2, M * G / 2], rel=1e-9) and np.abs(qdd).max() <= 1e-9
    assert abs(r.energy_drift) <= 1e-8


def test_a_rod_dropped_across_two_bars_rests_on_both(model):
    """The rod's centre midway between the bars: both strike at once, bounce, land together and each holds half
    the weight (the rod's axis BAR_R + R_LINK above the bars' axes)."""
    r = drop(model, 0.5 * sum(BAR_X), BAR_Y + BAR_R + R_LINK + 0.05, 1.5)
    assert r.status == 0, r.message
    assert {c.wall for i in r.impacts for c in i.contacts} == {"L1/bar_a", "L1/bar_b"}
    assert sorted(r.resting_final) == [(1, "L1/bar_a"), (1, "L1/bar_b")]
    q, qd = model.layout.reduce(r.q_final), model.layout.reduce(r.qd_final)
    assert q[4] == pytest.approx(BAR_Y + BAR_R + R_LINK, abs=1e-9)
    assert np.abs(qd).max() <= 1e-9
    qdd, lam = model.constrained_dynamics(q, qd, [label(model, "L1/bar_a"), label(model, "L1/bar_b")])
    assert lam == pytest.approx([M * G / 2, M * G / 2], rel=1e-8) and np.abs(qdd).max() <= 1e-9
    assert abs(r.energy_drift) <= 1e-8


def test_a_tilted_rod_on_the_bars_rolls_onto_both_and_the_energy_balance_closes(model):
    """Off-centre and tilted: one bar first, then the rod tips onto the other and comes to rest on both, lying
    level at their height; the bars are frictionless, so the rod keeps the sideways slide (along its axis, X1)
    the strikes gave it."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + 0.05, 0.5 * sum(BAR_X) + 0.55, BAR_Y + 0.12, 0.0])
    r = simulate(model, 2.0, q0=q0, qd0=np.zeros(6), t_eval=[], p={"e_bar_a": 0.3, "e_bar_b": 0.3}, **RUN)
    assert r.status == 0, r.message
    assert sorted(r.resting_final) == [(1, "L1/bar_a"), (1, "L1/bar_b")]
    q, qd = model.layout.reduce(r.q_final), model.layout.reduce(r.qd_final)
    assert q[2] == pytest.approx(math.pi / 2, abs=1e-9) and q[4] == pytest.approx(BAR_Y + BAR_R + R_LINK, abs=1e-9)
    assert np.abs(np.delete(qd, 3)).max() <= 1e-9 and 0.0 < abs(qd[3]) < 0.1
    qdd, lam = model.constrained_dynamics(q, qd, [label(model, "L1/bar_a"), label(model, "L1/bar_b")])
    assert (lam > 0.0).all() and lam.sum() == pytest.approx(M * G, rel=1e-8)
    assert abs(r.energy_drift) <= 1e-8


def test_sensitivities_go_through_the_rod_coming_to_rest_flat_on_a_face(model):
    """Dropped level onto the slab's face (e = 0.3): it bounces on both ends at once and lands on both; the final
    state's sensitivities along the drop height, the face's height and e against central differences of whole runs
    (the rod lying along the face rests on its two ends' contacts, each a point's with a derivative)."""
    from tests.test_sim_sensitivities import central_differences
    directions = ["q0[X2]", "center_y_slab", "e_slab"]
    r = drop(model, 0.0, TOP + R_LINK + 0.1, 0.6, sensitivities=directions)
    assert r.status == 0, r.message
    assert sorted(r.resting_final) == [(1, "O1/slab"), (1, "O2/slab")]
    assert r.sensitivities.valid, r.sensitivity_message
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, 0.5, TOP + R_LINK + 0.1, 0.0])
    p = model.parameters({"e_slab": 0.3, "e_bar_a": 0.3, "e_bar_b": 0.3})
    central_differences(model, 0.6, p, q0, np.zeros(6), directions, r.sensitivities.matrix, **RUN)
