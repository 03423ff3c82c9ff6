"""Forward sensitivities through the impact of a link on a fixed obstacle (gac_sens.c, a contact of kind
GAC_CONTACT_OBSTACLE): the derivative of the contact's row J^T n (gac_contact_normal_tangent: the closest point's
motion, the normal's rotation, the points' Jacobians' change) against central differences of gac_contact_normal and
of the gap, with the closest point inside the rod and at its end; and a tilted rod falling onto a ball off its centre
of mass, so that it turns after the strike, whose final state's sensitivities to the initial state, g, the ball's
restitution and the rod's length match central differences of whole runs (the same impacts across the stencil)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from tests.test_sim_sensitivities import central_differences

TIGHT = dict(rtol=1e-12, atol=1e-14)
BALL = (-0.45, 0.55, 0.0)
DIRECTIONS = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "e_ball", "l_1"]


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m (capsule radius 0.02 m) tilted 0.15 rad from the horizontal, O_1 = (0.2, 1, 0), falling
    under g onto a ball of radius 0.1 m: shifted along X1 at the start (q0[X1]), the rod strikes the ball inside its
    length (off its centre of mass) or with its end."""
    ball = Obstacle.sphere("ball", BALL, 0.1)
    scene = Scene(name="sens_obstacle_strike", links=(LineLink(1.0, 1.0, radius=0.02),),
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.15, 0.2, 1.0, 0.0), gravity=9.81, obstacles=(ball,))
    return load_model(scene, tangent=True)


def normal_tangent(model, q, dq, dp):
    """(d gap, J^T n, d(J^T n)) of the ball's contact along (dq, dp), by gac_contact_normal_tangent."""
    dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
    q, dq, dp = (np.ascontiguousarray(x, dtype=float) for x in (q, dq, dp))
    code = model.lib.gac_contact_normal_tangent(model.ffi.addressof(model.c.model), model._ptr(q), model._ptr(model.p),
                                                0, model._ptr(dq), model._ptr(dp), dgap, model._ptr(g),
                                                model._ptr(dg))
    assert code == model.lib.GAC_OK
    return dgap[0], g, dg


@pytest.mark.parametrize("x1, inside", [(0.2, True), (0.65, False)])
def test_the_rows_derivative_matches_central_differences_of_the_c_functions(model, x1, inside):
    """At random configurations near the ball, along random directions of q and of the rod's length: d gap and
    d(J^T n) against central differences (step 1e-5, fourth order) of the gap and of gac_contact_normal, to 1e-8 of
    the row's size; the closest point inside the rod (its motion and the normal's rotation) or at its end."""
    rng = np.random.default_rng(3)
    index = model.parameter_names.index("l_1")
    for _ in range(4):
        q = np.array([math.pi / 2 + 0.15 + rng.uniform(-0.1, 0.1), x1 + rng.uniform(-0.05, 0.05), 0.7])
        s = model.obstacle_gap(q, 1, "ball")[1]
        assert (0.0 < s < 1.0) == inside
        dq, dp = rng.normal(size=model.nq), np.zeros(len(model.p))
        dp[index] = rng.normal()
        dgap, g, dg = normal_tangent(model, q, dq, dp)
        assert np.allclose(g, model.contact_normal(q, 0), rtol=0, atol=1e-14)

        def at(h):
            p = model.p.copy()
            p[index] += h * dp[index]
            return model.contact_gaps(q + h * dq, p)[0], model.contact_normal(q + h * dq, 0, p)

        h = 1e-5
        (g1, n1), (g_1, n_1), (g2, n2), (g_2, n_2) = at(h), at(-h), at(2 * h), at(-2 * h)
        fd_gap = (8 * (g1 - g_1) - (g2 - g_2)) / (12 * h)
        fd_row = (8 * (n1 - n_1) - (n2 - n_2)) / (12 * h)
        assert dgap == pytest.approx(fd_gap, abs=1e-9)
        assert np.abs(dg - fd_row).max() <= 1e-8 * max(1.0, np.abs(fd_row).max())
        assert np.abs(dg).max() > 1e-3                         # the row turns: there is something to check


@pytest.mark.parametrize("x1, inside", [(0.2, True), (0.55, False)])
def test_a_rod_striking_the_ball_matches_central_differences(model, x1, inside):
    """The rod dropped from rest strikes the ball once (e = 0.7) and turns; the final state's sensitivities at
    T = 0.3 s against central differences of whole runs (tests/test_sim_sensitivities.py's helper, to 1e-6)."""
    p = model.parameters({"e_ball": 0.7})
    q0 = np.array(model.scene.q0, dtype=float)
    q0[3] = x1
    qd0 = np.zeros(6)
    r = simulate(model, 0.3, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["L1/ball"]], r.message
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    impact = r.impacts[0]
    assert (0.0 < model.obstacle_gap(model.layout.reduce(impact.q), 1, "ball")[1] < 1.0) == inside
    assert abs(impact.qd_after[2]) > 0.5                           # struck off its centre of mass, it turns
    assert all(math.isfinite(v) for v in impact.dt_dp.values())
    central_differences(model, 0.3, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, **TIGHT)
