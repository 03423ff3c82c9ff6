"""Two free chains tumbling in 3D in one box (codegen.combine, runtime/c/gac_switch.c): each turns its base, the
first through its chart's gimbal lock (t = 0.25 s), the second near its own (chi_A = 0.087 at t = 0.41 s), so the
run needs each chain's second base chart, switched on its own: the first chain on chart B while the second stays on
A (the model on mixed charts), then both on B.  The run reaches t_end with the energy balance closed and no link
through another, and before the chains first strike each other each moves as it does alone."""
import math
from dataclasses import replace

import numpy as np
import pytest

from codegen.scene import Chains, LineLink, load_scene
from runtime import load_model, simulate
from runtime.simulate import _loop_options, chart_measure

ACCURATE = dict(rtol=1e-12, atol=1e-14)
FIRST_STRIKE = 0.79       # s: the chains first strike each other at t = 0.792 s
SWITCH = 0.3              # the loop's chart_switch (simulate's default): chart B below it, back on A above twice it


def chains() -> Chains:
    """The gimbal-lock scene's chain as capsules (z_1 through the vertical at t = 0.25 s), and a 2-link capsule chain
    thrown at it from the right, spinning about all three axes."""
    lock = load_scene("gimbal-lock")
    walls = tuple(replace(w, points=()) for w in lock.walls)            # every point of each chain
    first = replace(lock, name="spin3d_c1", links=tuple(replace(link, radius=0.03) for link in lock.links),
                    walls=walls)
    second = replace(lock, name="spin3d_c2", links=(LineLink(0.4, 1.2, radius=0.04), LineLink(0.3, 1.0, radius=0.03)),
                     walls=walls, q0=(2.6, -0.4, 0.5, 1.0, 1.55, 1.1, 1.05), qd0=(2.0, -1.5, 1.0, 1.0, -2.8, 1.5, 0.1))
    return Chains(name="spin3d", chains=(first, second), link_restitution=0.9)


@pytest.fixture(scope="module")
def run():
    scene = chains()
    model = load_model(scene)
    return scene, model, simulate(model, 1.0, rtol=1e-10, atol=1e-12)


def _chi(scene, model, result) -> np.ndarray:
    """Each chain's chart A measure |cos theta_0| at the samples (n x 2; the samples are in the full layout)."""
    return np.abs(np.cos(result.q[:, [scene.state_offset(k) + 1 for k in (1, 2)]]))


def _charts_over_time(model, t_end: float, every: float = 0.002) -> list[tuple[float, int]]:
    """(t, sim.chart) every ``every`` s of a run (the C loop called directly): bit k - 1 of sim.chart set where chain
    k's base is on its chart B."""
    c, ffi = model.c, model.ffi
    opt = _loop_options(model, "dopri5", dict(rtol=1e-10, atol=1e-12), chart_switch=SWITCH)
    sim, record = c.new("sim"), c.new("impact_record")
    assert c.sim_init(sim, 0.0, model._ptr(model.q0), model._ptr(model.qd0), model._ptr(model.p), opt) == 0
    out, i_eval = [], ffi.new("int *", 0)
    for t in np.arange(every, t_end + every / 2, every):
        while sim.base.t < t:
            assert c.sim_advance(sim, float(t), ffi.NULL, 0, i_eval, ffi.NULL, record) > 0
        out.append((float(t), int(sim.base.chart)))
    return out


def test_the_model_has_a_chart_per_combination_of_the_chains_charts(run):
    scene, model, _ = run
    m, ffi, lib = model.c.model, model.ffi, model.lib
    assert m.nbase == 2 and [m.charts[j].theta0_index for j in range(2)] == [1, scene.chains[0].nq + 1]
    names = [ffi.string(m.chart_models[i].name).decode() for i in range(4)]
    assert names == ["spin3d", "spin3d_b1", "spin3d_b2", "spin3d_b3"] and m.chart_models[3] == m.chart_b
    assert lib.gac_model_check(m.chart_models[0]) == lib.GAC_OK             # the library's own descriptor
    q = model.q0.copy()                                      # the measure is the smaller of the two chains'
    q[1], q[scene.chains[0].nq + 1] = 1.2, 0.4
    assert chart_measure(model, q) == pytest.approx(math.cos(1.2), rel=1e-14)


def test_each_chain_switches_its_chart_on_its_own_and_the_run_reaches_t_end(run):
    scene, model, result = run
    assert result.status == 0 and result.t_final == pytest.approx(1.0), result.message
    chi = _chi(scene, model, result)
    assert chi[:, 0].min() < 1e-6 and chi[:, 1].min() < 0.1            # through the lock, and near it
    assert result.n_chart_switches >= 4
    charts = _charts_over_time(model, 0.5)
    seen = {mask for _, mask in charts}
    assert {0, 1, 3} <= seen, charts                        # chain 1 on B alone (mixed charts), then both on B
    for t, mask in charts:                                               # each chain on B only near its lock
        i = int(round(t * 1000))
        for k in (0, 1):
            assert chi[i, k] < 2 * SWITCH + 0.05 if mask >> k & 1 else chi[i, k] > SWITCH - 0.05, (t, mask)


@pytest.mark.parametrize("method, options", [("dop853", dict(rtol=1e-10, atol=1e-12)), ("rk4", dict(dt=1e-4))])
def test_the_other_methods_switch_the_same_way(run, method, options):
    """The same switches with DOP853 and with RK4's fixed steps (which switch at a step's start where the step would
    pass a lock)."""
    _, model, result = run
    other = simulate(model, 1.0, method=method, **options)
    assert other.status == 0 and other.n_chart_switches == result.n_chart_switches, other.message
    assert len(other.impacts) == len(result.impacts) and abs(other.energy_drift) < 1e-6


def test_the_energy_balance_closes_and_no_link_passes_through_another(run):
    scene, model, result = run
    assert abs(result.energy_drift) < 1e-9, result.energy_summary()
    across = [c for i in result.impacts for c in i.contacts if c.kind == "link" and c.links[0] <= 3 < c.links[1]]
    assert across, "the chains never struck each other"
    assert min(i.t for i in result.impacts if any(c.kind == "link" for c in i.contacts)) > FIRST_STRIKE
    first = len(model.layout.contacts)                                   # the link pairs after the kernel contacts
    worst = min(float(model.contact_gaps(model.layout.reduce(q))[first:].min()) for q in result.q)
    assert worst > -1e-9


@pytest.mark.slow            # each chain's own model with its chart B besides the combined one
def test_before_the_first_strike_each_chain_moves_as_alone(run):
    """The same motion, compared through each chain's points and their velocities (chart-free; chart A's rates are
    unbounded at its lock, so the velocities where a chain's chi_A < 1e-3 are left out)."""
    scene, model, _ = run
    result = simulate(model, FIRST_STRIKE, **ACCURATE)
    chi = _chi(scene, model, result)
    reduce = model.layout.reduce
    points = np.array([model.contact_points(reduce(q)) for q in result.q])
    velocities = np.array([model.contact_velocities(reduce(q), reduce(qd)) for q, qd in zip(result.q, result.qd)])
    start = 0
    for k, chain in enumerate(scene.chains, start=1):
        own = load_model(chain)
        alone = simulate(own, FIRST_STRIKE, **ACCURATE)
        assert alone.status == 0 and len(alone.t) == len(result.t)
        block = slice(start, start + chain.npoint)
        start += chain.npoint
        assert len([i for i in result.impacts if all(c.point in range(block.start + 1, block.stop + 1)
                                                       for c in i.contacts)]) == len(alone.impacts) > 0
        reduce = own.layout.reduce
        own_points = np.array([own.contact_points(reduce(q)) for q in alone.q])
        own_velocities = np.array([own.contact_velocities(reduce(q), reduce(qd)) for q, qd in zip(alone.q, alone.qd)])
        away = chi[:, k - 1] > 1e-3
        assert np.abs(points[:, block] - own_points).max() < 1e-9
        assert np.abs(velocities[away][:, block] - own_velocities[away]).max() < 2e-8


def test_without_charts_the_run_stops_at_the_first_chains_lock(run):
    scene, model, _ = run
    stopped = simulate(model, 1.0, charts=False, rtol=1e-10, atol=1e-12)
    assert stopped.status == -1 and "gimbal lock" in stopped.message, stopped.message
    chi = np.abs(np.cos(stopped.q_final[[1, scene.chains[0].nq + 1]]))
    assert 0.24 < stopped.t_final < 0.25 and chi[0] < 1e-2 < 0.5 < chi[1]   # at chain 1's lock (theta_0 = pi/2)
