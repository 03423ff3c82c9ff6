"""Coulomb friction at resting contacts (walls with `friction`): the constrained dynamics against a dense solve with
the independent reference model (studies/reference.py) on random 3D states; a rod sliding to rest against the
closed form x(t) = x0 + v0 t - c_f g t^2 / 2; a diagonal slide in 3D; a pushed rod that creeps below the Coulomb
limit at the regularised rate and accelerates above it at (F - c_f m g) / m; the energy balance with the friction
loss closing; a frictionless scene's code unchanged."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import SceneError, load_scene, scene_from_dict
from runtime import simulate
from studies.reference import reference_of
from conftest import quick_model

G = 9.81


def rod(friction=0.5, v=(2.0, 0.0), inputs=(), friction_velocity=1e-4, restitution=0.0):
    """A slender rod (1 m, 1 kg) lying on a floor along +X1, sliding at (v_X1, v_X3)."""
    data = {"name": "rod", "gravity": G, "links": [{"length": 1.0, "mu": 1.0}],
            "walls": {"x2_min": 0.0}, "restitution": restitution, "friction": friction,
            "friction_velocity": friction_velocity, "inputs": list(inputs),
            "initial": {"q": [-math.pi / 2, 0.0, -math.pi / 2, 1.0, 0.0, 0.0],
                        "qd": [0.0, 0.0, 0.0, v[0], 0.0, v[1]]}}
    return scene_from_dict(data)


@pytest.mark.parametrize("specialise", [True, False])
def test_a_sliding_rod_stops_as_coulomb_says(specialise):
    c_f, v0 = 0.5, 2.0
    scene = rod(c_f, (v0, 0.0))
    model = quick_model(scene, specialise=specialise)
    t_stop = v0 / (c_f * G)
    t = np.linspace(0.0, 0.6, 61)
    result = simulate(model, 0.6, t_eval=t, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert [e.kind for e in result.contact_events] == ["rest", "rest", "stick", "stick"] and not result.impacts
    x = result.q[:, scene.n + 2]
    exact = np.where(t < t_stop, 1.0 + v0 * t - 0.5 * c_f * G * t * t, 1.0 + v0 * v0 / (2 * c_f * G))
    assert np.abs(x - exact).max() < 1e-8                 # the regularisation below 1e-4 m/s moves it by 1e-9
    assert result.loss_friction == pytest.approx(0.5 * v0 * v0, rel=1e-9)
    assert abs(result.energy_residual) < 1e-9
    assert np.abs(result.q[:, scene.n + 3]).max() < 1e-12                  # still on the floor


def test_a_diagonal_slide_keeps_its_direction():
    """Sliding along (3, 4)/5 in the floor's plane (general model: both tangential axes): friction opposes the
    velocity, so the rod decelerates along a straight line by c_f g and stops after |v0|^2 / (2 c_f g)."""
    c_f, v = 0.4, (1.2, 1.6)
    scene = rod(c_f, v)
    model = quick_model(scene, specialise=False)
    result = simulate(model, 0.6, rtol=1e-10, atol=1e-12, t_eval=[0.1, 0.6])
    assert result.success, result.message
    speed0 = math.hypot(*v)
    s = speed0 * 0.1 - 0.5 * c_f * G * 0.01
    n = scene.n
    assert result.q[0, n + 2] - 1.0 == pytest.approx(s * v[0] / speed0, abs=1e-9)
    assert result.q[0, n + 4] == pytest.approx(s * v[1] / speed0, abs=1e-9)
    distance = speed0 ** 2 / (2 * c_f * G)
    assert result.q[1, n + 2] - 1.0 == pytest.approx(distance * v[0] / speed0, abs=1e-8)
    assert result.q[1, n + 4] == pytest.approx(distance * v[1] / speed0, abs=1e-8)


@pytest.mark.parametrize("force", [2.0, 7.0])
def test_a_pushed_rod_creeps_below_the_limit_and_slides_above_it(force):
    """A horizontal force F on the resting rod (c_f m g = 4.905 N), the regularised friction alone (stick=False; with
    sticking, the default, the rod stays exactly in place: tests/test_sim_stick.py): below the limit it creeps at the
    regularised rate v_s F / (c_f m g); above it, it accelerates at (F - c_f m g) / m from rest."""
    c_f, vs = 0.5, 1e-4
    scene = rod(c_f, (0.0, 0.0), inputs=("X1",), friction_velocity=vs)
    model = quick_model(scene)
    result = simulate(model, 0.5, u=[force], rtol=1e-10, atol=1e-12, t_eval=[0.5], stick=False)
    assert result.success, result.message
    n = scene.n
    limit = c_f * 1.0 * G
    if force < limit:
        assert result.qd[-1, n + 2] == pytest.approx(vs * force / limit, rel=1e-6)
    else:
        a = force - limit
        # the first v_s of speed is reached in the viscous regime; after it, exactly Coulomb
        assert result.qd[-1, n + 2] == pytest.approx(a * 0.5, abs=2 * vs)
    assert abs(result.energy_residual) < 1e-9 * max(1.0, result.work_input)


def contact_directions(scene, contacts, resting, J, qd):
    """The signed normal rows N and the generalised directions D = N + c_f J_t^T(-phi) of the resting contacts, from
    the reference model's point Jacobians J (n + 1, 3, nq): the friction law written out independently."""
    N, D = [], []
    for c in resting:
        point, wall = contacts[c]
        n_row = wall.normal_sign * J[point - 1, wall.axis]
        d = n_row.copy()
        if wall.friction > 0:
            tangents = [a for a in range(3) if a != wall.axis]
            vt = np.array([J[point - 1, a] @ qd for a in tangents])
            phi = vt / max(np.linalg.norm(vt), scene.friction_velocity)
            d -= wall.friction * sum(phi[j] * J[point - 1, a] for j, a in enumerate(tangents))
        N.append(n_row)
        D.append(d)
    return np.array(N), np.array(D)


def test_constrained_dynamics_with_friction_against_a_dense_solve():
    """Random 3D states of a 3-link chain with friction on the floor and a side wall, random sets of held
    contacts: the C solve (O(n) operators, LU of the non-symmetric system) against numpy with the reference
    model's dense I_f, R and point Jacobians."""
    data = {"name": "rough", "gravity": G,
            "links": [{"length": 1.0, "mu": 1.0}, {"length": 0.7, "mass": 1.3, "com": [0.3, 0.05, -0.02],
                                                   "inertia": [[0.01, 0.001, 0], [0.001, 0.05, 0.002], [0, 0.002, 0.055]],
                                                   "twist": 0.5},
                      {"length": 0.5, "mu": 2.0, "twist": -0.8}],
            "walls": {"x2_min": -5.0, "x1_min": -5.0, "x3_max": 5.0},
            "friction": {"x2_min": 0.7, "x1_min": 0.3}, "friction_velocity": 1e-3,
            "initial": {"q": [0.1, 0.2, 0.3, 0.4, 0.5, 0.0, 0.0, 0.0]}}
    scene = scene_from_dict(data)
    model = quick_model(scene, specialise=False)
    ref = reference_of(scene)
    rng = np.random.default_rng(3)
    contacts = model.contacts
    for trial in range(12):
        q = np.r_[rng.uniform(-1.2, 1.2, scene.n + 2), rng.uniform(-1, 1, 3)]
        qd = rng.uniform(-1, 1, scene.nq) * (1e-4 if trial == 0 else 1.0)      # trial 0: below v_s
        resting = sorted(rng.choice(len(contacts), size=rng.integers(1, 4), replace=False).tolist())
        points = {contacts[c][0] for c in resting}
        if len(points) < len(resting):
            continue                                   # one point on two walls: keep the sets simple
        qdd, lam = model.constrained_dynamics(q, qd, resting)

        M, R, J = ref.mass_matrix(q), ref.bias(q, qd), ref.point_jacobian(q)
        bias = model.contact_bias(q, qd)
        N, D = contact_directions(scene, contacts, resting, J, qd)
        rhs = [-contacts[c][1].normal_sign * bias[model.contact_rows.index((contacts[c][0], contacts[c][1].axis))]
               for c in resting]
        Minv_R, Minv_D = np.linalg.solve(M, R), np.linalg.solve(M, D.T)
        lam_ref = np.linalg.solve(N @ Minv_D, np.array(rhs) - N @ Minv_R)
        qdd_ref = Minv_R + Minv_D @ lam_ref
        assert np.abs(lam - lam_ref).max() < 1e-10 * max(1.0, np.abs(lam_ref).max())
        assert np.abs(qdd - qdd_ref).max() < 1e-10 * max(1.0, np.abs(qdd_ref).max())


def p_matrix(B, tol=1e-8):
    """B + B^T positive definite, or every principal minor above tol times its diagonal's scale (the library's rule)."""
    n = len(B)
    if np.linalg.eigvalsh(B + B.T).min() > 1e-8 * np.abs(np.diag(B + B.T)).max():
        return True
    for mask in range(1, 2 ** n):
        rows = [i for i in range(n) if mask >> i & 1]
        sub = B[np.ix_(rows, rows)]
        if not np.linalg.det(sub) > tol * np.prod([abs(sub[i, i]) or 1.0 for i in range(len(rows))]):
            return False
    return True


def test_the_painleve_guard_follows_the_p_matrix_rule():
    """Rough walls (c_f = 3) and random resting sets of a 3D chain: the C solve refuses exactly the states whose
    system B (formed here with the reference model) is no P-matrix, and solves the others."""
    from runtime.model import ImpactError
    data = {"name": "very_rough", "gravity": G,
            "links": [{"length": 1.0, "mu": 1.0}, {"length": 0.6, "mu": 0.5, "twist": 0.9},
                      {"length": 0.8, "mu": 1.5, "twist": -0.4}],
            "walls": {"x2_min": -5.0, "x1_min": -5.0, "x3_min": -5.0}, "friction": 3.0,
            "initial": {"q": [0.1, 0.2, 0.3, 0.4, 0.5, 0.0, 0.0, 0.0]}}
    scene = scene_from_dict(data)
    model = quick_model(scene, specialise=False)
    ref = reference_of(scene)
    rng = np.random.default_rng(11)
    contacts = model.contacts
    refused = accepted = 0
    for _ in range(60):
        q = np.r_[rng.uniform(-1.5, 1.5, scene.n + 2), rng.uniform(-1, 1, 3)]
        qd = rng.uniform(-2, 2, scene.nq)
        resting = sorted(rng.choice(len(contacts), size=rng.integers(1, 4), replace=False).tolist())
        if len({contacts[c][0] for c in resting}) < len(resting):
            continue
        M, J = ref.mass_matrix(q), ref.point_jacobian(q)
        N, D = contact_directions(scene, contacts, resting, J, qd)
        B = N @ np.linalg.solve(M, D.T)
        if p_matrix(B):
            model.constrained_dynamics(q, qd, resting)
            accepted += 1
        else:
            with pytest.raises(ImpactError, match="Painleve paradox"):
                model.constrained_dynamics(q, qd, resting)
            refused += 1
    assert refused >= 3 and accepted >= 10


def test_energy_balance_closes_with_impacts_and_sliding():
    """A chain thrown onto a rough floor (impacts with e = 0.3 and friction, then sliding and rolling to rest):
    initial energy = final + impact losses + friction loss, to the integration tolerance."""
    data = {"name": "rough_drop", "gravity": G, "links": [{"length": 1.0, "mu": 1.0, "count": 3}],
            "walls": {"x2_min": 0.0, "x1_min": -10.0, "x1_max": 10.0}, "restitution": 0.3, "friction": 0.6,
            "initial": {"q": [-math.pi / 2, 0.0, -1.2, 0.5, 0.4, 0.0, 1.0, 0.0],
                        "qd": [0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0]}}
    scene = scene_from_dict(data)
    result = simulate(quick_model(scene), 2.0, rtol=1e-10, atol=1e-12, t_eval=[])
    assert result.success, result.message
    assert result.impacts and result.loss_friction > 0.1                   # friction at the impacts took most
    assert any(impact.law == "gdi" and any(c.impulse_t != (0.0, 0.0) for c in impact.contacts)
               for impact in result.impacts)
    assert all(impact.energy_after <= impact.energy_before for impact in result.impacts)
    assert abs(result.energy_drift) < 1e-8


def test_scene_fields_are_checked_by_name():
    base = {"name": "x", "links": [{"length": 1.0, "mu": 1.0}], "walls": {"x2_min": -1.0},
            "initial": {"q": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]}}
    for friction, message in ((-0.1, "friction: the Coulomb coefficient must be in"),
                              ({"x2_min": "rough"}, "friction.x2_min"),
                              ({"x1_min": 0.5}, "friction.x1_min: there is no such wall")):
        with pytest.raises(SceneError, match=message):
            scene_from_dict({**base, "friction": friction})
    with pytest.raises(SceneError, match=r"friction_velocity: must be in \[1e-09, 1\] m/s"):
        scene_from_dict({**base, "friction": 0.5, "friction_velocity": 0.0})
    model = quick_model(scene_from_dict({**base, "friction": 0.5}))
    with pytest.raises(ValueError, match=r"p\[friction_x2_min\]: the Coulomb coefficient must be in \[0, 1000\]"):
        simulate(model, 0.1, p={"friction_x2_min": -1.0})


def test_frictionless_scenes_have_no_friction_rows():
    """Friction adds parameters and tangential rows only where a wall has it: the paper's scenes keep theirs."""
    scene = load_scene("paper-case1")
    model = quick_model(scene)
    assert not [name for name in scene.parameter_names() if name.startswith("friction_")]
    assert sorted(model.contact_rows) == sorted({(point, wall.axis) for point, wall in model.contacts})
    rough = rod(0.5)
    assert sorted(quick_model(rough).contact_rows) == [(1, 0), (1, 1), (2, 0), (2, 1)]      # planar: X1 tangent only
    assert sorted(quick_model(rough, specialise=False).contact_rows) == [(p, a) for p in (1, 2) for a in range(3)]


@pytest.mark.parametrize("c_f, v, paradox", [(2.0, -1.0, True), (2.0, 1.0, False), (1.0, -1.0, False)])
def test_the_painleve_paradox_is_named(c_f, v, paradox):
    """A uniform rod leaning at tan(theta) = 2 with its lower end sliding on a rough floor: its normal force obeys
    m B N = ..., m B = 1 + 3 cos(theta) (cos(theta) + c_f s sin(theta)) (s: the sliding direction's sign, towards the
    rod's lean +1), negative for s = -1 and c_f > 4/3 at this angle (Painleve): the constrained dynamics says so,
    and the run resolves it by a tangential impact at the start (tests/test_sim_painleve.py checks its impulses);
    otherwise it runs without one."""
    from runtime.model import ImpactError
    theta = math.atan(2.0)
    data = {"name": "painleve", "gravity": G, "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}],
            "walls": {"x2_min": 0.0}, "restitution": 0.0, "friction": c_f,
            "initial": {"q": [-math.pi / 2, 0.0, math.atan2(-math.cos(theta), math.sin(theta)), 1.0, 0.0, 0.0],
                        "qd": [0.0, 0.0, 0.0, v, 0.0, 0.0]}}
    model = quick_model(scene_from_dict(data))
    assert (1 + 3 * math.cos(theta) * (math.cos(theta) + c_f * math.copysign(1.0, v) * math.sin(theta)) < 0) == paradox
    result = simulate(model, 0.3, rtol=1e-10, atol=1e-12)
    assert result.success, result.message
    assert result.contact_events[0].kind == "rest"
    if paradox:
        with pytest.raises(ImpactError, match="Painleve paradox"):
            model.constrained_dynamics(model.q0, model.qd0, [0])
        assert result.n_tangential_impacts == 1 and "tangential impact" in result.message
        assert [(i.t, i.law) for i in result.impacts] == [(0.0, "gdi-tangential")]
    else:
        assert result.n_tangential_impacts == 0 and not result.impacts
