"""Sticking at resting contacts on rough walls (simulate(stick=True), the default): a pushed rod below the Coulomb
limit stays exactly in place (with stick=False it creeps at the regularised rate) and above it slides at
(F - c_f m g) / m from the start; a sliding rod stops at x0 + v0^2 / (2 c_f g) and stays stuck there; what a resting
chain costs with sticking against the regularisation and the smooth floor; the energy balance of a 3D chain with
several points on rough walls."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import load_scene, scene_from_dict
from runtime import simulate
from runtime.inputs import InputSchedule
from tests.test_sim_friction import G, rod
from conftest import quick_model


def transitions(result):
    """The run's stick and slip events as (kind, t, contact), after checking that result.n_sticks and result.n_slips
    count exactly them."""
    events = [(e.kind, e.t, e.label) for e in result.contact_events if e.kind in ("stick", "slip")]
    assert result.n_sticks == sum(kind == "stick" for kind, _, _ in events)
    assert result.n_slips == sum(kind == "slip" for kind, _, _ in events)
    return events


@pytest.mark.parametrize("force", [2.0, 4.8])
def test_a_pushed_rod_below_the_limit_stays_stuck(force):
    """F below c_f m g = 4.905 N: stuck, X1 exactly constant (no creep); the regularisation alone creeps at
    v_s F / (c_f m g)."""
    c_f, vs = 0.5, 1e-4
    scene = rod(c_f, (0.0, 0.0), inputs=("X1",), friction_velocity=vs)
    model = quick_model(scene)
    t = np.linspace(0.0, 0.5, 6)
    n = scene.n
    stuck = simulate(model, 0.5, u=[force], rtol=1e-10, atol=1e-12, t_eval=t)
    assert stuck.success, stuck.message
    assert np.abs(stuck.q[:, n + 2] - 1.0).max() < 1e-12 and np.abs(stuck.qd[:, n + 2]).max() < 1e-12
    assert stuck.n_sticks == 2 and stuck.n_slips == 0            # both ends stuck from the start, never slipping
    assert transitions(stuck) == [("stick", 0.0, "O1/x2_min"), ("stick", 0.0, "O2/x2_min")]
    assert stuck.loss_friction == 0.0 and abs(stuck.energy_residual) < 1e-12
    creep = simulate(model, 0.5, u=[force], rtol=1e-10, atol=1e-12, t_eval=[0.5], stick=False)
    assert creep.success and creep.n_sticks == 0
    assert creep.qd[-1, n + 2] == pytest.approx(vs * force / (c_f * G), rel=1e-6)
    assert creep.n_rhs > 100 * stuck.n_rhs                        # the stiff viscous regime it replaces


def test_a_pushed_rod_above_the_limit_slides_at_the_coulomb_rate():
    """F = 7 N > c_f m g: the stuck ends slip at once, along F, and the rod accelerates at (F - c_f m g) / m from the
    start (the slip begins against the full Coulomb force, not through the viscous regime)."""
    c_f, force = 0.5, 7.0
    scene = rod(c_f, (0.0, 0.0), inputs=("X1",), friction_velocity=1e-4)
    model = quick_model(scene)
    t = np.array([0.1, 0.3, 0.5])
    result = simulate(model, 0.5, u=[force], rtol=1e-10, atol=1e-12, t_eval=t)
    assert result.success, result.message
    a = force - c_f * G
    n = scene.n
    assert np.abs(result.qd[:, n + 2] - a * t).max() < 1e-9
    assert np.abs(result.q[:, n + 2] - (1.0 + 0.5 * a * t * t)).max() < 1e-9
    assert result.n_slips == 2 and result.n_sticks == 2
    assert sorted((kind, t) for kind, t, _ in transitions(result)) == [("slip", 0.0)] * 2 + [("stick", 0.0)] * 2
    assert result.loss_friction == pytest.approx(c_f * G * 0.5 * a * 0.25, rel=1e-9)      # c_f m g x distance
    assert abs(result.energy_residual) < 1e-12 * result.work_input


@pytest.mark.parametrize("specialise", [True, False])
def test_a_sliding_rod_stops_and_stays_stuck(specialise):
    """v0 = 2 m/s, c_f = 0.5: x(t) = x0 + v0 t - c_f g t^2 / 2 until it stops at x0 + v0^2 / (2 c_f g) (to within
    the v_s^2 / (2 c_f g) = 1e-9 m it would slide below v_s), then stuck: not a nanometre of creep afterwards; the
    friction took 1/2 m v0^2."""
    c_f, v0 = 0.5, 2.0
    scene = rod(c_f, (v0, 0.0))
    model = quick_model(scene, specialise=specialise)
    t_stop = v0 / (c_f * G)
    t = np.array([0.2, 0.45, 0.6, 1.0])
    result = simulate(model, 1.0, t_eval=t, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    n = scene.n
    x, stop = result.q[:, n + 2], 1.0 + v0 * v0 / (2 * c_f * G)
    assert x[0] == pytest.approx(1.0 + v0 * 0.2 - 0.5 * c_f * G * 0.04, abs=1e-9)
    assert t[1] > t_stop and abs(x[1] - stop) < 2e-9
    assert np.abs(x[1:] - x[1]).max() < 1e-13 and np.abs(result.qd[1:]).max() < 1e-12     # stuck: no creep
    assert result.n_sticks == 2 and result.n_slips == 0
    assert result.loss_friction == pytest.approx(0.5 * v0 * v0, rel=1e-9)
    assert abs(result.energy_residual) < 1e-9
    assert result.options["stick"] is True
    # the stick events: both ends at one step's end, once the rod is slower than v_s (within v_s / (c_f g) of the
    # stop) or has passed through zero speed
    events = transitions(result)
    assert [(kind, label) for kind, _, label in events] == [("stick", "O1/x2_min"), ("stick", "O2/x2_min")]
    assert events[0][1] == events[1][1] and abs(events[0][1] - t_stop) <= 1e-4 / (c_f * G)
    exported = result.to_json()["contact_events"]                 # what --json writes
    assert [(e["kind"], e["t"]) for e in exported[2:]] == [(kind, t) for kind, t, _ in events]


def test_a_rod_pushed_past_the_limit_slips_where_the_push_reaches_c_f_m_g():
    """A stuck rod pushed along X1 by a force growing linearly, F = k t (a linear schedule): the ends share the push
    and each slips where its share reaches c_f times its share of the weight, both at t = c_f m g / k, located as
    events to the loop's event tolerance; the slips are recorded as 'slip' events, each counted once."""
    c_f, k = 0.5, 10.0
    model = quick_model(rod(c_f, (0.0, 0.0), inputs=("X1",), friction_velocity=1e-4))
    push = InputSchedule([0.0, 1.0], [[0.0], [k]], mode="linear")
    result = simulate(model, 0.8, u=push, rtol=1e-10, atol=1e-12, t_eval=[])
    assert result.success, result.message
    events = transitions(result)
    assert [kind for kind, _, _ in events] == ["stick", "stick", "slip", "slip"]
    assert sorted(label for kind, _, label in events if kind == "slip") == ["O1/x2_min", "O2/x2_min"]
    t_slip = c_f * G / k
    for _, t, _ in events[2:]:
        assert abs(t - t_slip) < 1e-12
    assert result.qd_final[model.scene.n + 2] > 0.0                    # sliding along the push since


def rough_variants(friction):
    """The shipped rough-floor scene with the floor's c_f = friction, and the same scene with a smooth floor."""
    scene = load_scene("rough-floor")
    walls = tuple(dataclasses.replace(w, friction=friction if w.friction > 0 else 0.0) for w in scene.walls)
    rough = dataclasses.replace(scene, name=f"{scene.name}_cf{friction:g}".replace(".", "_"), walls=walls)
    smooth = dataclasses.replace(scene, name=f"{scene.name}_smooth",
                                 walls=tuple(dataclasses.replace(w, friction=0.0) for w in scene.walls))
    return rough, smooth


@pytest.mark.parametrize("friction", [0.6, 5.0])
def test_a_resting_chain_costs_little_more_than_on_a_smooth_floor(friction):
    """rough-floor (a 4-link chain thrown onto the floor, 4 s; it comes to rest near 1.3 s): with sticking the run
    costs a few times the smooth floor's right-hand sides, far fewer than the regularisation alone, whose rest is a
    stiff viscous regime of time constant v_s / (c_f g)."""
    rough, smooth = rough_variants(friction)
    runs = {"smooth": simulate(quick_model(smooth), 4.0, t_eval=[4.0])}
    rough_model = quick_model(rough)
    runs["stick"] = simulate(rough_model, 4.0, t_eval=[4.0])
    runs["regularised"] = simulate(rough_model, 4.0, t_eval=[4.0], stick=False)
    for name, result in runs.items():
        assert result.success, f"{name}: {result.message}"
    stick, regularised = runs["stick"], runs["regularised"]
    assert stick.n_rhs < 10 * runs["smooth"].n_rhs
    assert stick.n_rhs < regularised.n_rhs / 4
    assert len(stick.resting_final) == 5 and stick.n_sticks >= 5
    transitions(stick)
    assert np.abs(stick.qd_final).max() < 1e-9                     # at rest, stuck
    assert abs(stick.energy_residual) < 1e-6 and stick.loss_friction >= 0.0
    assert not any("friction_velocity" in w for w in stick.warnings)


def test_the_energy_balance_closes_in_3d_with_several_points_on_rough_walls():
    """A 3-link chain thrown onto a rough floor in 3D (the general model, both tangential axes; side walls rough
    too): impacts, sliding, sticking and slipping; the balance E - E0 + losses closes to the tolerance, friction's
    loss >= 0, and the run ends at rest with three points stuck, far cheaper than the regularisation alone."""
    data = {"name": "rough_drop3", "gravity": G, "links": [{"length": 1.0, "mu": 1.0, "count": 3}],
            "walls": {"x2_min": 0.0, "x1_min": -10.0, "x1_max": 10.0}, "restitution": 0.3, "friction": 0.6,
            "initial": {"q": [-math.pi / 2, 0.0, -1.2, 0.5, 0.4, 0.0, 1.0, 0.0],
                        "qd": [0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.7]}}
    model = quick_model(scene_from_dict(data), specialise=False, chart_b=True)      # it passes the gimbal lock
    result = simulate(model, 3.0, rtol=1e-10, atol=1e-12, t_eval=[3.0])
    assert result.success, result.message
    assert result.impacts and result.n_sticks >= 3
    transitions(result)
    assert result.loss_friction > 0.0
    assert abs(result.energy_drift) < 1e-8
    assert len(result.resting_final) == 3 and np.abs(result.qd_final).max() < 1e-9
    assert result.n_rhs < 20_000                       # the regularisation alone: about 1e5 before it stops


def test_the_option_is_checked():
    model = quick_model(rod(0.5, (0.0, 0.0)))
    with pytest.raises(ValueError, match="stick: must be True or False"):
        simulate(model, 0.1, stick=2)
    assert simulate(model, 0.1, stick=False).options["stick"] is False


def test_a_leaning_rod_slips_where_the_friction_it_needs_reaches_c_f_N():
    """A uniform rod (1 m, 1 kg) leaning 20 degrees from the vertical with its lower end stuck on a rough floor
    (c_f = 0.5), released from rest: it pivots about that end, phi_dd = 3 g sin(phi) / 2L, phi_d^2 = 3 g (cos phi0 -
    cos phi) / L, and the floor must supply F = m a_x and N = m (g + a_y) of its centre's acceleration; it slips
    where |F| = c_f N (closed form of the pivot phase, the time by quadrature).  The loop's slip event falls within
    1e-7 s of that time."""
    from scipy.integrate import quad
    from scipy.optimize import brentq
    g, length, c_f, phi0 = 9.81, 1.0, 0.5, math.radians(20.0)

    def floor_force(phi):                     # (F, N) per unit mass in the pivot phase
        phi_dd = 1.5 * g / length * math.sin(phi)
        phi_d2 = 3.0 * g / length * (math.cos(phi0) - math.cos(phi))
        a_x = 0.5 * length * (phi_dd * math.cos(phi) - phi_d2 * math.sin(phi))
        a_y = -0.5 * length * (phi_dd * math.sin(phi) + phi_d2 * math.cos(phi))
        return a_x, g + a_y

    phi_slip = brentq(lambda phi: abs(floor_force(phi)[0]) - c_f * floor_force(phi)[1], phi0 + 1e-6, math.radians(70))
    t_slip = quad(lambda phi: 1.0 / math.sqrt(3.0 * g / length * (math.cos(phi0) - math.cos(phi))), phi0, phi_slip)[0]
    assert 0.44 < t_slip < 0.45 and floor_force(phi_slip)[1] > 0          # it slips while pressing on the floor
    scene = scene_from_dict({"name": "leaning_rod", "gravity": g,
                             "links": [{"length": length, "mu": 1.0 / length, "J": [0.0, 0.0, 0.0]}],
                             "walls": {"x2_min": 0.0}, "restitution": 0.0, "friction": c_f,
                             "initial": {"q": [-math.pi / 2, 0.0, -phi0, 0.0, 0.0, 0.0]}})
    model = quick_model(scene)
    before = simulate(model, t_slip - 1e-7, t_eval=[], rtol=1e-11, atol=1e-13)
    after = simulate(model, t_slip + 1e-7, t_eval=[], rtol=1e-11, atol=1e-13)
    assert before.success and before.n_sticks == 1 and before.n_slips == 0
    assert after.success and after.n_slips == 1
    slip = [t for kind, t, label in transitions(after) if kind == "slip"]
    assert len(slip) == 1 and abs(slip[0] - t_slip) < 1e-7
