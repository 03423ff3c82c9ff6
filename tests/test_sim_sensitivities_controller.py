"""Sensitivities through state feedback (a controller with its Jacobian: runtime.inputs.Controller,
gac_sim_set_controller_jacobian): a planar 2-link chain falling onto a floor, two formulations of one dynamics --
joint 2's spring and damper (Joint(K, rest, C)) against the chain without them driven on theta_2 by the controller
u = -K (theta_2 - rest) - C theta_2' -- give the same trajectories and the same sensitivities, bouncing, landing and
resting, and on a rough floor through stick, slip and release; a nonlinear controller (of theta_2, theta_1, X1' and t)
against central finite differences of whole runs, on the rough floor too; a controller of a base angle through
switches of base chart; and the verdict and the errors without a usable Jacobian."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import Joint, scene_from_dict
from conftest import perturbed_start
from runtime import simulate
from runtime.inputs import Controller, pd

TIGHT = dict(rtol=1e-12, atol=1e-14)
K, REST, C = 8.0, 0.4, 0.3                       # joint 2: N m/rad, rad, N m s/rad
DIRECTIONS = ["q0[theta_1]", "q0[theta_2]", "qd0[X1]", "qd0[theta_2]", "e_x2_min", "g"]


def chain(name: str, friction: float = 0.0):
    """Two line links (1 m and 0.8 m) in the X1-X2 plane above the floor x2_min = 0, turning as they fall."""
    return scene_from_dict({
        "name": name, "gravity": 9.81, "restitution": 0.7, "friction": friction, "walls": {"x2_min": 0.0},
        "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}, {"length": 0.8, "mu": 1.2, "J": [0.0, 0.0, 0.0]}],
        "initial": {"q": [-math.pi / 2, 0.0, 0.3, 0.9, 0.0, 1.2, 0.0], "qd": [0.0, 0.0, 1.0, -2.0, 0.5, 0.0, 0.0]}})


def pair(compiled, friction: float = 0.0):
    """(the chain with joint 2's spring and damper, the chain driven on theta_2), specialised (planar, nq = 4)."""
    suffix = "_rough" if friction else ""
    spring = dataclasses.replace(chain("ctrl_spring" + suffix, friction), joints=(Joint(K, REST, C),))
    driven = dataclasses.replace(chain("ctrl_driven" + suffix, friction), inputs=("theta_2",))
    return (compiled(spring, specialise=True, tangent=True), compiled(driven, specialise=True, tangent=True))


@pytest.fixture(scope="module")
def models(compiled):
    return pair(compiled)


@pytest.fixture(scope="module")
def rough(compiled):
    return pair(compiled, friction=0.5)


def theta_index(model, name: str) -> int:
    return model.scene.full_coordinate_names().index(name)


def spring_controller(model) -> Controller:
    """The spring and damper as a controller, written out (pd() gives the same)."""
    i = theta_index(model, "theta_2")

    def jacobian(t, q, qd):
        du_dq, du_dqd = np.zeros((1, len(q))), np.zeros((1, len(q)))
        du_dq[0, i], du_dqd[0, i] = -K, -C
        return du_dq, du_dqd

    return Controller(lambda t, q, qd: [-K * (q[i] - REST) - C * qd[i]], jacobian)


def same(a, b, tol):
    return np.abs(np.asarray(a) - b).max() <= tol * max(np.abs(b).max(), 1e-300)


@pytest.mark.parametrize("e,t_end,events", [(0.7, 0.92, ()), (0.0, 0.69, ("rest", "release"))])
@pytest.mark.parametrize("helper", [False, True])
def test_a_spring_and_its_controller_give_the_same_sensitivities(models, e, t_end, events, helper):
    """Bouncing (5 impacts), or landing with e = 0 (3 landings, resting contacts held in flight, a release; still
    moving at t_end): the two formulations agree along the initial state, the restitution and g, and so do the
    events' times' derivatives."""
    spring, driven = models
    u = pd(driven, kp=K, kd=C, target=REST) if helper else spring_controller(driven)
    a = simulate(spring, t_end, p={"e_x2_min": e}, sensitivities=DIRECTIONS, **TIGHT)
    b = simulate(driven, t_end, p={"e_x2_min": e}, u=u, sensitivities=DIRECTIONS, **TIGHT)
    assert a.success and b.success and len(a.impacts) == len(b.impacts) >= 3
    assert set(events) <= {event.kind for event in a.contact_events}
    assert same(b.q, a.q, 1e-10) and same(b.qd, a.qd, 1e-10)
    assert a.sensitivities.valid and b.sensitivities.valid, b.sensitivity_message
    assert b.sensitivities.n_impacts == a.sensitivities.n_impacts
    assert same(b.sensitivities.matrix, a.sensitivities.matrix, 1e-8)
    for x, y in zip(a.contact_events, b.contact_events):             # the events' times' derivatives too
        assert x.kind == y.kind and same(list(y.dt_dp.values()), np.array(list(x.dt_dp.values())), 1e-8)


@pytest.mark.parametrize("start", [(0.6, -0.8, 0.5), (0.6, -0.8, 2.0)])
def test_on_a_rough_floor_through_stick_slip_and_release(rough, start):
    """Lying on a rough floor (friction 0.5) and pushed along it: the points stick, slip, leave and land again; where
    an event the loop does not differentiate (a slow slide at an impact) ends the sensitivities it ends both runs' at
    the same time; at every sample before it (all of them where none does) they agree, and so do the slip and release
    times' derivatives."""
    spring, driven = rough
    theta_1, theta_2, speed = start
    q0 = [-math.pi / 2, 0.0, theta_1, theta_2, 0.0, 0.0, 0.0]
    qd0 = [0.0, 0.0, 0.0, 0.0, speed, 0.0, 0.0]
    t = np.linspace(0.0, 1.5, 751)
    run = dict(t_eval=t, q0=q0, qd0=qd0, sensitivities=DIRECTIONS[:4] + ["g", "friction_x2_min"],
               sensitivities_at_samples=True, **TIGHT)
    a = simulate(spring, 1.5, **run)
    b = simulate(driven, 1.5, u=spring_controller(driven), **run)
    assert same(b.q, a.q, 1e-10)
    assert b.sensitivities.code == a.sensitivities.code != 8   # (not the controller's)
    if a.sensitivities.valid:
        end = math.inf
    else:
        end = a.sensitivities.t_event
        assert b.sensitivities.t_event == pytest.approx(end, abs=1e-12)
    kinds = {event.kind for event in a.contact_events if event.t < end}
    assert {"stick", "slip", "release"} <= kinds
    before = t < end
    assert before.sum() > 100 and not np.isnan(b.sensitivities.at_samples[before]).any()
    assert same(b.sensitivities.at_samples[before], a.sensitivities.at_samples[before], 1e-8)
    for x, y in zip(a.contact_events, b.contact_events):             # the events' times' derivatives
        if x.t < end and x.kind in ("slip", "release"):
            assert x.kind == y.kind and same(list(y.dt_dp.values()), np.array(list(x.dt_dp.values())), 1e-8)


KN, CN, KX, W = 6.0, 0.05, 0.5, 0.3


def nonlinear(model) -> Controller:
    """u = -KN sin(theta_2 - rest) - CN theta_2'^3 + KX cos(theta_1) X1' + W sin(3 t), with its Jacobian."""
    i1, i2, ix = (theta_index(model, name) for name in ("theta_1", "theta_2", "X1"))

    def function(t, q, qd):
        return [-KN * math.sin(q[i2] - REST) - CN * qd[i2] ** 3 + KX * math.cos(q[i1]) * qd[ix] + W * math.sin(3 * t)]

    def jacobian(t, q, qd):
        du_dq, du_dqd = np.zeros((1, len(q))), np.zeros((1, len(q)))
        du_dq[0, i2] = -KN * math.cos(q[i2] - REST)
        du_dq[0, i1] = -KX * math.sin(q[i1]) * qd[ix]
        du_dqd[0, i2] = -3 * CN * qd[i2] ** 2
        du_dqd[0, ix] = KX * math.cos(q[i1])
        return du_dq, du_dqd

    return Controller(function, jacobian)


@pytest.mark.parametrize("e,t_end,directions", [(0.7, 0.92, DIRECTIONS), (0.0, 0.69, DIRECTIONS[:4] + ["g"])])
def test_a_nonlinear_controller_matches_central_differences(models, e, t_end, directions):
    """Bouncing (13 impacts), or landing and resting with a release (whose rate takes the controller's explicit
    d/dt): each column against a central difference of the final state, and the release time's derivative against
    that of the release time, the perturbed runs meeting the same impacts and contact events."""
    driven = models[1]
    u = nonlinear(driven)
    p = driven.parameters({"e_x2_min": e})
    q0, qd0 = np.array(driven.scene.q0, dtype=float), np.array(driven.scene.qd0, dtype=float)
    nominal = simulate(driven, t_end, p=p, u=u, sensitivities=directions, **TIGHT)
    assert nominal.sensitivities.valid, nominal.sensitivity_message
    sequence = [tuple(c.label for c in i.contacts) for i in nominal.impacts]
    kinds = [event.kind for event in nominal.contact_events]
    assert len(sequence) >= 4 and (e > 0 or "release" in kinds)

    def final(h, direction):
        p1, q1, qd1 = perturbed_start(driven, direction, h, p, q0, qd0)
        run = simulate(driven, t_end, p=p1, q0=q1, qd0=qd1, u=u.function, **TIGHT)
        assert [tuple(c.label for c in i.contacts) for i in run.impacts] == sequence, direction
        assert [event.kind for event in run.contact_events] == kinds, direction
        times = [event.t for event in run.contact_events if event.kind == "release"]
        return np.concatenate([driven.layout.reduce(run.q_final), driven.layout.reduce(run.qd_final), times])

    step = 1e-6
    releases = [event for event in nominal.contact_events if event.kind == "release"]
    nx = 2 * driven.nq
    for j, direction in enumerate(directions):
        fd = (final(step, direction) - final(-step, direction)) / (2 * step)
        column = nominal.sensitivities.matrix[:, j]
        assert np.abs(fd[:nx] - column).max() <= 1e-6 * max(10.0, np.abs(fd[:nx]).max()), direction
        for event, value in zip(releases, fd[nx:]):
            assert event.dt_dp[direction] == pytest.approx(value, rel=1e-6, abs=1e-7), direction


def test_a_nonlinear_controller_through_stick_and_slip_matches_central_differences(rough):
    """On the rough floor the point lands stuck and slips (the slip's event rate takes the controller's explicit d/dt:
    without it dt_slip is off by ~2 %): the final state and the slip time against central differences (step 1e-5:
    below it the stick at a step's end makes the difference noisy)."""
    driven = rough[1]
    u = nonlinear(driven)
    directions = ["q0[theta_1]", "q0[theta_2]", "qd0[X1]", "g", "friction_x2_min"]
    q0 = np.array([-math.pi / 2, 0.0, 0.6, -0.8, 0.0, 0.0, 0.0])
    qd0 = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0])
    t_end, p = 0.5, driven.p.copy()
    nominal = simulate(driven, t_end, p=p, q0=q0, qd0=qd0, u=u, sensitivities=directions, **TIGHT)
    assert nominal.sensitivities.valid, nominal.sensitivity_message
    kinds = [event.kind for event in nominal.contact_events]
    assert kinds == ["rest", "stick", "slip"]
    slip = nominal.contact_events[2]

    def final(h, direction):
        p1, q1, qd1 = perturbed_start(driven, direction, h, p, q0, qd0)
        run = simulate(driven, t_end, p=p1, q0=q1, qd0=qd1, u=u.function, **TIGHT)
        assert [event.kind for event in run.contact_events] == kinds, direction
        return np.concatenate([driven.layout.reduce(run.q_final), driven.layout.reduce(run.qd_final),
                               [run.contact_events[2].t]])

    step, nx = 1e-5, 2 * driven.nq
    for j, direction in enumerate(directions):
        fd = (final(step, direction) - final(-step, direction)) / (2 * step)
        column = nominal.sensitivities.matrix[:, j]
        assert np.abs(fd[:nx] - column).max() <= 1e-6 * max(10.0, np.abs(fd[:nx]).max()), direction
        assert slip.dt_dp[direction] == pytest.approx(fd[nx], rel=1e-4, abs=1e-6), direction


def test_a_controller_of_the_base_angles_through_chart_switches(compiled):
    """The gimbal-lock scene (a free 2-link chain crossing chart A's lock, onto chart B and back) driven on theta_2 by
    a controller of chart A's base angles and rates: on chart B the directions are carried to chart A's coordinates
    before the controller's Jacobian takes them.  Against central differences (step 1e-5, as the charts' own test)."""
    from test_sim_sensitivities import central_differences
    from codegen.scene import load_scene
    scene = load_scene("gimbal-lock")
    model = compiled(dataclasses.replace(scene, name="ctrl_gimbal", inputs=("theta_2",)), specialise=True,
                     chart_b=True, tangent=True)
    full = model.scene.full_coordinate_names()
    i0, i2 = full.index("theta_0"), full.index("theta_2")

    def function(t, q, qd):          # (of theta_0 alone among the base angles: theta_-1's and theta_1's rates are
        return [0.8 * math.sin(q[i0]) * qd[i0] + 1.5 * math.cos(q[i0]) - 2.0 * (q[i2] - 0.5)]   # unbounded at the lock)

    def jacobian(t, q, qd):
        du_dq, du_dqd = np.zeros((1, len(q))), np.zeros((1, len(q)))
        du_dq[0, i0] = 0.8 * math.cos(q[i0]) * qd[i0] - 1.5 * math.sin(q[i0])
        du_dq[0, i2], du_dqd[0, i0] = -2.0, 0.8 * math.sin(q[i0])
        return du_dq, du_dqd

    directions = ["q0[theta_0]", "qd0[theta_-1]", "qd0[theta_1]", "g"]
    options = dict(method="dop853", rtol=1e-12, atol=1e-14)
    p = model.parameters({"e_x2_min": 0.9})
    r = simulate(model, 0.69, p=p, u=Controller(function, jacobian), sensitivities=directions, **options)
    assert r.success and r.n_chart_switches >= 1 and r.sensitivities.valid, (r.message, r.sensitivity_message)
    central_differences(model, 0.69, p, np.array(scene.q0), np.array(scene.qd0), directions, r.sensitivities.matrix,
                        step=1e-5, u=function, **options)


def test_a_controller_without_its_jacobian_ends_them(models):
    """A plain function, or a Controller without a Jacobian: the verdict GAC_SENS_CONTROLLER at the start, the run
    itself unchanged."""
    driven = models[1]
    u = spring_controller(driven)
    with_jacobian = simulate(driven, 0.92, u=u, sensitivities=DIRECTIONS, **TIGHT)
    for plain in (u.function, Controller(u.function)):
        r = simulate(driven, 0.92, u=plain, sensitivities=DIRECTIONS, **TIGHT)
        assert r.sensitivities.code == 8 and r.sensitivities.t_event == 0.0
        assert r.sensitivities.status == "inputs from a controller (they may depend on the state)"
        assert np.isnan(r.sensitivities.matrix).all()
        assert np.array_equal(r.q, with_jacobian.q)


def test_the_c_setter_wants_a_controller_first(models):
    driven = models[1]
    c, lib = driven.c, driven.lib
    sim = c.new("sim")
    assert c.sim_init(sim, 0.0, driven._ptr(driven.q0), driven._ptr(driven.qd0), driven.ffi.NULL, driven.ffi.NULL) == 0
    from runtime.inputs import _python_controller_jacobian
    _python_controller_jacobian(driven)
    assert c.sim_set_controller_jacobian(sim, c.python_controller_jacobian) == lib.GAC_ERR_BAD_OPTION
    assert c.sim_set_controller_jacobian(sim, driven.ffi.NULL) == lib.GAC_OK
    assert c.sim_set_controller_jacobian(driven.ffi.NULL, driven.ffi.NULL) == lib.GAC_ERR_NULL_ARGUMENT


def bad(du_dq=None, du_dqd=None, pair=True):
    def jacobian(t, q, qd):
        a = np.zeros((1, len(q))) if du_dq is None else du_dq
        b = np.zeros((1, len(q))) if du_dqd is None else du_dqd
        return (a, b) if pair else a
    return jacobian


@pytest.mark.parametrize("jacobian,message", [
    (bad(du_dq=np.zeros((1, 4))), r"u.jacobian: at t = 0 s: du/dq has shape \(1, 4\); expected \(1, 7\): a row per "
                                  r"input, a column per coordinate of the full layout"),
    (bad(du_dqd=np.zeros((2, 7))), r"u.jacobian: at t = 0 s: du/dqd has shape \(2, 7\); expected \(1, 7\)"),
    (bad(du_dq=np.full((1, 7), np.nan)), r"u.jacobian: at t = 0 s: du/dq has a value that is not finite"),
    (bad(pair=False), r"u.jacobian: at t = 0 s: expected a pair \(du/dq, du/dqd\), got ndarray"),
    (3.0, r"u.jacobian: expected a function J\(t, q, qd\) -> \(du/dq, du/dqd\) or None, got 3.0"),
])
def test_bad_jacobians_are_named(models, jacobian, message):
    driven = models[1]
    with pytest.raises(ValueError, match=message):
        simulate(driven, 0.1, u=Controller(lambda t, q, qd: [0.0], jacobian), sensitivities=["g"])


def test_pd_checks_its_gains(models):
    driven = models[1]
    with pytest.raises(ValueError, match=r"pd.kp: expected a number or 1 numbers \(theta_2\), got \[1, 2\]"):
        pd(driven, kp=[1, 2], kd=0.0)
    with pytest.raises(ValueError, match=r"pd.target: must be finite"):
        pd(driven, kp=1.0, kd=0.0, target=math.inf)
    with pytest.raises(ValueError, match=r"u.function: expected a function u\(t, q, qd\)"):
        simulate(driven, 0.1, u=Controller(None))
