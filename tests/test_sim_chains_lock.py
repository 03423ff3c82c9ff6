"""Several chains and the base chart (codegen.combine): one chain turns its base in 3D, the other is planar.  The
model has that chain's chart B (NAME_model_b, one base as a one-chain model has), so a run passes the chain's gimbal
lock as the chain does alone; without it (charts=False) a run that reaches the lock stops there with the loop's
gimbal-lock status, as the chain's own one-chart model does."""
import math
from dataclasses import replace

import numpy as np
import pytest

from codegen.scene import Chains
from codegen.scene import LineLink, Scene, load_scene
from runtime import load_model, simulate

ACCURATE = dict(rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def scenes():
    turning = load_scene("gimbal-lock")                       # theta_0 reaches pi/2 at t = 0.25 s
    walls = tuple(replace(w, points=()) for w in turning.walls)          # every point of each chain
    planar = Scene(name="lock_c2", links=(LineLink(0.3, 1.0),), gravity=turning.gravity, walls=walls,
                   q0=(-math.pi / 2, 0.0, 0.2, 1.7, 1.5, 1.0), qd0=(0.0, 0.0, 1.0, 0.0, 0.0, 0.0))
    return turning, Chains(name="lock", chains=(replace(turning, name="lock_c1"), planar))


def test_a_run_passes_the_turning_chains_lock_on_its_chart_b_as_the_chain_alone(scenes):
    turning, chains = scenes
    model = load_model(chains)
    m, ffi = model.c.model, model.ffi
    assert m.chart.theta0_index == 1 and m.nbase == 0 and ffi.string(m.chart_b.name) == b"lock_b"
    run = simulate(model, 0.6, max_steps=20000, **ACCURATE)
    assert run.status == 0 and run.n_chart_switches >= 1, run.message
    own_model = load_model(turning)
    own = simulate(own_model, 0.6, max_steps=20000, **ACCURATE)
    assert own.status == 0 and len(own.t) == len(run.t)
    points = np.array([model.contact_points(model.layout.reduce(q))[:turning.npoint] for q in run.q])
    alone = np.array([own_model.contact_points(own_model.layout.reduce(q)) for q in own.q])
    assert np.abs(points - alone).max() < 1e-7                       # the chain moves as alone (chart-free)


def test_without_charts_a_run_that_reaches_the_lock_stops_with_the_gimbal_status(scenes):
    turning, chains = scenes
    model = load_model(chains)
    run = simulate(model, 0.6, max_steps=20000, charts=False, **ACCURATE)
    assert run.status == -1 and "gimbal lock" in run.message, run.message
    own = simulate(load_model(turning, chart_b=False), 0.6, max_steps=20000, **ACCURATE)
    assert own.status == -1 and run.t_final == pytest.approx(own.t_final, abs=2e-3)   # (each at its own step's end)
    assert abs(math.cos(run.q_final[1])) < 1e-2                      # chain 1's theta_0 at pi/2: its chart's lock
    k = min(len(run.t), len(own.t))                                  # the same samples: the chain moves as alone
    assert np.allclose(run.q[:k, :turning.nq], own.q[:k], atol=1e-7)
