"""Driven chains: inputs, joint springs and dampers, against independent formulations.

* the generalised forces against the numpy reference model (virtual power of joint torques and base forces,
  spring angles read off the frames), on random 3D chains: forward dynamics, R, power, spring energy;
* the Lagrangian expansion (springs through their potential) against the Gibbs-Appell kernels;
* closed forms: two rods joined by a torsional spring, floating with g = 0, oscillate at
  omega^2 = 24 K / (m l^2); a damper alone makes their relative rate decay at 24 C / (m l^2);
* momentum of a free chain under internal torques, and the energy balance of driven runs with impacts;
* an undriven scene's operation counts are those of the passive model.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import Joint, LineLink, Scene, SceneError, Wall, default_scene, load_scene, scene_from_dict
from runtime import simulate
from runtime.inputs import InputSchedule
from studies import reference
from conftest import chain, driven, driven_free_chain, random_parameters, reference_of, quick_model

def rel_err(a, b):
    return np.abs(np.asarray(a) - b).max() / max(np.abs(b).max(), 1e-300)


def springs_of(scene: Scene, p: np.ndarray):
    names = scene.parameter_names()
    springs, dampers = {}, {}
    for k, joint in enumerate(scene.joints, start=2):
        if joint.stiffness is not None:
            springs[k] = (p[names.index(f"stiffness_{k}")], p[names.index(f"rest_angle_{k}")])
        if joint.damping is not None:
            dampers[k] = p[names.index(f"damping_{k}")]
    return springs, dampers


@pytest.mark.parametrize("n,kinds", [(2, ("line",)), (3, ("rigid", "line")), (4, ("rigid",))])
def test_generalised_forces_match_the_reference(derived, n, kinds):
    """The derivation (run as Python, no C); test_build_kernels and the runs below check the compiled C."""
    scene = driven(chain(n, kinds, twists=True), seed=n)
    model = derived(scene)
    assert model.nu == len(scene.inputs) >= 6
    rng = np.random.default_rng(n)
    for trial in range(4):
        p = random_parameters(scene, seed=400 * n + trial)
        springs, dampers = springs_of(scene, p)
        for k in springs:                           # new spring and damper constants too
            springs[k] = (rng.uniform(0.5, 20), rng.uniform(-1, 1))
            dampers[k] = rng.uniform(0.1, 3)
        names = scene.parameter_names()
        for k, (K, rest) in springs.items():
            p[names.index(f"stiffness_{k}")], p[names.index(f"rest_angle_{k}")] = K, rest
        for k, C in dampers.items():
            p[names.index(f"damping_{k}")] = C
        ref = reference_of(scene, p)
        q, qd = reference.random_state(n, rng)
        u = rng.normal(size=model.nu) * 3
        Q = ref.applied_forces(q, qd, u, scene.inputs, springs, dampers)
        assert rel_err(model.bias(q, qd, p, u), ref.bias(q, qd) + Q) < 1e-10
        expected = np.linalg.solve(ref.mass_matrix(q), ref.bias(q, qd) + Q)
        assert rel_err(model.forward_dynamics(q, qd, p, u), expected) < 1e-9
        # the power of the inputs and the dampers' dissipation, from the reference's forces
        P_in, P_damp = model.power(q, qd, p, u)
        Q_in = ref.applied_forces(q, qd, u, scene.inputs)
        Q_damp = ref.applied_forces(q, qd, dampers=dampers)
        assert P_in == pytest.approx(Q_in @ qd, rel=1e-12, abs=1e-12)
        assert P_damp == pytest.approx(-Q_damp @ qd, rel=1e-12) and P_damp >= 0
        # the springs' potential is part of V
        passive = dataclasses.replace(scene, joints=(), inputs=())
        V_springs = model.energy(q, qd, p)[1] - ref.energy(q, qd)[1]
        assert V_springs == pytest.approx(ref.spring_energy(q, springs), rel=1e-11)
        assert passive.parameter_names() == scene.parameter_names()[:len(passive.parameter_names())]


def test_lagrangian_expansion_agrees_with_gibbs_appell(derived):
    """The Euler-Lagrange expansion takes the springs from their potential (dV/dq), not as torques (both
    derivations run as Python)."""
    scene = driven(chain(2, ("rigid",), twists=True), seed=7)
    ga, el = derived(scene), derived(scene, formulation="lagrange")
    rng = np.random.default_rng(7)
    for _ in range(4):
        q, qd = reference.random_state(2, rng)
        u = rng.normal(size=ga.nu)
        assert rel_err(el.bias(q, qd, u=u), ga.bias(q, qd, u=u)) < 1e-10
        assert rel_err(el.forward_dynamics(q, qd, u=u), ga.forward_dynamics(q, qd, u=u)) < 1e-9


# ---------------------------------------------------------------------------------------------------
# closed forms: two uniform rods (mass m, length l, no thickness) joined by a joint, floating, g = 0.
# With zero momentum and the rods nearly in line, the relative angle phi obeys
#   (m l^2 / 24) phi'' = -K phi - C phi'
# (each rod turns by -+phi/2 about the joint, which stays at the centre of mass: T = (m l^2 / 48) phi'^2).
# ---------------------------------------------------------------------------------------------------
def two_rods(stiffness=None, damping=None, phi0=0.0, rate0=0.0, l=1.0, mu=1.5) -> Scene:
    """Link 1 along +X1 from the origin, link 2 turned by phi0; velocities with zero linear and angular
    momentum at the straight configuration: theta_dot_1 = -rate0 / 2, X2_dot = l rate0 / 4."""
    q0 = (-math.pi / 2, 0.0, -math.pi / 2, phi0, 0.0, 0.0, 0.0)
    qd0 = (0.0, 0.0, -rate0 / 2, rate0, 0.0, l * rate0 / 4, 0.0)
    return Scene(name="two_rods", links=(LineLink(l, mu, (0.0, 0.0, 0.0)),) * 2, gravity=0.0, q0=q0, qd0=qd0,
                 joints=(Joint(stiffness, 0.0, damping),))


def test_torsional_spring_oscillates_at_the_reduced_inertia_frequency():
    K, l, mu, phi0 = 3.0, 1.0, 1.5, 1e-5
    m = mu * l
    omega = math.sqrt(24 * K / (m * l * l))
    period = 2 * math.pi / omega
    t = np.linspace(0, 3 * period, 61)
    run = simulate(quick_model(two_rods(stiffness=K, phi0=phi0)), t[-1], t_eval=t, method="dop853",
                   rtol=1e-13, atol=1e-20)
    assert run.success
    phi = run.q[:, 3]
    assert np.abs(phi - phi0 * np.cos(omega * t)).max() < 1e-6 * phi0     # nonlinearity ~ phi0^2
    assert np.abs(phi - phi0 * np.cos(1.01 * omega * t)).max() > 1e-2 * phi0   # the check can tell


def test_damper_decays_at_the_predicted_rate():
    C, l, mu, rate0 = 0.2, 1.0, 1.5, 1e-5
    m = mu * l
    decay = 24 * C / (m * l * l)
    t = np.linspace(0, 2.0, 21)
    run = simulate(quick_model(two_rods(damping=C, rate0=rate0)), t[-1], t_eval=t, method="dop853",
                   rtol=1e-13, atol=1e-22)
    rate = run.qd[:, 3]
    assert np.abs(rate - rate0 * np.exp(-decay * t)).max() < 1e-6 * rate0
    # the dampers took the kinetic energy: the balance closes
    assert run.loss_damping == pytest.approx(run.energy_initial - run.energy_final, rel=1e-8)


def test_momentum_of_a_free_chain_is_kept_under_internal_torques(compiled):
    """g = 0, no walls: joint inputs (state feedback from Python), springs and dampers are internal."""
    scene = driven_free_chain()
    model = compiled(scene, tangent=True)              # the derivative tests' model: one build
    ref = reference_of(scene)

    def pd(t, q, qd):
        return -4.0 * (q[3:5] - 0.5) - 0.5 * qd[3:5] + np.sin(3 * t)
    run = simulate(model, 1.0, t_eval=np.linspace(0, 1, 11), u=pd, method="dop853", rtol=1e-12, atol=1e-12)
    assert run.success and run.work_input != 0.0
    P = np.array([ref.linear_momentum(q, qd) for q, qd in zip(run.q, run.qd)])
    L = np.array([ref.angular_momentum(q, qd) for q, qd in zip(run.q, run.qd)])
    assert np.abs(P - P[0]).max() < 1e-10 * max(1.0, np.abs(P).max())
    assert np.abs(L - L[0]).max() < 1e-9 * max(1.0, np.abs(L).max())
    assert abs(run.energy_drift) < 1e-9


DRIVEN_SCENE = "driven-fold"


@pytest.mark.parametrize("how", ["constant", "hold", "linear", "function"])
def test_energy_balance_closes_on_driven_runs_with_impacts(how):
    model = quick_model(DRIVEN_SCENE)
    u = {"constant": [0.4, -0.3],
         "hold": InputSchedule([0.2, 0.5, 0.9], [[0.5, 0.0], [-0.5, 0.3], [0.0, 0.0]]),
         "linear": InputSchedule([0.0, 0.6, 1.2], [[0.0, 0.0], [1.0, -1.0], [0.0, 0.5]], mode="linear"),
         "function": lambda t, q, qd: -2.0 * qd[3:5] + 0.3}[how]
    run = simulate(model, 1.5, u=u, method="dop853", rtol=1e-12, atol=1e-12)
    assert run.success, run.message
    assert len(run.impacts) >= 2 and run.loss_damping > 0 and run.work_input != 0
    assert abs(run.energy_drift) < 1e-9, run.energy_summary()
    if how == "hold":                    # the held values, sampled
        assert np.array_equal(run.u[np.searchsorted(run.t, 0.3)], [0.5, 0.0])


def test_hold_schedule_jumps_on_a_step_boundary():
    """A held schedule equals two runs chained at the jump (the second from the first's end state)."""
    model = quick_model(DRIVEN_SCENE)
    opts = dict(method="dop853", rtol=1e-12, atol=1e-12, max_impacts=1)
    whole = simulate(model, 0.12, u=InputSchedule([0.0, 0.06], [[1.0, -1.0], [-2.0, 0.5]]), **opts)
    first = simulate(model, 0.06, u=[1.0, -1.0], **opts)
    second = simulate(model, 0.06, u=[-2.0, 0.5], q0=first.q_final, qd0=first.qd_final, **opts)
    assert not whole.impacts and not first.impacts
    assert rel_err(whole.q_final, second.q_final) < 1e-9


def test_python_input_function_errors_reach_the_caller():
    model = quick_model(DRIVEN_SCENE)

    def broken(t, q, qd):
        if t > 0.05:
            raise KeyError("no gain for this state")
        return [0.0, 0.0]
    with pytest.raises(KeyError, match="no gain"):
        simulate(model, 0.2, u=broken)
    with pytest.raises(ValueError, match="u: the input function returned 3 values"):
        simulate(model, 0.2, u=lambda t, q, qd: [0.0, 0.0, 0.0])


@pytest.mark.parametrize("u,message", [
    ([1.0], "u: expected 2 finite number(s) (theta_2, theta_3)"),
    ([1.0, float("nan")], "u: expected 2 finite number(s)"),
    ("fast", "u: expected 2 number(s) (theta_2, theta_3), an InputSchedule or a function"),
    (InputSchedule([0.0, 0.0], [[0, 0], [1, 1]]), "u.times: must be finite and strictly increasing"),
    (InputSchedule([0.0], [[0, 0, 0]]), "u.values: expected one row of 2 value(s)"),
    (InputSchedule([0.0], [[0, 0]], mode="cubic"), "u.mode: must be one of"),
])
def test_bad_inputs_are_named(u, message):
    with pytest.raises(ValueError) as error:
        simulate(quick_model(DRIVEN_SCENE), 0.1, u=u)
    assert message in str(error.value)


def test_inputs_on_a_model_without_any_are_refused():
    with pytest.raises(ValueError, match="u: this model has no inputs"):
        simulate(quick_model("paper-case1"), 0.1, u=[1.0])


def test_parameters_by_name():
    model = quick_model(DRIVEN_SCENE)
    stiff = simulate(model, 0.3, p={"stiffness_2": 40.0, "damping_3": 0.0}, max_impacts=1)
    base = simulate(model, 0.3, max_impacts=1)
    assert not np.allclose(stiff.q_final, base.q_final)
    with pytest.raises(ValueError, match="p\\[stiffnes_2\\]: no such parameter; this model's parameters are g, "):
        simulate(model, 0.1, p={"stiffnes_2": 1.0})
    with pytest.raises(ValueError, match="p\\[stiffness_2\\]: must be >= 0"):
        simulate(model, 0.1, p={"stiffness_2": -1.0})


@pytest.mark.parametrize("table,message", [
    ({"inputs": ["theta_9"]}, "inputs: unknown coordinate 'theta_9'; allowed: theta_-1, theta_0"),
    ({"inputs": ["X1", "X1"]}, "inputs: a coordinate is named twice"),
    ({"inputs": "X1"}, "inputs: expected a list of coordinate names"),
    ({"links2": {"stiffness": -1.0}}, "links[2].stiffness: must be >= 0"),
    ({"links2": {"rest_angle": 0.5}}, "links[2].rest_angle: given without a stiffness"),
    ({"links2": {"damping": float("inf")}}, "links[2].damping: must be a finite number"),
])
def test_bad_driven_scene_fields_are_named(table, message):
    data = {"links": [{"length": 1.0, "mu": 1.0}, {"length": 1.0, "mu": 1.0, **table.get("links2", {})}]}
    if "inputs" in table:
        data["inputs"] = table["inputs"]
    with pytest.raises(SceneError) as error:
        scene_from_dict(data)
    assert message in str(error.value)


def test_an_undriven_scene_generates_the_passive_operations():
    """Counts of the 4-link default chain (specialised): a scene without inputs, springs or dampers has no
    extra term, and each joint's spring, damper and input cost a few operations only."""
    from codegen.pipeline import generate
    scene = default_scene(4)
    passive = {f.name: f.ops.total for f in generate(scene).functions}
    assert (passive["mass_matrix"], passive["bias"], passive["forward_dynamics"], passive["energy"]) == \
        (137, 119, 316, 176)
    assert passive["power"] == 0
    full = dataclasses.replace(scene, joints=(Joint(5.0, 0.1, 0.5),) * 3, inputs=("theta_2", "theta_3", "theta_4"))
    ops = {f.name: f.ops.total for f in generate(full).functions}
    assert 0 < ops["forward_dynamics"] - passive["forward_dynamics"] <= 8 * 3


def test_planar_specialisation_keeps_inputs_in_the_plane():
    scene = load_scene(DRIVEN_SCENE)
    from codegen.specialise import layout_for
    assert layout_for(scene).planar_normal is not None
    out = dataclasses.replace(scene, inputs=("theta_2", "theta_0"))
    layout = layout_for(out)
    assert layout.planar_normal is None and "an input drives theta_0 out of the plane" in layout.notes[0]


def test_walls_stay_walls_under_inputs():
    """A strong input cannot push a point through a wall: impacts keep every gap >= -tolerance."""
    model = quick_model(DRIVEN_SCENE)
    run = simulate(model, 1.0, u=[8.0, -8.0], t_eval=np.linspace(0, 1, 401))
    assert run.success, run.message
    scene = model.scene
    from codegen.scene import contact_points
    lowest = min(contact_points(scene, q)[:, 1].min() for q in run.q)
    assert lowest > -1e-6
    assert isinstance(scene.walls[0], Wall)


# ---------------------------------------------------------------------------------------------------
# joint limits: stops handled like walls (events, Newton's law on a row of the identity, resting)
# ---------------------------------------------------------------------------------------------------
def rods_with_stops(e: float, rate0: float = 0.0, lower=-0.2, upper=0.2) -> Scene:
    q0 = (-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 0.0, 0.0)
    qd0 = (0.0, 0.0, -rate0 / 2, rate0, 0.0, rate0 / 4, 0.0)
    return Scene(name=f"rods_stops_{int(e * 10)}", links=(LineLink(1.0, 1.5, (1e-3, 1e-3, 1e-3)),) * 2, gravity=0.0,
                 q0=q0, qd0=qd0, joints=(Joint(lower=lower, upper=upper, limit_restitution=e),), inputs=("theta_2",))


def test_an_elastic_stop_reverses_the_joint_rate_and_keeps_energy_and_momentum(compiled):
    scene = rods_with_stops(1.0, rate0=1.0)
    model = compiled(scene)
    run = simulate(model, 2.0, method="dop853", rtol=1e-12, atol=1e-12)
    assert run.success and len(run.impacts) >= 4
    ref = reference_of(scene)
    for impact in run.impacts:
        assert [c.kind for c in impact.contacts] == ["stop"]
        stop = impact.contacts[0].wall
        assert stop in ("theta_2_upper", "theta_2_lower")
        assert impact.q[3] == pytest.approx(0.2 if stop.endswith("upper") else -0.2, abs=1e-9)
        assert impact.qd_after[3] == pytest.approx(-impact.qd_before[3], rel=1e-10)       # e = 1 on theta_2's row
        for momentum in (ref.linear_momentum, ref.angular_momentum):                       # an internal impulse
            assert np.abs(momentum(impact.q, impact.qd_after) - momentum(impact.q, impact.qd_before)).max() < 1e-12
    assert abs(run.energy_final - run.energy_initial) < 1e-10 * run.energy_initial
    assert abs(run.loss_impacts) < 1e-12


def test_a_plastic_stop_holds_the_joint_until_the_input_pulls_it_off(compiled):
    model = compiled(rods_with_stops(0.0))
    u = InputSchedule([0.0, 0.6], [[0.5], [-0.5]])               # push into the upper stop, then away from it
    run = simulate(model, 1.0, u=u, t_eval=np.linspace(0, 1, 101), method="dop853", rtol=1e-10, atol=1e-12)
    assert run.success, run.message
    first = run.impacts[0]
    assert first.contacts[0].wall == "theta_2_upper" and first.qd_after[3] == pytest.approx(0.0, abs=1e-12)
    kinds = [(e.kind, e.wall) for e in run.contact_events]
    assert ("rest", "theta_2_upper") in kinds and ("release", "theta_2_upper") in kinds
    rest = next(e.t for e in run.contact_events if e.kind == "rest")
    held = (run.t > rest) & (run.t <= 0.6)
    assert held.sum() > 10 and np.abs(run.q[held, 3] - 0.2).max() < 1e-6      # at its stop while pushed
    assert run.q[-1, 3] < 0.19                                                   # and off it once pulled
    assert abs(run.energy_drift) < 1e-8


def test_stops_and_walls_take_part_in_one_impact():
    run = simulate(DRIVEN_SCENE, 1.0)
    assert run.success
    mixed = [i for i in run.impacts if {c.kind for c in i.contacts} == {"wall", "stop"}]
    assert mixed and all(c.impulse >= 0 for c in mixed[0].contacts)
    assert "theta_2_upper" in run.impact_table() and "O1/x2_min" in run.impact_table()


@pytest.mark.parametrize("joint,message", [
    ({"lower": 0.5, "upper": 0.5}, "links[2].upper: must be > lower = 0.5 rad, got 0.5"),
    ({"limit_restitution": 0.5}, "links[2].limit_restitution: given without a lower or upper limit"),
    ({"upper": 1.0, "limit_restitution": 1.5}, "links[2].limit_restitution: must be in [0, 1], got 1.5"),
    ({"upper": -0.5}, "initial.q[3] (theta_2): 0.0 rad is beyond the joint's upper limit -0.5 rad"),
])
def test_bad_limits_are_named(joint, message):
    data = {"links": [{"length": 1.0, "mu": 1.0}, {"length": 1.0, "mu": 1.0, **joint}],
            "initial": {"q": [-1.5707963267948966, 0.0, -1.5707963267948966, 0.0, 0.0, 0.0, 0.0]}}
    with pytest.raises(SceneError) as error:
        scene_from_dict(data)
    assert message in str(error.value)


def test_limits_by_parameter_are_checked():
    model = quick_model(DRIVEN_SCENE)
    with pytest.raises(ValueError, match=r"p\[upper_2\]: must be > p\[lower_2\] = 0.5, got 0.2"):
        simulate(model, 0.1, p={"lower_2": 0.5, "upper_2": 0.2})
    with pytest.raises(ValueError, match="joint 2 is beyond its upper limit upper_2"):
        simulate(model, 0.1, p={"upper_2": 0.3})


def test_stop_gaps_and_rows_match_finite_differences(derived):
    """Each contact's gap (walls and stops) changes along its Jacobian row signed by its normal: dgap/dq =
    normal_sign J[row] (finite differences), and a stop's row has no J_dot qd term."""
    scene = dataclasses.replace(chain(3, twists=True),
                                joints=(Joint(lower=-2.0, upper=2.5, limit_restitution=0.4), Joint(upper=3.0)))
    model = derived(scene)
    q, qd = reference.random_state(3, np.random.default_rng(5))
    q[3:5] = [0.3, -0.7]
    J, bias, h = model.contact_jacobian(q), model.contact_bias(q, qd), 1e-6
    stops = 0
    for c, (point, wall) in enumerate(model.contacts):
        axis = "theta" if hasattr(wall, "joint") else wall.axis
        row = model.contact_rows.index((point, axis))
        grad = [(model.contact_gaps(q + h * e)[c] - model.contact_gaps(q - h * e)[c]) / (2 * h) for e in np.eye(8)]
        assert np.allclose(grad, wall.normal_sign * J[row], atol=1e-8)
        if axis == "theta":
            stops += 1
            assert bias[row] == 0.0
    assert stops == 3
