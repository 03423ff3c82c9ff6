"""Coulomb friction at resting contacts without a Jacobian row (a link on a fixed obstacle): a stuck contact holds
the closest points' relative velocity along its frame's tangents t1, t2 at zero (rows J^T t1, J^T t2, their biases
from the frame's exact derivative), a sliding one takes c_f lambda_N against its sliding, as a rough wall's point.
A free rod lying across two rough bars on an incline (gravity tilted by ALPHA along the rod): with tan ALPHA < c_f it
stays exactly in place, with tan ALPHA > c_f it slides down at g (sin ALPHA - c_f cos ALPHA), without friction at
g sin ALPHA, the friction's loss closing the energy balance; pushed along the incline by a force growing linearly,
it slips where the friction it needs reaches c_f N, located as an event; the frame rows' biases against central
differences along a trajectory, at a bar, a box's face and a box's edge; sensitivities end with the link status."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import simulate
from runtime.inputs import InputSchedule

G, M, R_LINK, ALPHA = 9.81, 1.0, 0.02, 0.12
BAR_Y, BAR_X, BAR_R = 0.5, (2.7, 3.3), 0.03      # bars along X3 at X2 = BAR_Y, X1 = BAR_X, radius BAR_R
BLOCK = ((-3.0, 0.3, 0.0), (0.4, 0.3, 0.4))      # a box far from the bars (centre, half extents)
RUN = dict(rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def model(compiled):
    """A free rod of 1 m, 1 kg (theta_1 = pi/2: along -X1 from O_1), pushed along X1 (input u), two rough bars
    (friction_bar_a, friction_bar_b runtime parameters) and a rough box, gravity tilted by ALPHA towards +X1: an
    incline along the rod."""
    obstacles = (Obstacle.bar("bar_a", (BAR_X[0], BAR_Y, -0.5), (BAR_X[0], BAR_Y, 0.5), BAR_R, friction=0.5),
                 Obstacle.bar("bar_b", (BAR_X[1], BAR_Y, -0.5), (BAR_X[1], BAR_Y, 0.5), BAR_R, friction=0.5),
                 Obstacle.box("block", *BLOCK, friction=0.5))
    scene = Scene(name="rod_on_rough_bars", links=(LineLink(1.0, M, radius=R_LINK),), gravity=G,
                  gravity_direction=(math.sin(ALPHA), -math.cos(ALPHA), 0.0), inputs=("X1",),
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 3.5, BAR_Y + BAR_R + R_LINK, 0.0), obstacles=obstacles)
    return compiled(scene, tangent=True)


def on_the_bars(model, friction, t_end, push=0.0, **kwargs):
    """The rod from rest lying across both bars, centred between them, with c_f = friction at both."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, 0.5 * sum(BAR_X) + 0.5, BAR_Y + BAR_R + R_LINK, 0.0])
    p = model.parameters({"friction_bar_a": friction, "friction_bar_b": friction})
    return simulate(model, t_end, q0=q0, qd0=np.zeros(6), p=p, u=kwargs.pop("u", [push]), **RUN, **kwargs)


def test_below_the_friction_angle_the_rod_stays_stuck(model):
    """tan ALPHA = 0.121 < c_f = 0.3: both contacts stick at the start and hold for a second, the rod not moving
    (no creep), friction taking nothing; the resting forces balance the weight along the incline's normal."""
    r = on_the_bars(model, 0.3, 1.0, t_eval=np.linspace(0.0, 1.0, 11))
    assert r.status == 0, r.message
    assert sorted(r.resting_final) == [(1, "L1/bar_a"), (1, "L1/bar_b")]
    assert r.n_sticks == 2 and r.n_slips == 0
    assert np.abs(r.q - r.q[0]).max() < 1e-12 and np.abs(r.qd).max() < 1e-12
    assert r.loss_friction == 0.0 and abs(r.energy_drift) < 1e-12


@pytest.mark.parametrize("friction", [0.1, 0.0])
def test_above_the_friction_angle_the_rod_slides_at_the_coulomb_rate(model, friction):
    """tan ALPHA > c_f: the rod slides down the incline along its axis at g (sin ALPHA - c_f cos ALPHA) from the
    start, never stuck (c_f = 0: g sin ALPHA, the frictionless rest), its height and attitude held; friction takes
    c_f m g cos ALPHA times the distance, and the energy balance closes with that loss."""
    t = np.array([0.1, 0.3, 0.5])
    r = on_the_bars(model, friction, 0.5, t_eval=t)
    assert r.status == 0, r.message
    assert sorted(r.resting_final) == [(1, "L1/bar_a"), (1, "L1/bar_b")]
    a = G * (math.sin(ALPHA) - friction * math.cos(ALPHA))
    assert np.abs(r.qd[:, 3] - a * t).max() < 1e-9
    assert np.abs(r.q[:, 3] - (0.5 * sum(BAR_X) + 0.5 + 0.5 * a * t * t)).max() < 1e-9
    assert np.abs(r.q[:, 4] - (BAR_Y + BAR_R + R_LINK)).max() < 1e-9 and np.abs(r.qd[:, [0, 1, 2, 4, 5]]).max() < 1e-9
    distance = 0.5 * a * 0.25
    assert r.loss_friction == pytest.approx(friction * M * G * math.cos(ALPHA) * distance, rel=1e-9, abs=1e-12)
    assert abs(r.energy_drift) < 1e-8
    assert r.n_sticks == 0 and r.n_slips == 0                   # the cone cannot hold it: sliding from the start


def test_a_growing_push_makes_the_rod_slip_where_it_needs_c_f_N(model):
    """Stuck at c_f = 0.3 and pushed down the incline by F = k t: the friction needed, m g sin ALPHA + k t, reaches
    c_f m g cos ALPHA at t* = m g (c_f cos ALPHA - sin ALPHA) / k, where both contacts slip (each holding half),
    located as events; then the rod accelerates down the incline."""
    c_f, k = 0.3, 5.0
    push = InputSchedule([0.0, 1.0], [[0.0], [k]], mode="linear")
    r = on_the_bars(model, c_f, 0.6, u=push, t_eval=[])
    assert r.status == 0, r.message
    events = [(e.kind, e.t, e.label) for e in r.contact_events if e.kind in ("stick", "slip")]
    assert [kind for kind, _, _ in events] == ["stick", "stick", "slip", "slip"]
    t_slip = M * G * (c_f * math.cos(ALPHA) - math.sin(ALPHA)) / k
    assert sorted(label for kind, _, label in events if kind == "slip") == ["L1/bar_a", "L1/bar_b"]
    for _, t, _ in events[2:]:
        assert abs(t - t_slip) < 1e-12
    assert r.qd_final[3] > 0.0 and abs(r.energy_drift) < 1e-8


def test_sensitivities_hold_the_stuck_rod_and_follow_the_sliding_one(model):
    """Stuck on the rough bars (c_f = 0.3; the two contacts' t1 rows, both along the rod, the same row: one drops out
    as in the loop) the rod does not move, so after 0.5 s its position moves with its start's along the bars (1 on
    the diagonal) and with nothing else, its velocities with nothing.  Sliding (c_f = 0.1 at both) it accelerates at
    a = g (sin ALPHA - c_f cos ALPHA) whatever the bars share of its weight, bar a's share w_a = (X_b - x_c) / (X_b -
    X_a) = 1/2 - a t^2 / 1.2 as its centre x_c moves on; bar a's coefficient then moves it by d'' = -g cos ALPHA w_a
    (the shares summing to 1, x_c's own change leaves the total friction as it is): dX1/dc_a = -g cos ALPHA (T^2 / 4
    - a T^4 / 14.4), its velocity's -g cos ALPHA (T / 2 - a T^3 / 3.6), and dX1/dg = (sin ALPHA - c_f cos ALPHA)
    T^2 / 2."""
    names = ["q0[X1]", "q0[X3]", "g", "friction_bar_a"]
    r = on_the_bars(model, 0.3, 0.5, sensitivities=names, t_eval=[])
    assert r.status == 0 and r.n_sticks == 2, r.message
    assert r.sensitivities.valid, r.sensitivity_message
    s = r.sensitivities
    expected = np.zeros((len(s.rows), len(names)))
    expected[s.rows.index("q[X1]"), 0] = expected[s.rows.index("q[X3]"), 1] = 1.0
    assert np.abs(s.matrix - expected).max() < 1e-9
    T, c_f = 0.2, 0.1
    r = on_the_bars(model, c_f, T, sensitivities=names, t_eval=[])
    assert r.status == 0 and r.n_sticks == 0 and r.n_slips == 0, r.message
    assert r.sensitivities.valid, r.sensitivity_message
    s, a, cos = r.sensitivities, G * (math.sin(ALPHA) - c_f * math.cos(ALPHA)), math.cos(ALPHA)
    column = {name: s.matrix[:, names.index(name)] for name in names}
    X1, V1 = s.rows.index("q[X1]"), s.rows.index("qd[X1]")
    assert column["friction_bar_a"][X1] == pytest.approx(-G * cos * (T ** 2 / 4 - a * T ** 4 / 14.4), rel=1e-8)
    assert column["friction_bar_a"][V1] == pytest.approx(-G * cos * (T / 2 - a * T ** 3 / 3.6), rel=1e-8)
    assert column["g"][X1] == pytest.approx((math.sin(ALPHA) - c_f * cos) * T ** 2 / 2, rel=1e-8)
    assert column["q0[X1]"][X1] == pytest.approx(1.0, rel=1e-9)
