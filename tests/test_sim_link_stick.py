"""Coulomb friction at resting link pairs (friction.links, along the pair's contact frame at the closest points of
the two axes, both sides moving): three one-link chains on an incline (gravity tilted by ALPHA along X1), rods A1 and
A2 lying across two rough bars (c_f = 1, stuck) and rod B lying across A1 and A2 (the pairs' c_f = 0.1 < tan ALPHA).
B slides down the incline on the two rods at g (sin ALPHA - c_f cos ALPHA) while A1 and A2 are held by the bars,
every contact a link pair or an obstacle; the energy balance closes with the friction's loss."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import Chains, LineLink, Obstacle, Scene
from runtime import simulate

G, ALPHA, C_F = 9.81, 0.12, 0.1
BAR_Y, BAR_R, R_B = 0.5, 0.03, 0.02                  # bars along X1 at X2 = BAR_Y, X3 = -0.3, 0.3; rod B's radius
A_X = (2.7, 3.3)                                      # rods A1, A2 (bare segments) along X3 at these X1


@pytest.fixture(scope="module")
def model(compiled):
    bars = (Obstacle.bar("bar_l", (2.0, BAR_Y, -0.3), (4.0, BAR_Y, -0.3), BAR_R, friction=1.0),
            Obstacle.bar("bar_r", (2.0, BAR_Y, 0.3), (4.0, BAR_Y, 0.3), BAR_R, friction=1.0))
    gravity = (math.sin(ALPHA), -math.cos(ALPHA), 0.0)

    def chain(k, q0, radius):
        return Scene(name=f"link_stick_c{k}", links=(LineLink(1.0, 1.0, radius=radius),), gravity=G,
                     gravity_direction=gravity, obstacles=bars, q0=q0)

    y_a = BAR_Y + BAR_R
    chains = (chain(1, (0.0, 0.0, math.pi / 2, A_X[0], y_a, -0.5), 0.0),      # along +X3, centred on X3 = 0
              chain(2, (0.0, 0.0, math.pi / 2, A_X[1], y_a, -0.5), 0.0),
              chain(3, (-math.pi / 2, 0.0, math.pi / 2, 3.5, y_a + R_B + 1e-12, 0.0), R_B))   # along -X1 from O_5
    return compiled(Chains(name="link_stick", chains=chains, link_restitution=0.0, link_friction=C_F))


def test_a_rod_slides_down_two_rods_held_by_rough_bars(model):
    """The pairs L1-L5 and L3-L5 come to rest and slip at the start (tan ALPHA > c_f), the rods A1, A2 stick on the
    bars at the first step's end (tried while the pairs were stuck, their cones could not hold the stack); from
    then on B's velocity grows at g (sin ALPHA - c_f cos ALPHA) (1e-9 between samples), A1 and A2 do not move
    (1e-12), B keeps its height and attitude; the balance closes with friction's loss, about c_f m g cos ALPHA times
    B's slide."""
    t = np.array([0.1, 0.3, 0.5])
    r = simulate(model, 0.5, rtol=1e-10, atol=1e-12, t_eval=t)
    assert r.status == 0, r.message
    assert sorted(label for _, label in r.resting_final) == sorted(
        ["L1-L5", "L3-L5", "L1/bar_l", "L1/bar_r", "L3/bar_l", "L3/bar_r"])
    events = [(e.kind, e.label) for e in r.contact_events if e.kind in ("stick", "slip")]
    assert sorted(label for kind, label in events if kind == "slip") == ["L1-L5", "L3-L5"]
    assert all(e.t == 0.0 for e in r.contact_events if e.kind == "slip")
    assert sorted(label for kind, label in events if kind == "stick" and "bar" in label) == [
        "L1/bar_l", "L1/bar_r", "L3/bar_l", "L3/bar_r"]
    a = G * (math.sin(ALPHA) - C_F * math.cos(ALPHA))
    b = 12                                              # rod B's coordinates: qd[12:18], X1 rate qd[15]
    assert np.abs(np.diff(r.qd[:, b + 3]) - a * np.diff(t)).max() < 1e-9
    assert np.abs(r.qd[:, :12]).max() < 1e-12 and np.abs(r.q[:, [3, 9]] - A_X).max() < 1e-9
    assert np.abs(r.qd[:, [b, b + 1, b + 2, b + 4, b + 5]]).max() < 1e-9
    slide = r.q[-1, b + 3] - 3.5
    assert r.loss_friction == pytest.approx(C_F * G * math.cos(ALPHA) * slide, rel=1e-3)
    assert abs(r.energy_drift) < 1e-8
