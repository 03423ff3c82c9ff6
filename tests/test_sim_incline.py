"""Gravity along a tilted direction (gravity_direction): the box's floor becomes an incline.  One model (a slender rod,
1 m, 1 kg, on a floor x2_min, gravity tilted by ALPHA about X3, so d = (sin ALPHA, -cos ALPHA, 0)); the friction
coefficient and the restitution are runtime parameters, so every case below runs it:

* lying on the rough incline with tan ALPHA > c_f it slides down with a = g (sin ALPHA - c_f cos ALPHA):
  x(t) = x0 + v0 t + a t^2 / 2 (Coulomb sliding, the normal force m g cos ALPHA);
* with tan ALPHA < c_f, put down at rest, it stays put;
* thrown clear of the floor, its centre of mass follows r_G0 + v_G0 t + g d t^2 / 2 whatever it spins;
* frictionless and elastic (e = 1), bouncing down the incline, it keeps its energy, and its potential energy is
  -g m d . r_G, computed here from its points."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import contact_points, scene_from_dict
from runtime import simulate
from conftest import quick_model

G = 9.81
ALPHA = math.radians(25.0)
D = (math.sin(ALPHA), -math.cos(ALPHA), 0.0)          # gravity's direction in the box (the incline's) frame
LYING = [-math.pi / 2, 0.0, -math.pi / 2, 1.0, 0.0, 0.0]   # along +X1 from X1 = 1, both ends on the floor


def incline_rod():
    return scene_from_dict({"name": "incline_rod", "gravity": G, "gravity_direction": list(D),
                            "links": [{"length": 1.0, "mu": 1.0}], "walls": {"x2_min": 0.0},
                            "restitution": 0.0, "friction": 0.3, "friction_velocity": 1e-4,
                            "initial": {"q": LYING, "qd": [0.0] * 6}})


@pytest.fixture(scope="module")
def rod():
    scene = incline_rod()
    return scene, quick_model(scene, specialise=False)


def centre_of_mass(scene, q) -> np.ndarray:
    """The uniform rod's centre of mass: the middle of O_1 O_2."""
    return contact_points(scene, np.asarray(q)).mean(axis=0)


def test_it_slides_down_as_coulomb_says_when_tan_alpha_exceeds_c_f(rod):
    scene, model = rod
    c_f, v0 = 0.3, 0.5
    assert math.tan(ALPHA) > c_f
    a = G * (math.sin(ALPHA) - c_f * math.cos(ALPHA))
    t = np.linspace(0.0, 0.5, 51)
    result = simulate(model, 0.5, t_eval=t, p={"friction_x2_min": c_f}, qd0=[0.0, 0.0, 0.0, v0, 0.0, 0.0],
                      rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert [e.kind for e in result.contact_events] == ["rest", "rest"] and not result.impacts
    x = result.q[:, scene.n + 2]
    assert np.abs(x - (1.0 + v0 * t + 0.5 * a * t * t)).max() < 1e-8
    assert np.abs(result.q[:, scene.n + 3]).max() < 1e-12 and np.abs(result.q[:, scene.n + 4]).max() < 1e-12
    # the friction took c_f m g cos(alpha) times the distance slid
    distance = x[-1] - 1.0
    assert result.loss_friction == pytest.approx(c_f * G * math.cos(ALPHA) * distance, rel=1e-8)
    assert abs(result.energy_drift) < 1e-9


def test_it_stays_put_when_c_f_exceeds_tan_alpha(rod):
    scene, model = rod
    c_f = 0.6
    assert math.tan(ALPHA) < c_f
    result = simulate(model, 0.5, t_eval=np.linspace(0.0, 0.5, 11), p={"friction_x2_min": c_f},
                      rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert [e.kind for e in result.contact_events] == ["rest", "rest", "stick", "stick"]
    assert np.abs(result.q - np.array(LYING)).max() < 1e-12
    assert np.abs(result.qd).max() < 1e-12


def test_its_centre_of_mass_falls_along_d_in_flight(rod):
    scene, model = rod
    q0 = [0.3, -0.4, 0.8, 1.0, 2.5, 0.2]                  # turned in 3D, 2.5 m up the floor's normal
    qd0 = [1.5, -2.0, 3.0, 0.4, 0.5, -0.3]                # spinning about every axis, thrown
    t = np.linspace(0.0, 0.4, 41)
    result = simulate(model, 0.4, t_eval=t, q0=q0, qd0=qd0, rtol=1e-11, atol=1e-12)
    assert result.success, result.message
    assert not result.impacts
    h = 1e-7                                               # the centre's initial velocity by a central difference
    v_G0 = (centre_of_mass(scene, np.array(q0) + h * np.array(qd0))
            - centre_of_mass(scene, np.array(q0) - h * np.array(qd0))) / (2 * h)
    r_G0 = centre_of_mass(scene, q0)
    expected = r_G0 + np.outer(t, v_G0) + 0.5 * G * np.outer(t * t, D)
    got = np.array([centre_of_mass(scene, q) for q in result.q])
    assert np.abs(got - expected).max() < 1e-8


def test_energy_is_conserved_bouncing_down_a_smooth_incline(rod):
    scene, model = rod
    q0 = [-math.pi / 2, 0.0, -1.0, 1.0, 0.8, 0.0]
    qd0 = [0.0, 0.0, 4.0, 1.0, 0.5, 0.0]
    result = simulate(model, 2.0, t_eval=np.linspace(0.0, 2.0, 201), q0=q0, qd0=qd0,
                      p={"friction_x2_min": 0.0, "e_x2_min": 1.0}, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert result.n_impacts >= 3
    assert abs(result.energy_drift) < 1e-8 and abs(result.loss_impacts) < 1e-8 * result.energy_scale
    # the model's potential energy is -g m d . r_G (m = 1 kg), and T + V stays at its start
    p = scene.parameter_vector()
    for q, qd in zip(result.q[::20], result.qd[::20]):
        T, V = model.energy(q, qd, p)
        assert V == pytest.approx(-G * np.dot(D, centre_of_mass(scene, q)), rel=1e-12, abs=1e-12)
        assert T + V == pytest.approx(result.energy_initial, rel=1e-8)
