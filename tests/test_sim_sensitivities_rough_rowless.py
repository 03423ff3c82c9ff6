"""Forward sensitivities through frictional impacts (the GDI law) at contacts without a Jacobian row (gac_sens.c): a
rod striking a rough ball obliquely, stuck or sliding on it, and two capsule links of one chain striking each other
with friction.  Coulomb's cone acts along the contact frame's rows J^T t1, J^T t2 (t1 link i's axis off the normal,
t2 = n x t1; a planar model's t2, which no motion takes, left out as the law leaves it); the law's differential takes
their derivative from the frame's turning and the closest points' motion (gac_contact_frame_tangent).  The final
state's sensitivities to the initial state, g, the rod's length, the obstacle's place and size, its restitution and
its friction coefficient match central differences of whole runs (the same impacts across the stencil)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from tests.test_sim_link_loop import folding_scene
from tests.test_sim_sensitivities import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
BALL = Obstacle.sphere("ball", (-0.45, 0.55, 0.0), 0.1, friction=0.4)
DIRECTIONS = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "l_1", "e_ball", "friction_ball",
              "center_x_ball", "radius_ball"]


def rough_ball_scene() -> Scene:
    """A free rod of 1 m (capsule radius 0.02 m) tilted 0.15 rad from the horizontal, O_1 = (0.2, 1, 0), falling under
    g onto a rough ball (c_f = 0.4) of radius 0.1 m inside its length."""
    return Scene(name="sens_rough_ball", links=(LineLink(1.0, 1.0, radius=0.02),),
                 q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.15, 0.2, 1.0, 0.0), gravity=9.81, obstacles=(BALL,))


@pytest.fixture(scope="module")
def planar():
    return load_model(rough_ball_scene(), tangent=True)


def _mode(impact, c_f: float) -> str:
    (contact,) = impact.contacts
    return "slide" if math.hypot(*contact.impulse_t) >= (1 - 1e-6) * c_f * contact.impulse else "stick"


@pytest.mark.parametrize("c_f, vx, mode", [(0.4, 1.5, "slide"), (0.4, 0.3, "stick"), (2.0, 1.0, "stick")])
def test_a_rod_striking_a_rough_ball_matches_central_differences(planar, c_f, vx, mode):
    """The rod thrown sideways at vx onto the ball (e = 0.7): one frictional impact, its tangential impulse on the
    cone (sliding through the impact) or inside it (stuck), after which the rod flies clear; the sensitivities are
    carried through it (valid, finite dt*) and match central differences of the final state at T = 0.3 s."""
    model = planar
    p = model.parameters({"e_ball": 0.7, "friction_ball": c_f})
    q0, qd0 = np.array(model.scene.q0, dtype=float), np.zeros(6)
    qd0[3] = vx
    r = simulate(model, 0.3, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["L1/ball"]], r.message
    impact = r.impacts[0]
    assert impact.law == "gdi" and abs(impact.contacts[0].impulse_t[0]) > 1e-3 * impact.contacts[0].impulse
    assert _mode(impact, c_f) == mode
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    assert all(math.isfinite(v) for v in impact.dt_dp.values())
    central_differences(model, 0.3, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, **TIGHT)


def test_a_rod_striking_a_rough_ball_in_3d_matches_central_differences():
    """The general (3D) model, the rod thrown sideways and out of the plane: both frame rows act, the impulse slides
    on the cone in a direction of its own; the sensitivities match central differences (directions out of the plane
    too)."""
    model = load_model(rough_ball_scene(), tangent=True, specialise=False)
    p = model.parameters({"e_ball": 0.7, "friction_ball": 0.4})
    q0, qd0 = np.array(model.scene.q0, dtype=float), np.zeros(6)
    qd0[3], qd0[5] = 1.2, 0.15
    directions = DIRECTIONS + ["q0[X3]", "qd0[X3]", "qd0[theta_0]", "center_z_ball"]
    r = simulate(model, 0.3, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["L1/ball"]], r.message
    impact = r.impacts[0]
    assert _mode(impact, 0.4) == "slide" and min(abs(x) for x in impact.contacts[0].impulse_t) > 1e-3
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    central_differences(model, 0.3, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_a_rough_link_pair_strike_matches_central_differences():
    """tests/test_sim_sensitivities_link.py's folding chain with friction between its links (c_f = 0.3): links 1 and
    3 strike once under the frictional law; the sensitivities match central differences of the final state."""
    scene = dataclasses.replace(folding_scene(1.0), name="sens_rough_link_pair", link_friction=0.3)
    model = load_model(scene, tangent=True)
    directions = ["q0[theta_2]", "q0[theta_3]", "qd0[theta_2]", "qd0[X1]", "qd0[theta_1]", "l_3", "mu_2"]
    q0, qd0, p = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float), model.p.copy()
    r = simulate(model, 0.5, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["O1-L3"]], r.message
    impact = r.impacts[0]
    assert impact.law == "gdi" and abs(impact.contacts[0].impulse_t[0]) > 1e-3 * impact.contacts[0].impulse
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    central_differences(model, 0.5, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)
