"""Forward sensitivities through rest on link pairs and obstacles (contacts without a Jacobian row held like a wall's
point, gac_sens.c): the held row J^T n at the closest points and its derivative (the closest points' motion and the
normal's turning, gac_contact_normal_tangent), the held gap's derivative n . dD, and the bias dg(qd) . qd's derivative
(exact along qd, a fourth-order central difference along q and p: gac_rowless_bias_tangent); stuck on a rough one,
the frame's rows J^T t1, J^T t2 held too, with their biases and derivatives (gac_contact_frame_tangent); sliding, its
friction along them.  A rod lands on a smooth ball (e = 0), turns and slides over it and leaves it (a release); a
tilted rod lands on one smooth bar and tips onto a second; a rod falls across another lying on the floor, lands on
it, pivots and lands on the floor with the pair held; a rod lands on a rough ball and rocks on it, stuck, or slips,
slides and leaves (planar and in 3D); a rod lands across another with friction between them and pivots on it, stuck
or sliding.  The final state's sensitivities and the landings' and releases' event times' match central differences
of whole runs; the ball's, the crossing rods' and the rocking rod's runs fail them with the bias's change along q and
p left out, the slipping rods' with the frame rows' derivative in the sliding friction left out."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import Chains, LineLink, Obstacle, Scene, Wall
from runtime import load_model, simulate
from tests.test_sim_obstacle_rest import BAR_X, BAR_Y, G, M, OBSTACLES, R_LINK
from tests.test_sim_sensitivities import central_differences, perturbed_start

TIGHT = dict(rtol=1e-12, atol=1e-14)


def ball_scene() -> Scene:
    """A free rod of 1 m (capsule radius 0.02 m) tilted 0.15 rad from the horizontal, O_1 = (0.2, 1, 0), falling under
    g onto a smooth ball of radius 0.1 m inside its length."""
    return Scene(name="sens_rest_ball", links=(LineLink(1.0, 1.0, radius=0.02),),
                 q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.15, 0.2, 1.0, 0.0), gravity=9.81,
                 obstacles=(Obstacle.sphere("ball", (-0.45, 0.55, 0.0), 0.1),))


def crossing_scene() -> Chains:
    """Two rods of 1 m (capsule radius 0.02 m) in one box with a plastic floor: rod A lying on the floor along X3,
    rod B along -X1 from O = (0.8, 0.16, 0) tilted 0.1 rad, crossing A 0.2 m off B's centre (the pair plastic)."""
    floor = (Wall("x2_min", 0.0, restitution=0.0),)
    a = Scene(name="sens_cross_a", links=(LineLink(1.0, 1.0, radius=0.02),), gravity=9.81, walls=floor,
              q0=(0.0, 0.0, math.pi / 2, 0.1, 0.02, -0.5))
    b = Scene(name="sens_cross_b", links=(LineLink(1.0, 1.0, radius=0.02),), gravity=9.81, walls=floor,
              q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.1, 0.8, 0.16, 0.0))
    return Chains(name="sens_cross_rest", chains=(a, b), link_restitution=0.0)


def event_times_match(model, t_end, p, q0, qd0, directions, events, step=1e-6):
    """Each landing's and release's dt_dp against the central difference of its time (the same events across the
    stencil), to 1e-6 of the largest."""
    def times(h, direction):
        p1, q1, qd1 = perturbed_start(model, direction, h, p, q0, qd0)
        run = simulate(model, t_end, p=p1, q0=q1, qd0=qd1, **TIGHT)
        moving = [(e.kind, e.wall) for e in run.contact_events if e.t > 0.0]
        assert moving == [(e.kind, e.wall) for e in events], direction
        return np.array([e.t for e in run.contact_events if e.t > 0.0])

    for direction in directions:
        fd = (times(step, direction) - times(-step, direction)) / (2 * step)
        exact = np.array([e.dt_dp[direction] for e in events])
        assert np.abs(fd - exact).max() <= 1e-6 * max(1.0, np.abs(fd).max()), direction


@pytest.fixture(scope="module")
def ball():
    return load_model(ball_scene(), tangent=True)


def test_a_rod_landing_on_a_smooth_ball_slides_over_it_and_leaves(ball):
    """e = 0: the rod lands on the ball (one plastic strike), turns and slides over it held by its normal, and leaves
    it when the contact force falls to 0; the final state at 0.8 s and both events' times against central
    differences (the rest and the release differentiated, the rod's length, g and the ball's place and size among the
    directions)."""
    model = ball
    p = model.parameters({"e_ball": 0.0})
    q0, qd0 = np.array(model.scene.q0, dtype=float), np.zeros(6)
    qd0[3] = 0.3
    directions = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "l_1", "center_x_ball", "radius_ball"]
    r = simulate(model, 0.8, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["L1/ball"]], r.message
    events = [e for e in r.contact_events if e.t > 0.0]
    assert [(e.kind, e.wall) for e in events] == [("rest", "L1/ball"), ("release", "L1/ball")]
    assert events[1].t - events[0].t > 0.1                       # held for a while, then released
    assert r.sensitivities.valid, r.sensitivity_message
    central_differences(model, 0.8, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)
    event_times_match(model, 0.8, p, q0, qd0, directions, events)


def test_a_tilted_rod_lands_on_one_smooth_bar_and_tips_onto_the_other():
    """tests/test_sim_obstacle_rest.py's rod on two bars (e = 0.3): it strikes and comes to rest on one bar, then
    tips onto the other (an impact with a link on an obstacle at rest) and rests on both, sliding along its axis; the
    final state's sensitivities against central differences."""
    scene = Scene(name="obstacle_rest", links=(LineLink(1.0, M, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 0.5, 1.0, 0.0), obstacles=OBSTACLES)
    model = load_model(scene, tangent=True)
    p = model.parameters({"e_bar_a": 0.3, "e_bar_b": 0.3})
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + 0.05, 0.5 * sum(BAR_X) + 0.55, BAR_Y + 0.12, 0.0])
    qd0 = np.zeros(6)
    directions = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "e_bar_a", "l_1"]
    run = dict(TIGHT, h_max=0.005)
    r = simulate(model, 1.0, p=p, q0=q0, qd0=qd0, sensitivities=directions, **run)
    assert r.success and sorted(r.resting_final) == [(1, "L1/bar_a"), (1, "L1/bar_b")], r.message
    assert any(e.kind == "rest" and e.wall == "L1/bar_a" for e in r.contact_events)
    assert r.sensitivities.valid, r.sensitivity_message
    assert abs(r.sensitivities.matrix[3, 2]) > 0.5                 # X1 moves with qd0[X1]: not a static answer
    central_differences(model, 1.0, p, q0, qd0, directions, r.sensitivities.matrix, **run)


def test_a_rod_falling_across_another_lands_on_it_pivots_and_lands_on_the_floor():
    """Rod B lands on rod A (the pair plastic, A's ends at rest on the floor taking part), pivots on it held by the
    pair's normal with both links moving, and its end lands on the floor with the pair held; the final state at 0.6 s
    and the pair's and the floor's landing times against central differences."""
    scene = crossing_scene()
    model = load_model(scene, tangent=True, specialise=False)
    p = model.p.copy()
    q0 = model.layout.reduce(np.concatenate([np.array(c.q0, dtype=float) for c in scene.chains]))
    qd0 = np.zeros(model.nq)
    directions = ["q0[c2.X2]", "q0[c2.theta_1]", "qd0[c2.X1]", "qd0[c2.theta_1]", "g", "c2.l_1", "c1.mu_1"]
    r = simulate(model, 0.6, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [sorted(c.label for c in i.contacts) for i in r.impacts] == \
        [["L1-L3", "O1/x2_min", "O2/x2_min"], ["L1-L3", "O1/x2_min", "O2/x2_min", "O3/x2_min"]], r.message
    events = [e for e in r.contact_events if e.t > 0.0]
    assert [(e.kind, e.wall) for e in events] == [("rest", "L1-L3"), ("rest", "x2_min")]
    assert r.sensitivities.valid, r.sensitivity_message
    central_differences(model, 0.6, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)
    event_times_match(model, 0.6, p, q0, qd0, directions, events)


def rough_crossing_scene(c_f: float) -> Chains:
    """crossing_scene with Coulomb friction c_f between the two rods (the floor smooth)."""
    return dataclasses.replace(crossing_scene(), name=f"sens_cross_rough{int(round(100 * c_f))}", link_friction=c_f)


def rough_ball_model(specialise: bool = True):
    """tests/test_sim_obstacle_friction.py's free rod of 1.2 m above a rough ball of radius 0.3 m at the origin."""
    ball = Obstacle.sphere("ball", (0.0, 0.0, 0.0), 0.3, friction=0.5)
    scene = Scene(name="rough_ball", links=(LineLink(1.2, 1.5, (2e-3, 3e-3, 4e-3), 0.02),), gravity=9.81,
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.3, -0.4, 0.8, 0.1), obstacles=(ball,))
    return load_model(scene, tangent=True, specialise=specialise)


@pytest.mark.parametrize("c_f, off, events", [
    (0.5, 0.05, ["rest", "stick"]),
    (0.2, 0.1, ["rest", "stick", "slip", "release"]),
    (0.05, 0.1, ["rest", "stick", "slip", "release"])])
def test_a_rod_landing_on_a_rough_ball_sticks_rocks_slips_and_leaves(c_f, off, events):
    """The rod dropped flat, its centre `off` beside the ball's top (e = 0): it lands and sticks; with c_f = 0.5 it
    rocks on the ball without slipping (its contact held along n, t1, t2); with less friction it slips where its
    force reaches the cone's edge, slides over the ball (its friction along the frame) and leaves it.  The final state
    at 0.8 s against central differences, the ball's radius and friction and the rod's length among the
    directions."""
    model = rough_ball_model()
    q0, qd0 = np.array([-math.pi / 2, 0.0, -math.pi / 2, -0.6 + off, 0.5, 0.0]), np.zeros(6)
    p = model.parameters({"e_ball": 0.0, "friction_ball": c_f})
    directions = ["q0[X1]", "q0[X2]", "q0[theta_1]", "g", "friction_ball", "radius_ball", "l_1"]
    r = simulate(model, 0.8, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [e.kind for e in r.contact_events] == events, r.message
    assert r.sensitivities.valid, r.sensitivity_message
    if "slip" in events:
        assert abs(r.sensitivities.matrix[:, directions.index("friction_ball")]).max() > 0.1
    central_differences(model, 0.8, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_a_rod_slipping_on_a_rough_ball_in_3d_matches_central_differences():
    """The general model, the rod thrown out of the plane too: it slips in a direction of its own over the frame's
    two tangents (the slip direction's derivative carried into the viscous band), slides and leaves."""
    model = rough_ball_model(specialise=False)
    q0, qd0 = np.array([-math.pi / 2, 0.0, -math.pi / 2, -0.5, 0.5, 0.0]), np.zeros(6)
    qd0[0], qd0[5] = 0.5, 0.3
    p = model.parameters({"e_ball": 0.0, "friction_ball": 0.2})
    directions = ["q0[X3]", "qd0[X3]", "q0[X1]", "g", "friction_ball", "radius_ball", "l_1"]
    r = simulate(model, 0.8, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [e.kind for e in r.contact_events] == ["rest", "stick", "slip", "release"], r.message
    assert r.sensitivities.valid, r.sensitivity_message
    central_differences(model, 0.8, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


@pytest.mark.parametrize("c_f, stuck", [(1.0, True), (0.02, False)])
def test_a_rod_landing_across_a_rough_rod_pivots_on_it(c_f, stuck):
    """The crossing rods with friction between them: rod B lands on rod A and, with c_f = 1, sticks and pivots on it
    (the pair's contact held along its frame, both links moving) until its end lands on the smooth floor in an impact
    with the stuck pair (the final state at 0.6 s); with c_f = 0.02 it slides on A as it pivots (at 0.15 s).  Against
    central differences."""
    scene = rough_crossing_scene(c_f)
    model = load_model(scene, tangent=True, specialise=False)
    p = model.p.copy()
    q0 = model.layout.reduce(np.concatenate([np.array(c.q0, dtype=float) for c in scene.chains]))
    qd0 = np.zeros(model.nq)
    directions = ["q0[c2.X2]", "q0[c2.theta_1]", "qd0[c2.X1]", "g", "c2.l_1"]
    t_end = 0.6 if stuck else 0.15
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and r.n_sticks == int(stuck) and r.n_slips == 0, r.message
    assert [(e.kind, e.label) for e in r.contact_events if e.t > 0.0] == \
        ([("rest", "L1-L3"), ("stick", "L1-L3"), ("rest", "O3/x2_min")] if stuck else [("rest", "L1-L3")])
    assert r.sensitivities.valid, r.sensitivity_message
    central_differences(model, t_end, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)
