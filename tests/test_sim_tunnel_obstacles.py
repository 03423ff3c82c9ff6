"""No pass-through of finite obstacles between the event samples (docs/simulation.md, "Events", pass-throughs): a
rod dropped flat onto a box with the integrator's steps unbounded (free flight is integrated exactly, so its steps
grow to seconds) bounces, falls back, lands and rests on the box instead of crossing it; a rod thrown so fast that
one step carries it across a small sphere strikes the sphere; a turning rod whose free end sweeps through a bead
faster inside a sample interval than any of its points moves at the interval's ends strikes the bead (the bound's
factor 2 on the speed is what finds it).  Each run is checked independently: the rod's segment against the body
(numpy distances) at dense samples of the run.  A throw far from both costs the same steps and right-hand sides as
on a model without obstacles."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, RigidLink, Scene
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
    ends = ["O1/slab", "O2/slab"]                   # level on a face: both ends' contacts at once
    assert len(r.impacts) >= 2 and all(sorted(c.wall for c in i.contacts) == ends for i in r.impacts)
    assert r.impacts[0].t == pytest.approx(math.sqrt(2 * 0.1 / G), rel=1e-9)
    assert sorted(r.resting_final) == [(1, "O1/slab"), (1, "O2/slab")]
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


# A rigid rod of 1 m with its mass at O_1 (a hammer's head; no gravity): O_1 flies straight at V along X1 while the rod
# turns at OMEGA, so q is linear in t and RK4 integrates it exactly with any step.  The free end O_2 moves at
# |V + OMEGA x (O_2 - O_1)|, up to V + OMEGA L = 20 m/s where the turn carries it along X1.
V, OMEGA, BEAD_R = 10.0, 10.0, 0.03
BEAD = Obstacle.sphere("bead", (0.0, 0.0, 0.0), BEAD_R)
DELTA = 0.57                                  # s: the sample interval (RK4's step, 1 sample per step)
T_CROSS, ANGLE_CROSS = 2.8 * DELTA, -math.pi / 2 + 1.16     # O_2 at the bead's centre; the rod's angle from X1 then


@pytest.fixture(scope="module")
def whirl():
    head = RigidLink(1.0, 1.0, (0.0, 0.0, 0.0), ((1e-4, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1)))
    return load_model(Scene(name="tunnel_whirl", links=(head,), gravity=0.0, q0=(*FLAT, 0.0, 3.0, 0.0),
                            obstacles=(BEAD,)))


def whirl_points(t):
    """O_1, O_2 and the speed of the faster at time t of the free motion (numpy, independent of the model)."""
    angle = ANGLE_CROSS + OMEGA * (t - T_CROSS)
    o1 = np.array([V * (t - T_CROSS), 0.0, 0.0]) - [math.cos(ANGLE_CROSS), math.sin(ANGLE_CROSS), 0.0]
    o2 = o1 + [math.cos(angle), math.sin(angle), 0.0]
    v2 = np.array([V - OMEGA * math.sin(angle), OMEGA * math.cos(angle), 0.0])
    return o1, o2, max(V, float(np.linalg.norm(v2)))


def test_a_rod_whose_end_speeds_up_inside_a_sample_interval_strikes_a_bead(whirl):
    """Over the sample interval [2, 3] DELTA the rod's free end sweeps through the bead (0.06 m across) at 16.7 m/s
    (up to 20 m/s inside the interval), while at the interval's ends no point of the rod moves faster than O_1,
    w = 10 m/s (the turn carries O_2 against the flight there).  The gaps at the ends, g_a + g_b = 5.79 m, exceed
    w DELTA = 5.70 m: only the bound's factor 2 (2 w DELTA = 11.4 m) splits the interval and finds the strike; the end
    speeds taken as the largest inside would pass it as clear.  Neither the samples (gaps > 0 at both ends) nor the
    dip search (which needs the gap falling at the interval's start; here it rises) see it."""
    t_a, t_b = 2 * DELTA, 3 * DELTA
    bead = np.zeros(3)
    gap = lambda t: segment_distance(*whirl_points(t)[:2], bead, bead) - BEAD_R
    w = max(whirl_points(t_a)[2], whirl_points(t_b)[2])
    assert w * (t_b - t_a) <= gap(t_a) + gap(t_b) < 2 * w * (t_b - t_a)       # the regime: only the factor 2 splits
    assert min(gap(t) for t in np.linspace(t_a, t_b, 2001)) < -0.02               # the end passes through the bead
    assert gap(t_a + 1e-7) > gap(t_a - 1e-7)                                       # receding at the start: no dip
    q0 = np.array([*FLAT[:2], ANGLE_CROSS - OMEGA * T_CROSS - math.pi / 2, *whirl_points(0.0)[0]])
    qd0 = np.array([0.0, 0.0, OMEGA, V, 0.0, 0.0])
    r = simulate(whirl, 4 * DELTA, q0=q0, qd0=qd0, method="rk4", dt=DELTA, event_samples=1, p={"e_bead": 1.0},
                 t_eval=np.linspace(0.0, 4 * DELTA, 4001))
    assert r.status == 0, r.message
    assert r.impacts and [c.wall for c in r.impacts[0].contacts] == ["L1/bead"] and t_a < r.impacts[0].t < T_CROSS
    gaps = [segment_distance(p[0], p[1], bead, bead) - BEAD_R for p in segments(whirl, r)]
    assert min(gaps) >= -1e-6
