"""Mounted bases in the hybrid loop: closed forms of a pinned rod pendulum (its small-oscillation period, the time a
rod released horizontally takes to reach a wall below its pivot by the incomplete elliptic integral), a fixed-base
arm against the reference model integrated by scipy, a spherical pin through the gimbal lock of its base chart, and
the shipped scene mounted-arm (impacts, a joint stop, resting contact, an input) with its energy balance."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipkinc

from codegen.scene import Base, LineLink, Scene, Wall, load_scene
from conftest import chain, quick_model, reference_of
from runtime import simulate

L, MU, G = 0.8, 1.5, 9.81
OMEGA = math.sqrt(3 * G / (2 * L))      # a uniform rod about its end: phi'' = -(3 g / 2 L) sin(phi)
PIVOT = (0.0, 2.0, 0.0)


def rod(walls=(), theta1=-math.pi / 2, name="pinned_rod"):
    """A uniform slender rod (no cross-section inertia) pinned at PIVOT, turning about X3; theta_1 = -pi/2 points
    it along +X1 (horizontal), theta_1 = -pi straight down."""
    return Scene(name=name, links=(LineLink(L, MU, (0.0, 0.0, 0.0)),), gravity=G, walls=walls,
                 base=Base("pinned", "revolute", PIVOT, (0.0, 0.0, 1.0)), q0=(theta1,))


def test_pinned_rod_has_one_coordinate_and_the_small_oscillation_period():
    model = quick_model(rod(name="pinned_rod_open"))
    assert model.nq == 1 and list(model.layout.held) == [0, 1, 3, 4, 5]
    amplitude = 1e-3
    x0 = np.array([-math.pi + amplitude, 0.0])              # hanging down, turned a little
    crossing = lambda t, x: x[0] + math.pi
    crossing.terminal, crossing.direction = True, 0
    solution = solve_ivp(lambda t, x: model.rhs(t, x), (0.0, 2.0), x0, method="DOP853", rtol=1e-13, atol=1e-15,
                         events=crossing, dense_output=True)
    quarter = solution.t_events[0][0]
    exact = 2 * math.pi * math.sqrt(2 * L / (3 * G))           # the small-oscillation period
    assert abs(4 * quarter / exact - 1) < 1e-6                 # amplitude 1e-3: the period is longer by ~A^2 / 16
    k2 = math.sin(amplitude / 2) ** 2
    assert abs(quarter - ellipkinc(math.pi / 2, k2) / OMEGA) < 1e-10
    E0 = sum(model.energy(x0[:1], x0[1:]))
    scale = MU * L * G * L / 2                                  # the rod's potential energy about the pivot
    for x in solution.sol(np.linspace(0.0, quarter, 20)).T:
        assert abs(sum(model.energy(x[:1], x[1:])) - E0) < 1e-12 * scale


def test_rod_released_horizontally_reaches_the_wall_below_its_pivot_at_the_elliptic_time():
    """Released along +X1, the rod swings down through the vertical and its tip O_2 meets the wall X1 = -c below
    the pivot at phi = -asin(c / L) from the vertical: t = (K(m) + F(psi, m)) / omega, m = sin^2(pi / 4),
    sin psi = sin(asin(c / L) / 2) / sqrt(m).  The pivot does no work: the energy balance closes (e = 1)."""
    c = 0.3
    model = quick_model(rod(walls=(Wall("x1_min", -c, 1.0),)))
    assert [(p, w.name) for p, w in model.contacts] == [(2, "x1_min")]   # O_1 is held: not a contact
    result = simulate(model, 0.9, method="dop853", rtol=1e-12, atol=1e-12)
    assert result.status == 0 and len(result.impacts) >= 1
    m = 0.5
    psi = math.asin(math.sin(math.asin(c / L) / 2) / math.sqrt(m))
    t_hit = (ellipkinc(math.pi / 2, m) + ellipkinc(psi, m)) / OMEGA
    assert abs(result.impacts[0].t - t_hit) < 1e-9
    assert np.array_equal(result.q[:, 3:6], np.tile(PIVOT, (len(result.t), 1)))    # X held: full layout
    assert np.all(result.qd[:, [0, 1, 3, 4, 5]] == 0.0)
    assert abs(result.energy_final - result.energy_initial) < 1e-9 * result.energy_scale
    assert abs(result.energy_drift) < 1e-9


def test_fixed_base_arm_matches_the_reference_integrated():
    """A 2-link arm on a fixed, tilted base (3D: joint 2 is twisted) under gravity, against the reference model's
    M[free, free] qdd = R[free] integrated by scipy."""
    scene = chain(2, ("rigid", "line"), twists=True, walls=False)
    scene = dataclasses.replace(scene, base=Base("fixed", None, (0.2, 0.5, -0.1), None, (0.4, -0.3, 0.9)),
                                q0=(0.6,), qd0=(1.5,), gravity=9.81)
    model = quick_model(scene)
    assert model.nq == 1
    ref = reference_of(scene)
    layout = model.layout
    free = list(layout.free)

    def reference_rhs(t, x):
        q, qd = layout.expand(x[:1]), layout.expand(x[1:], velocity=True)
        M, R = ref.mass_matrix(q)[np.ix_(free, free)], ref.bias(q, qd)[free]
        return np.r_[x[1:], np.linalg.solve(M, R)]

    t = np.linspace(0.0, 1.5, 31)
    expected = solve_ivp(reference_rhs, (0.0, 1.5), np.r_[model.q0, model.qd0], method="DOP853", rtol=1e-12,
                         atol=1e-12, t_eval=t).y
    result = simulate(model, 1.5, method="dop853", t_eval=t, rtol=1e-12, atol=1e-12)
    assert result.status == 0
    assert np.abs(result.q[:, 3] - expected[0]).max() < 1e-8
    assert np.abs(result.qd[:, 3] - expected[1]).max() < 1e-8
    assert abs(result.energy_drift) < 1e-9


def test_spherical_pin_through_the_gimbal_lock():
    """A 2-link chain on a spherical pin spinning through theta_0 = pi/2: the loop switches to the second base chart
    (the three angles stay coordinates), O_1 stays at the pin and the energy is conserved."""
    scene = chain(2, ("line", "rigid"), twists=True, walls=False)
    base = Base("pinned", "spherical", (0.0, 0.0, 0.0))
    q0 = (0.0, 1.3, 0.4, 0.7)                    # theta_-1, theta_0, theta_1, theta_2 (no X: held)
    qd0 = (0.0, 3.0, 0.5, -1.0)
    scene = dataclasses.replace(scene, base=base, q0=q0, qd0=qd0, gravity=0.0, name="pinned_spin")
    model = quick_model(scene, chart_b=True)
    assert model.nq == 4
    result = simulate(model, 1.0, method="dop853", rtol=1e-11, atol=1e-11)
    assert result.status == 0 and result.n_chart_switches >= 1
    assert np.abs(result.q[:, 4:7]).max() == 0.0
    assert abs(result.energy_final - result.energy_initial) < 1e-8 * result.energy_initial


def test_mounted_arm_scene_energy_balance_with_an_input():
    """The shipped scene: the arm hits its elbow stop, the right wall and the floor and comes to rest; with a
    shoulder torque its energy balance (inputs' work, dampers, impacts) closes."""
    scene = load_scene("mounted-arm")
    model = quick_model(scene)
    assert model.nq == 2
    result = simulate(model, 3.0, rtol=1e-10, atol=1e-10)
    assert result.status == 0, result.message
    hit = {c.label for impact in result.impacts for c in impact.contacts}
    assert {"theta_3_lower", "O4/x1_max", "O4/x2_min"} <= hit
    assert result.resting_final
    assert abs(result.energy_drift) < 1e-7
    driven = simulate(model, 1.0, u=[0.8], rtol=1e-10, atol=1e-10)
    assert driven.status == 0 and driven.work_input != 0.0
    assert abs(driven.energy_drift) < 1e-7


def test_state_given_to_a_mounted_model_keeps_its_base():
    model = quick_model(rod(walls=(Wall("x1_min", -0.3, 1.0),)))
    q0 = np.array(model.layout.expand(model.q0))
    q0[5] += 0.1
    with pytest.raises(ValueError, match=r"q0\[5\]: the scene's base holds it at 0.0"):
        simulate(model, 0.1, q0=q0)


def test_rolled_forward_dynamics_of_a_mounted_chain():
    """A 9-link chain on a revolute pin, its forward dynamics as loops over the run of identical links
    (codegen.rolled), against the reference's restricted equations."""
    from studies import reference
    scene = chain(9, walls=False)
    scene = dataclasses.replace(scene, base=Base("pinned", "revolute", (0.0, 0.0, 0.0), (0.3, 0.4, 0.5)), q0=(),
                                qd0=(), name="rolled_pinned9")
    model = quick_model(scene, rolled=True)
    assert model.nq == 9
    ref, layout = reference_of(scene), model.layout
    free = list(layout.free)
    rng = np.random.default_rng(9)
    for _ in range(3):
        q, qd = reference.random_state(9, rng)
        q, qd = layout.expand(layout.reduce(q)), layout.expand(layout.reduce(qd), velocity=True)
        expected = np.linalg.solve(ref.mass_matrix(q)[np.ix_(free, free)], ref.bias(q, qd)[free])
        qdd = model.rhs(0.0, np.r_[layout.reduce(q), layout.reduce(qd)])[model.nq:]
        assert np.abs(qdd - expected).max() < 1e-10 * np.abs(expected).max()


def test_motor_at_a_revolute_pivot_does_the_work_it_should():
    """An input on theta_1 of a revolute pin (a motor at the pivot): with a constant torque tau the work of the
    inputs is tau (theta_1(t) - theta_1(0)), and the energy balance closes."""
    scene = dataclasses.replace(rod(name="pinned_rod_motor"), inputs=("theta_1",))
    model = quick_model(scene)
    tau = 2.5
    result = simulate(model, 1.0, method="dop853", u=[tau], rtol=1e-12, atol=1e-12)
    assert result.status == 0
    assert abs(result.work_input - tau * (result.q_final[2] - result.q[0, 2])) < 1e-9 * result.energy_scale
    assert abs(result.energy_final - result.energy_initial - result.work_input) < 1e-9 * result.energy_scale
