"""Forward sensitivities through a switch of base chart (gac_sens_switch, gac_chart_convert_tangent): the derivative
of the switch map x_B = phi(x_A) against its finite differences, both ways; the saltation term of the switch
(f_B(phi(x)) - (d phi / dx) f_A(x)) dt* is 0; and the final state's sensitivities of runs of the gimbal-lock scene
that cross chart A's lock (onto chart B and back, ending on chart B, with an impact on chart B, starting on chart B;
DOP853, DOPRI5 and RK4) against central differences, the samples' too.  The C unit test (tests/c) checks the
derivative of the conversion at random states too.  Other events: tests/test_sim_sensitivities.py."""
from __future__ import annotations

import numpy as np
import pytest

from codegen.charts import Chart
from codegen.scene import load_scene
from runtime import simulate
from test_sim_sensitivities import central_differences

TIGHT = dict(method="dop853", rtol=1e-12, atol=1e-14)
DIRECTIONS = ["q0[theta_0]", "qd0[theta_-1]", "qd0[theta_1]", "q0[X2]", "g", "l_1", "e_x2_min"]
ELASTIC_BELOW_1 = {"e_x2_min": 0.9}        # (the scene's e = 1: a central difference along e needs room above it)


@pytest.fixture(scope="module")
def scene():
    return load_scene("gimbal-lock")


@pytest.fixture(scope="module")
def model(compiled, scene):
    return compiled(scene, specialise=True, chart_b=True, tangent=True)


def measure_a(scene, q):
    return Chart.of(scene.base_twists).measure(np.asarray(q)[..., 1])


def bases(model):
    """(chart A's gac_base *, chart B's)."""
    ffi, descriptor = model.ffi, model.c.model
    return ffi.addressof(descriptor, "base"), ffi.addressof(descriptor.chart_b[0], "base")


def convert(model, source, target, x, near):
    out = np.zeros_like(x)
    code = model.lib.gac_chart_convert(source, target, model.nq, model._ptr(x), model._ptr(near), model._ptr(out))
    assert code == model.lib.GAC_OK
    return out


def convert_tangent(model, source, target, x, y, S):
    """(d phi / dx) S, S (k x nx) direction-major."""
    S = np.ascontiguousarray(S, dtype=float).copy()
    code = model.lib.gac_chart_convert_tangent(source, target, model.nq, model._ptr(x), model._ptr(y), len(S),
                                               model._ptr(S))
    assert code == model.lib.GAC_OK
    return S


@pytest.fixture(scope="module")
def switch_states(model, scene):
    """States of the scene's run in chart A's coordinates where the loop switches (chi_A within [0.2, 0.7]), and
    random ones (angles and rates), each with chart A's measure above 0.1."""
    r = simulate(model, 0.7, t_eval=np.linspace(0.0, 0.7, 141), **TIGHT)
    mu = measure_a(scene, r.q)
    nq = model.nq
    picked = [np.concatenate([model.layout.reduce(q), model.layout.reduce(qd)])
              for q, qd, m in zip(r.q, r.qd, mu) if 0.2 <= m <= 0.7][::4]
    rng = np.random.default_rng(3)
    while len(picked) < 12:
        x = rng.normal(0.0, 1.5, 2 * nq)
        if measure_a(scene, x[:nq]) > 0.1:
            picked.append(x)
    return picked


def test_the_switch_maps_derivative_matches_its_finite_differences(model, switch_states):
    """d phi / dx (the base angles: E_B d theta_B = E_A d theta_A; their rates: E_B d theta_B' = dE_A theta_A' +
    E_A d theta_A' - dE_B theta_B') against central differences of gac_chart_convert, A -> B and B -> A, along every
    state component (step 1e-6: to ~1e-8)."""
    a, b = bases(model)
    nx, step = 2 * model.nq, 1e-6
    worst = 0.0
    for x_a in switch_states:
        x_b = convert(model, a, b, x_a, x_a[:model.nq])   # (near: ignored but for the angles' 2 pi shifts)
        for source, target, x in ((a, b, x_a), (b, a, x_b)):
            y = convert(model, source, target, x, (x_b if target == b else x_a)[:model.nq])
            D = convert_tangent(model, source, target, x, y, np.eye(nx)).T      # column i: along component i
            for i in range(nx):
                e = np.zeros(nx)
                e[i] = step
                plus = convert(model, source, target, x + e, y[:model.nq])
                minus = convert(model, source, target, x - e, y[:model.nq])
                fd = (plus - minus) / (2 * step)
                worst = max(worst, np.abs(fd - D[:, i]).max() / max(1.0, np.abs(fd).max()))
    assert worst < 1e-8


def test_the_switch_has_no_saltation_term(model, switch_states):
    """The two charts' fields are phi-related, f_B(phi(x)) = (d phi / dx) f_A(x) (the same motion in two
    coordinates), so the term (f_B - (d phi / dx) f_A) dt* of a switch at a state-dependent time vanishes."""
    a, b = bases(model)
    ffi, nq = model.ffi, model.nq
    p = model.parameters()
    u = np.zeros(1)
    for x_a in switch_states:
        x_b = convert(model, a, b, x_a, x_a[:nq])
        f_a, f_b = np.zeros(2 * nq), np.zeros(2 * nq)
        f_a[:nq], f_b[:nq] = x_a[nq:], x_b[nq:]
        model.c.model.forward_dynamics(model._ptr(x_a[:nq]), model._ptr(x_a[nq:]), model._ptr(u), model._ptr(p),
                                       model._ptr(f_a[nq:]))
        model.c.model.chart_b.forward_dynamics(model._ptr(x_b[:nq]), model._ptr(x_b[nq:]), model._ptr(u),
                                               model._ptr(p), model._ptr(f_b[nq:]))
        carried = convert_tangent(model, a, b, x_a, x_b, f_a[None])[0]
        assert np.abs(carried - f_b).max() <= 1e-10 * np.abs(f_b).max()
    assert ffi.NULL != model.c.model.chart_b.forward_dynamics_tangent   # chart B has its tangent kernels


# (name, t_end, charts, base angle theta_0 at the start or None, chart switches): through chart A's lock onto chart
# B and back; ending on chart B (S reported in chart A's coordinates); with charts = 0.35 the impact at 0.694 s
# falls on chart B (the next, at 0.725 s, on chart A again); starting on chart B (theta_0 0.1 from the lock: the seeds carried onto it) and switching back.
RUNS = [("onto B and back", 0.69, True, None, 2),
        ("ending on B", 0.6, True, None, 1),
        ("impact on B", 0.75, 0.35, None, 2),
        ("starting on B", 0.5, True, np.pi / 2 - 0.1, 2)]


@pytest.mark.parametrize("run", RUNS, ids=[r[0] for r in RUNS])
def test_sensitivities_through_the_switch_match_central_differences(model, scene, run):
    """The final state's sensitivities against central differences (step 1e-5: with impacts, the located impact
    times' noise, ~1e-12 s, makes a step of 1e-6 too short for 1e-6 of the column)."""
    name, t_end, charts, theta_0, switches = run
    q0, qd0 = np.array(scene.q0), np.array(scene.qd0)
    if theta_0 is not None:
        q0[1] = theta_0
    p = model.parameters(ELASTIC_BELOW_1)
    t = np.linspace(0.0, t_end, 201)
    r = simulate(model, t_end, t_eval=t, p=p, q0=q0, qd0=qd0, charts=charts, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and r.n_chart_switches == switches, r.message
    assert r.sensitivities.valid, r.sensitivity_message        # (a switch used to end them: GAC_SENS_CHART)
    assert r.sensitivities.n_impacts == len(r.impacts)
    if name == "impact on B":           # on B from chi_A < 0.35 until chi_A > 0.7, which comes after the first impact
        mu, first = measure_a(scene, r.q), r.impacts[0].t
        assert mu[0] > 0.35 and mu[(t > 0.2) & (t < first)].max() < 0.7 and len(r.impacts) == 2
    central_differences(model, t_end, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, step=1e-5, charts=charts,
                        **TIGHT)


@pytest.mark.parametrize("options", [dict(method="rk4", dt=1e-3), dict(method="dopri5", rtol=1e-11, atol=1e-13)],
                         ids=["rk4", "dopri5"])
def test_every_integrator_carries_them_through_the_switch(model, scene, options):
    """RK4 (whose switch is made at a step's start) and DOPRI5, onto chart B and back: against central differences
    of the same method's runs."""
    directions = ["q0[theta_0]", "qd0[theta_-1]", "g"]
    p = model.parameters()
    r = simulate(model, 0.69, p=p, sensitivities=directions, **options)
    assert r.success and r.n_chart_switches == 2 and r.sensitivities.valid, r.message
    central_differences(model, 0.69, p, np.array(scene.q0), np.array(scene.qd0), directions, r.sensitivities.matrix,
                        step=1e-5, **options)


def test_the_samples_sensitivities_are_in_chart_a_coordinates(model, scene):
    """S at each sample (chart A's coordinates, also those taken on chart B) against central differences of the
    samples, away from chart A's lock (where chart A's angles' derivatives grow like 1 / chi_A); the last is the
    final matrix."""
    t = np.linspace(0.0, 0.69, 70)
    direction = "qd0[theta_1]"
    r = simulate(model, 0.69, t_eval=t, sensitivities=[direction], sensitivities_at_samples=True, **TIGHT)
    assert r.sensitivities.valid and r.n_chart_switches == 2
    step, qd0 = 1e-6, np.array(scene.qd0)
    runs = []
    for h in (step, -step):
        qd = qd0.copy()
        qd[2] += h
        runs.append(simulate(model, 0.69, t_eval=t, qd0=qd, **TIGHT))
    free = list(model.layout.free)
    fd = (np.hstack([runs[0].q[:, free], runs[0].qd[:, free]])
          - np.hstack([runs[1].q[:, free], runs[1].qd[:, free]])) / (2 * step)
    S = r.sensitivities.at_samples[:, :, 0]
    away = measure_a(scene, r.q) > 0.05
    on_b = (measure_a(scene, r.q) < 0.6) & (t > 0.15) & (t < 0.62)      # (a stretch the loop integrates on B)
    assert away.sum() > 50 and (away & on_b).sum() > 20
    assert np.abs(S[away] - fd[away]).max() <= 1e-6 * max(10.0, np.abs(fd[away]).max())
    assert np.array_equal(S[-1], r.sensitivities.matrix[:, 0])
