"""The derived flight kernels against the independent numpy model (studies/reference.py): Jacobian-assembled
mass matrix and world-frame recursive Newton-Euler bias.  No C: the kernels' flattened programs run as Python
(tests/derived.py); test_build_kernels.py checks that the compiled C computes the same."""
import numpy as np
import pytest

from studies import reference
from conftest import chain, random_parameters, reference_of, tilted

# gravity along -X2, and tilted (gravity_direction a random unit vector) for the twisted chains of rigid links
CASES = [(n, twists, kinds, tilt) for n in range(1, 6) for twists, kinds, tilt in
         ((False, ("line",), False), (True, ("line",), False), (True, ("rigid", "line"), False),
          (True, ("rigid", "line"), True))]


def scene_of(n, kinds=("line",), twists=False, tilt=False):
    """chain(n, kinds, twists), with gravity along a random direction if ``tilt``."""
    scene = chain(n, kinds, twists)
    return tilted(scene, seed=n) if tilt else scene


def rel_err(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


@pytest.mark.parametrize("n,random_twists,kinds,tilt", CASES)
def test_inertia_matrix_and_rhs_match_reference(derived, n, random_twists, kinds, tilt):
    scene = scene_of(n, kinds, random_twists, tilt)
    model = derived(scene)
    rng = np.random.default_rng(n)
    for trial in range(4):
        p = random_parameters(scene, seed=100 * n + trial)
        ref = reference_of(scene, p)
        q, qd = reference.random_state(n, rng)
        assert rel_err(model.mass_matrix(q, p), ref.mass_matrix(q)) < 1e-10
        assert rel_err(model.bias(q, qd, p), ref.bias(q, qd)) < 1e-10
        assert rel_err(model.forward_dynamics(q, qd, p), ref.forward_dynamics(q, qd)) < 1e-9


@pytest.mark.parametrize("n", range(1, 7))
def test_inertia_matrix_is_symmetric_positive_definite(derived, n):
    scene = chain(n, ("line", "rigid"), twists=True)
    model = derived(scene)
    rng = np.random.default_rng(n)
    for trial in range(5):
        p = random_parameters(scene, seed=200 * n + trial)
        q, _ = reference.random_state(n, rng)
        M = model.mass_matrix(q, p)
        assert np.array_equal(M, M.T)
        assert np.linalg.eigvalsh(M).min() > 0
        # Eq. II: the translational block is M_tot I
        total_mass = reference_of(scene, p).m.sum()
        assert np.allclose(M[n + 2:, n + 2:], total_mass * np.eye(3), rtol=1e-14, atol=0)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_contact_kinematics(derived, n):
    """Points and velocities against the reference; Jacobian rows against finite differences."""
    scene = chain(n, twists=True)
    model = derived(scene)
    p = random_parameters(scene, seed=30 + n)
    ref = reference_of(scene, p)
    rng = np.random.default_rng(n)
    q, qd = reference.random_state(n, rng)
    assert rel_err(model.contact_points(q, p), ref.points(q)) < 1e-12
    assert rel_err(model.contact_velocities(q, qd, p), ref.point_velocities(q, qd)) < 1e-12
    J = model.contact_jacobian(q, p)
    h = 1e-6
    for col in range(scene.nq):
        dq = np.zeros(scene.nq)
        dq[col] = h
        diff = (model.contact_points(q + dq, p) - model.contact_points(q - dq, p)) / (2 * h)
        for row, (point, axis) in enumerate(model.contact_rows):
            assert abs(J[row, col] - diff[point - 1, axis]) < 1e-8
    # Eq. 42: J qd is the velocity of the points
    v = model.contact_velocities(q, qd, p)
    for row, (point, axis) in enumerate(model.contact_rows):
        assert abs(J[row] @ qd - v[point - 1, axis]) < 1e-12 * max(1, np.abs(v).max())


@pytest.mark.parametrize("tilt", [False, True])
@pytest.mark.parametrize("n", [1, 3])
def test_gaps_and_energy(derived, n, tilt):
    scene = scene_of(n, ("rigid", "line"), twists=True, tilt=tilt)
    model = derived(scene)
    rng = np.random.default_rng(n)
    for trial in range(3):
        p = random_parameters(scene, seed=40 * n + trial)
        ref = reference_of(scene, p)
        q, qd = reference.random_state(n, rng)
        points = ref.points(q)
        expected = [(points[pt - 1, w.axis] - w.position) * w.normal_sign for pt, w in scene.contacts()]
        assert np.allclose(model.contact_gaps(q, p), expected, rtol=1e-13, atol=1e-13)
        T, V = model.energy(q, qd, p)
        T_ref, V_ref = ref.energy(q, qd)
        assert abs(T - T_ref) < 1e-12 * abs(T_ref)
        assert abs(V - V_ref) < 1e-12 * (abs(V_ref) + 1)
        # the two paths of the model agree too: T = 1/2 qd' I_f qd
        assert abs(T - 0.5 * qd @ model.mass_matrix(q, p) @ qd) < 1e-12 * T
        # and the fused kernel the loop takes its energy from gives the same T, V and accelerations
        qdd, T_fused, V_fused = model.forward_dynamics_energy(q, qd, p)
        assert (T_fused, V_fused) == pytest.approx((T, V), rel=1e-13, abs=1e-13)
        assert rel_err(qdd, model.forward_dynamics(q, qd, p)) < 1e-12


@pytest.mark.parametrize("tilt", [False, True])
def test_gravity_is_minus_gradient_of_potential(derived, tilt):
    scene = scene_of(3, twists=True, tilt=tilt)
    model = derived(scene)
    q, _ = reference.random_state(3, np.random.default_rng(5))
    zero = np.zeros(scene.nq)
    h = 1e-6
    grad = np.array([(model.energy(q + h * e, zero)[1] - model.energy(q - h * e, zero)[1]) / (2 * h)
                     for e in np.eye(scene.nq)])
    assert np.allclose(model.bias(q, zero), -grad, rtol=1e-7, atol=1e-7)
