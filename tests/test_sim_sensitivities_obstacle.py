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


def normal_tangent(model, q, dq, dp, descriptor=None):
    """(d gap, J^T n, d(J^T n)) of the ball's contact along (dq, dp), by gac_contact_normal_tangent (on the model's
    descriptor, or on ``descriptor``)."""
    dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
    q, dq, dp = (np.ascontiguousarray(x, dtype=float) for x in (q, dq, dp))
    descriptor = model.ffi.addressof(model.c.model) if descriptor is None else descriptor
    code = model.lib.gac_contact_normal_tangent(descriptor, model._ptr(q), model._ptr(model.p), 0, model._ptr(dq),
                                                model._ptr(dp), dgap, model._ptr(g), model._ptr(dg))
    assert code == model.lib.GAC_OK
    return dgap[0], g, dg


STEPS = ((1, 45.0), (2, -9.0), (3, 1.0))            # 6th-order central difference: sum c_k (f(+kh) - f(-kh)) / 60h


def central(f, h=1e-4):
    return sum(c * (f(k * h) - f(-k * h)) for k, c in STEPS) / (60.0 * h)


@pytest.mark.parametrize("x1, inside", [(0.2, True), (0.65, False)])
def test_the_rows_derivative_matches_central_differences_of_the_c_functions(model, x1, inside):
    """At random configurations near the ball, along random directions of q and of the rod's length: d gap and
    d(J^T n) (exact: the points' and their velocities' tangent kernels) against sixth-order central differences
    (step 1e-4) of the gap and of gac_contact_normal, to 1e-10 of the row's size (seen ~1e-11); the closest point
    inside the rod (its motion and the normal's rotation) or at its end.  A descriptor without those two kernels
    (its own central differences of contact_points and contact_velocities) agrees to 1e-10."""
    rng = np.random.default_rng(3)
    index = model.parameter_names.index("l_1")
    without_point_tangents = model.ffi.new("gac_model *", model.c.model)
    without_point_tangents.contact_points_tangent = without_point_tangents.contact_velocities_tangent = model.ffi.NULL
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
            return np.concatenate([[model.contact_gaps(q + h * dq, p)[0]], model.contact_normal(q + h * dq, 0, p)])

        fd = central(at)
        assert dgap == pytest.approx(fd[0], rel=1e-10)
        assert np.abs(dg - fd[1:]).max() <= 1e-10 * max(1.0, np.abs(fd[1:]).max())
        assert np.abs(dg).max() > 1e-3                         # the row turns: there is something to check
        _, _, dg_fd = normal_tangent(model, q, dq, dp, descriptor=without_point_tangents)
        assert np.abs(dg_fd - dg).max() <= 1e-10 * np.abs(dg).max()


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


# ---- boxes and planes (gac_obstacle.c): a face's constant normal, an edge's or a corner's turning one ----------

@pytest.fixture(scope="module")
def box_model():
    """tests/test_sim_obstacle_box.py's scene (a free rod of 1 m among a slab, a ridge, a corner, a tilted box and a
    roof plane), with the tangent kernels."""
    from tests.test_sim_obstacle_box import G, OBSTACLES, R_LINK
    scene = Scene(name="obstacle_box", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 0.5, 1.0, 0.0), obstacles=OBSTACLES)
    return load_model(scene, tangent=True)


def test_box_and_plane_rows_derivative_matches_central_differences(box_model):
    """Random states of the rod clear of each box and of the plane, for each contact (the link's: its closest point
    at an end of the rod on a face, inside it against an edge or a corner; each joint point's): d gap and d(J^T n) along random directions of q and of the rod's length
    against sixth-order central differences of the gap and of gac_contact_normal, to 1e-10 of the row's size."""
    from tests.test_sim_obstacle_box import OBSTACLES
    model = box_model
    rng = np.random.default_rng(3)
    centres = {o.name: np.array(o.a) for o in OBSTACLES[:4]} | {"roof": np.array((0.0, 5.5, 0.0))}
    index = model.parameter_names.index("l_1")
    checked = {"end": 0, "inside": 0}
    for trial in range(120):                                  # each link's and joint point's contact in turn
        c = trial % len(model.contacts)
        o = model.contacts[c][1].obstacle
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 3), centres[o.name] + rng.uniform(-0.9, 0.9, 3)])
        q[1] = rng.uniform(-1.2, 1.2)                         # theta_0 away from the base chart's lock
        gap, s, _, _ = model.contact_geometry(q, c)
        if gap < 0.02:                                        # inside or near: the gradient may have a kink
            continue
        dq, dp = rng.normal(size=model.nq), np.zeros(len(model.p))
        dp[index] = rng.normal()
        dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
        code = model.lib.gac_contact_normal_tangent(model.ffi.addressof(model.c.model), model._ptr(q),
                                                    model._ptr(model.p), c, model._ptr(dq), model._ptr(dp), dgap,
                                                    model._ptr(g), model._ptr(dg))
        assert code == model.lib.GAC_OK, (trial, model.contacts[c][1].name)

        def at(h):
            p = model.p.copy()
            p[index] += h * dp[index]
            return np.concatenate([[model.contact_gaps(q + h * dq, p)[c]], model.contact_normal(q + h * dq, c, p)])

        fd = central(at)
        # (the stencil's round-off on the gap, a difference of positions ~|x|: 2e-16 |x| 110 / (60 h) = 4e-12 |x|,
        # the roof 6 m up)
        size = max(1.0, float(np.abs(q[3:]).max()))
        assert dgap[0] == pytest.approx(fd[0], rel=1e-10, abs=1e-11 * size), (trial, model.contacts[c][1].name)
        assert np.abs(dg - fd[1:]).max() <= 1e-10 * max(1.0, np.abs(fd[1:]).max()), (trial, model.contacts[c][1].name)
        checked["inside" if 0.0 < s < 1.0 else "end"] += 1
    assert checked["end"] >= 10 and checked["inside"] >= 8


BOX_DIRECTIONS = ["q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[theta_1]", "g", "l_1", "q0[X3]", "q0[theta_0]"]


@pytest.mark.parametrize("name, x1, top, tilt, x3, impacts", [
    ("ridge", 3.75, 0.3 + 0.2 * math.sqrt(2), 0.0, 0.1, 1),       # across the ridge's edge, off the rod's middle
    ("corner", 6.3, 0.3 + 0.25 * math.sqrt(3), 0.1, 0.05, 1),     # onto the cube's corner
    ("slab", 0.7, 0.4, 0.15, 0.0, 3),                             # end first onto the slab's face, then both ends
    ("tilted", -2.6, 1.5, 0.2, 0.2, 1)])                          # onto a box turned at random
def test_a_rod_striking_a_box_matches_central_differences(box_model, name, x1, top, tilt, x3, impacts):
    """The rod, tilted by ``tilt`` and dropped from rest onto a box (e = 0.6), strikes it (an edge's or a corner's
    normal turning with the rod, a face's constant): the sensitivities are carried through (valid, each impact
    differentiated) and match central differences of whole runs at T = 0.3-0.4 s."""
    from tests.test_sim_obstacle_box import H, OBSTACLES, R_LINK
    model = box_model
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + tilt, x1, top + R_LINK + H, x3])
    p = model.parameters({f"e_{o.name}": 1.0 for o in OBSTACLES} | {f"e_{name}": 0.6})
    directions = BOX_DIRECTIONS + [f"e_{name}"]
    t_end = 0.4 if name == "tilted" else 0.3
    r = simulate(model, t_end, p=p, q0=q0, qd0=np.zeros(6), sensitivities=directions, **TIGHT)
    # an end on a face strikes by its joint point's contact (the slab: the lower end, the other, the lower again)
    struck = [["O2/slab"], ["O1/slab"], ["O2/slab"]] if name == "slab" else [[f"L1/{name}"]] * impacts
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == struck, r.message
    assert r.sensitivities.valid and r.sensitivities.n_impacts == impacts, r.sensitivity_message
    central_differences(model, t_end, p, q0, np.zeros(6), directions, r.sensitivities.matrix, **TIGHT)
