"""Forward sensitivities through an impact of several contacts among which a link strikes a fixed obstacle
(gac_sens.c: the multi-contact differential with a row J^T n of a GAC_CONTACT_OBSTACLE contact beside a wall's):
a rod tilted 0.3 rad from the horizontal falls without turning so that its lower end O_2 meets the floor as a point
inside its length meets a ball, both in one impact, both taking an impulse (the rod's centre of mass lies between
them).  The ball's gap is 4e-6 m from the floor's at the impact, on one side or the other, so that one contact
locates the impact (its gap gives dt*) and the other joins it within the simultaneity window (contact_tol 1e-5 m,
wider than the stencil moves the gaps apart); the final state's sensitivities to the initial state, g, the rod's
length and both restitutions against central differences of whole runs (the same impacts across the stencil).
The same rod, moved 3 m along X1 and 0.5 m up, strikes two balls at once, its end O_2 on one and a point inside
its length on the other: two obstacle contacts, no wall."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene, Wall
from runtime import load_model, simulate
from tests.test_sim_sensitivities import central_differences

OPTIONS = dict(rtol=1e-12, atol=1e-14, contact_tol=1e-5)
R_LINK, R_BALL = 0.02, 0.1
TILT = 0.3           # rad: the rod's slope, O_2 lowest
S = 0.7              # the ball's contact along the rod from O_2 (the centre of mass, at 0.5, between the two)
DROP = 0.05          # m: O_2's fall to the floor
OFFSET = 4e-6        # m: the other contact's gap when the first strikes
AWAY = np.array([3.0, 0.5, 0.0])    # m: the two balls' rod at the strike, from the first one's
T_END = 0.2
DIRECTIONS = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "l_1", "e_x2_min", "e_ball"]


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m (capsule radius 0.02 m, so its end's floor gap is its height less 0.02 m), a floor
    x2_min = 0 (e = 0.5) and a ball (radius 0.1 m) placed so that, falling straight down, the rod touches both at
    once: the ball's centre below the point at S of the rod by the radii along the rod's upward normal.  AWAY from
    there two more balls, "side" as the first and "end" below O_2, its centre beyond the end along the rod (the
    closest point stays at the end)."""
    u = np.array([math.cos(TILT), math.sin(TILT), 0.0])          # along the rod, from O_2 up to O_1
    n = np.array([-math.sin(TILT), math.cos(TILT), 0.0])         # its upward normal in the plane
    o2 = np.array([0.0, R_LINK, 0.0])                            # O_2 at the strike
    down = -(n + 0.5 * u) / np.linalg.norm(n + 0.5 * u)          # from O_2 to the end ball's centre
    ball = Obstacle.sphere("ball", tuple(o2 + S * u - (R_LINK + R_BALL) * n), R_BALL)
    side = Obstacle.sphere("side", tuple(AWAY + o2 + S * u - (R_LINK + R_BALL) * n), R_BALL)
    end = Obstacle.sphere("end", tuple(AWAY + o2 + (R_LINK + R_BALL) * down), R_BALL)
    o1 = o2 + u + np.array([0.0, DROP, 0.0])
    scene = Scene(name="sens_link_multi", links=(LineLink(1.0, 1.0, radius=R_LINK),),
                  walls=(Wall("x2_min", 0.0, 0.5),), q0=(-math.pi / 2, 0.0, math.pi / 2 + TILT, o1[0], o1[1], 0.0),
                  gravity=9.81, obstacles=(ball, side, end))
    return load_model(scene, tangent=True)


def labels(model) -> list[str]:
    """The model's contacts as the impacts name them (O<i>/<wall>, L<i>/<obstacle>), in the gaps' order."""
    return [f"O{i}/{c.name}" if isinstance(c, Wall) else c.name for i, c in model.contacts]


@pytest.mark.parametrize("located", ["O2/x2_min", "L1/ball"])
def test_a_rod_striking_the_floor_and_a_ball_at_once_matches_central_differences(model, located):
    """The rod turned about O_1 by +-OFFSET / S so that the floor's contact or the ball's locates the impact (the
    other's gap OFFSET there, the located one's ~0); both take an impulse and the rod turns after it.  The
    sensitivities are carried through (valid, one impact differentiated) and match central differences of the final
    state at T = 0.2 s to 1e-6.  The two sides differ (t* = min of the two strike times has a kink where they meet):
    each matches its own stencil."""
    q0 = np.array(model.scene.q0, dtype=float)
    q0[2] += (OFFSET if located == "O2/x2_min" else -OFFSET) / S
    qd0, p = np.zeros(6), model.parameters({"e_ball": 0.9})
    r = simulate(model, T_END, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **OPTIONS)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["O2/x2_min", "L1/ball"]], r.message
    impact = r.impacts[0]
    assert all(c.impulse > 0.1 for c in impact.contacts)
    gaps = dict(zip(labels(model), model.contact_gaps(model.layout.reduce(impact.q))))
    other = "L1/ball" if located == "O2/x2_min" else "O2/x2_min"
    assert abs(gaps[located]) < 1e-9 and 0.5 * OFFSET < gaps[other] < OFFSET
    assert abs(impact.qd_after[2]) > 0.3                          # it turns after the strike
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    assert all(math.isfinite(v) for v in impact.dt_dp.values())
    central_differences(model, T_END, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, **OPTIONS)


@pytest.mark.parametrize("located", ["L1/end", "L1/side"])
def test_a_rod_striking_two_balls_at_once_matches_central_differences(model, located):
    """The rod AWAY from the first case strikes the end ball with O_2 and the side ball inside its length in one
    impact (which of them locates it set as above), both taking an impulse: two obstacle rows in the law, each with
    its own turning normal and e; the sensitivities (both e among the directions) against central differences."""
    q0 = np.array(model.scene.q0, dtype=float)
    q0[3:5] += AWAY[:2]
    q0[2] += (OFFSET if located == "L1/end" else -OFFSET) / S
    qd0, p = np.zeros(6), model.parameters({"e_end": 0.5, "e_side": 0.9})
    directions = DIRECTIONS[:6] + ["e_end", "e_side"]
    r = simulate(model, T_END, p=p, q0=q0, qd0=qd0, sensitivities=directions, **OPTIONS)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["L1/side", "L1/end"]], r.message
    impact = r.impacts[0]
    assert all(c.impulse > 0.1 for c in impact.contacts)
    gaps = dict(zip(labels(model), model.contact_gaps(model.layout.reduce(impact.q))))
    other = "L1/side" if located == "L1/end" else "L1/end"
    assert abs(gaps[located]) < 1e-9 and 0.5 * OFFSET < gaps[other] < OFFSET
    assert abs(impact.qd_after[2]) > 0.3
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    central_differences(model, T_END, p, q0, qd0, directions, r.sensitivities.matrix, **OPTIONS)
