"""No pass-through of finite obstacles between the event samples (docs/simulation.md, "Events", pass-throughs): a
rod dropped flat onto a box with the integrator's steps unbounded (free flight is integrated exactly, so its steps
grow to seconds) bounces, falls back, lands and rests on the box instead of crossing it; a rod thrown so fast that
one step carries it across a small sphere strikes the sphere.  Each run is checked independently: the rod's segment
against the body (numpy distances) at dense samples of the run.  A throw far from both costs the same steps and
right-hand sides as on a model without obstacles."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from studies.fuzz import segment_distance

G, R_LINK, TOP = 9.81, 0.02, 0.4
BALL_C, BALL_R = (3.0, 5.0, 0.0), 0.05
SLAB = Obstacle.box("slab", (0.0, TOP / 2, 0.0), (0.8, TOP / 2, 0.5))
BALL = Obstacle.sphere("ball", BALL_C, BALL_R)
FLAT = (-math.pi / 2, 0.0, math.pi / 2)          # the rod horizontal, along -X1 from O_1


def rod_scene(name, obstacles):
    return Scene(name=name, links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G, q0=(*FLAT, 0.5, 1.0, 0.0),
                 obstacles=obstacles)


@pytest.fixture(scope="module")
def model():
    return load_model(rod_scene("tunnel_obstacles", (SLAB, BALL)))


def segments(model, result):
    """The rod's joint points O_1, O_2 at each sample of the run."""
    return [model.contact_points(model.layout.reduce(q)) for q in result.q]


def test_a_rod_dropped_on_a_box_without_a_step_limit_lands_on_it(model):
    q0 = np.array([*FLAT, 0.5, TOP + R_LINK + 0.1, 0.0])
    r = simulate(model, 1.5, q0=q0, qd0=np.zeros(6), t_eval=np.linspace(0.0, 1.5, 3001), p={"e_slab": 0.3})
    assert r.status == 0, r.message
    assert len(r.impacts) >= 2 and all([c.wall for c in i.contacts] == ["L1/slab"] for i in r.impacts)
    assert r.impacts[0].t == pytest.approx(math.sqrt(2 * 0.1 / G), rel=1e-9)
    assert r.resting_final == [(1, "L1/slab")]
    assert r.q_final[4] == pytest.approx(TOP + R_LINK, abs=1e-9)
    # independently: the segment never inside the slab by more than the contact tolerance
    depth = [SLAB.distance(p[0], p[1]) - R_LINK for p in segments(model, r)]
    assert min(depth) >= -1e-6


def test_a_rod_thrown_fast_at_a_small_sphere_strikes_it(model):
    """At 60 m/s the rod crosses the sphere (0.14 m across with the rod's radius) in 2.3 ms; free flight's steps are
    far longer."""
    q0 = np.array([*FLAT, 0.0, BALL_C[1], 0.0])
    qd0 = np.array([0.0, 0.0, 0.0, 60.0, 0.0, 0.0])
    r = simulate(model, 0.2, q0=q0, qd0=qd0, t_eval=np.linspace(0.0, 0.2, 4001), p={"e_ball": 1.0})
    assert r.status == 0, r.message
    assert r.impacts and [c.wall for c in r.impacts[0].contacts] == ["L1/ball"]
    assert r.impacts[0].qd_after[3] < 0.0 < r.impacts[0].qd_before[3]
    gaps = [segment_distance(p[0], p[1], np.array(BALL_C), np.array(BALL_C)) - BALL_R - R_LINK
            for p in segments(model, r)]
    assert min(gaps) >= -1e-6
    assert r.q_final[3] < BALL_C[0] - 1.0        # sent back, never past the sphere


def test_far_from_the_obstacles_the_run_costs_what_it_costs_without_them(model):
    bare = load_model(rod_scene("tunnel_bare", ()))
    q0 = np.array([-math.pi / 2, 0.0, 1.2, 20.0, 30.0, 0.0])
    qd0 = np.array([0.0, 0.0, 3.0, 1.0, 4.0, 0.0])
    runs = [simulate(m, 2.0, q0=q0, qd0=qd0, t_eval=[]) for m in (model, bare)]
    assert all(r.status == 0 and not r.impacts for r in runs)
    assert (runs[0].n_steps, runs[0].n_rhs) == (runs[1].n_steps, runs[1].n_rhs)
    assert np.array_equal(runs[0].q_final, runs[1].q_final)
