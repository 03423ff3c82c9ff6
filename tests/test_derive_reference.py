"""Self-consistency tests of the reference model in studies/reference.py.

Each test checks one physical property through a code path different from the
one that produced the quantity, so that a convention slip in reference.py
shows up as a failure.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from studies.reference import (
    ReferenceChain,
    Rx,
    Ry,
    Rz,
    default_twists,
    line_link,
    random_chain,
    random_state,
    rigid_link,
    skew,
)

N_VALUES = [1, 2, 3, 5]


def tilt(chain, rng):
    """The chain with gravity along a random unit vector d (ReferenceChain.up = -d) instead of -X2."""
    d = rng.normal(size=3)
    chain.up = -d / np.linalg.norm(d)
    return chain


def central_gradient(f, x, eps=1e-6):
    """Central finite-difference gradient of the scalar function f at x."""
    x = np.asarray(x, dtype=float)
    grad = np.zeros_like(x)
    for j in range(len(x)):
        dx = np.zeros_like(x)
        dx[j] = eps
        grad[j] = (f(x + dx) - f(x - dx)) / (2 * eps)
    return grad


# ---------------------------------------------------------------------------
# 7. Base orientation convention
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("n", N_VALUES)
def test_R1_is_yaw_pitch_roll(n):
    """With the default twists, R_1 = Ry(th_{-1}) Rz(th_0) Rx(th_1) T_1."""
    rng = np.random.default_rng(700 + n)
    chain = random_chain(n, rng)
    T_1 = default_twists(n)[2]
    for _ in range(5):
        q, _ = random_state(n, rng)
        expected = Ry(q[0]) @ Rz(q[1]) @ Rx(q[2]) @ T_1
        np.testing.assert_allclose(chain.frames(q)[2], expected, atol=1e-14)
        # and link 1 points along X2 when all angles vanish
        np.testing.assert_allclose(chain.frames(np.zeros(n + 5))[2][:, 0], [0, 1, 0], atol=1e-15)


# ---------------------------------------------------------------------------
# 1. Mass matrix
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("random_twists", [False, True])
@pytest.mark.parametrize("n", N_VALUES)
def test_mass_matrix_spd_and_kinetic_energy(n, random_twists):
    """M is symmetric positive definite and 1/2 qd.M.qd equals T from energy()."""
    rng = np.random.default_rng(100 + n)
    chain = random_chain(n, rng, random_twists)
    for _ in range(5):
        q, qd = random_state(n, rng)
        M = chain.mass_matrix(q)
        np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-13 * np.abs(M).max())
        assert np.linalg.eigvalsh(M).min() > 0
        T, _ = chain.energy(q, qd)
        assert T > 0
        np.testing.assert_allclose(0.5 * qd @ M @ qd, T, rtol=1e-12)


@pytest.mark.parametrize("n", N_VALUES)
def test_inverse_dynamics_is_affine_in_qdd_with_slope_M(n):
    """ID(q, qd, qdd) - ID(q, qd, 0) = M qdd: Newton-Euler agrees with the Jacobians."""
    rng = np.random.default_rng(150 + n)
    chain = random_chain(n, rng, random_twists=True)
    q, qd = random_state(n, rng)
    qdd = rng.normal(size=n + 5)
    lhs = chain.inverse_dynamics(q, qd, qdd) - chain.inverse_dynamics(q, qd, np.zeros(n + 5))
    np.testing.assert_allclose(lhs, chain.mass_matrix(q) @ qdd, rtol=1e-11, atol=1e-11 * np.abs(lhs).max())


# ---------------------------------------------------------------------------
# 2. Gravity
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("tilted", [False, True])
@pytest.mark.parametrize("n", N_VALUES)
def test_gravity_is_minus_gradient_of_potential(n, tilted):
    """R(q, 0) = -dV/dq."""
    rng = np.random.default_rng(200 + n)
    chain = random_chain(n, rng, random_twists=True)
    if tilted:
        chain = tilt(chain, rng)
    for _ in range(3):
        q, _ = random_state(n, rng)
        dV = central_gradient(lambda x: chain.energy(x, np.zeros(n + 5))[1], q)
        R = chain.bias(q, np.zeros(n + 5))
        np.testing.assert_allclose(R, -dV, rtol=1e-6, atol=1e-6 * np.abs(dV).max())
        # the X components are the total weight, along d = -up (-X2 by default)
        np.testing.assert_allclose(R[n + 2:], -chain.g * chain.m.sum() * chain.up, rtol=1e-12,
                                   atol=1e-12 * chain.g * chain.m.sum())


# ---------------------------------------------------------------------------
# 3. Energy conservation
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("n", N_VALUES)
def test_power_balance(n):
    """Along qdd = M^{-1} R the total energy is constant: dE/dt = 0."""
    rng = np.random.default_rng(300 + n)
    chain = random_chain(n, rng, random_twists=True)
    N = n + 5
    for _ in range(3):
        q, qd = random_state(n, rng)
        qdd = chain.forward_dynamics(q, qd)
        E_of_q = lambda x: sum(chain.energy(x, qd))
        E_of_qd = lambda x: sum(chain.energy(q, x))
        terms = np.concatenate([central_gradient(E_of_q, q) * qd,
                                central_gradient(E_of_qd, qd) * qdd])
        assert len(terms) == 2 * N
        assert abs(terms.sum()) < 1e-6 * np.abs(terms).sum()


@pytest.mark.parametrize("n", [1, 3])
def test_power_balance_fails_for_wrong_dynamics(n):
    """Sanity check that the power-balance test can fail: drop the velocity terms."""
    rng = np.random.default_rng(350 + n)
    chain = random_chain(n, rng, random_twists=True)
    q, qd = random_state(n, rng)
    wrong_qdd = np.linalg.solve(chain.mass_matrix(q), chain.bias(q, np.zeros(n + 5)))
    terms = np.concatenate([central_gradient(lambda x: sum(chain.energy(x, qd)), q) * qd,
                            central_gradient(lambda x: sum(chain.energy(q, x)), qd) * wrong_qdd])
    assert abs(terms.sum()) > 1e-3 * np.abs(terms).sum()


# ---------------------------------------------------------------------------
# 4. Symbolic Lagrangian cross-check
# ---------------------------------------------------------------------------

def sym_Rz(a):
    return sp.Matrix([[sp.cos(a), -sp.sin(a), 0], [sp.sin(a), sp.cos(a), 0], [0, 0, 1]])


def sym_constant(A):
    """Constant numpy matrix as a sympy Matrix, with round-off zeros made exact."""
    A = np.where(np.abs(A) < 1e-14, 0.0, A)
    return sp.Matrix(A.tolist())


def lagrangian_equations(chain):
    """Lambdified M(q) and R(q, qd) from the Euler-Lagrange equations.

    T and V are built with sympy from the frame definitions; the velocity of
    O_i is the symbolic time derivative of its position and the angular
    velocity of link i is sum_{k<=i} z_k thd_k (checked independently in
    test_angular_velocity_matches_frame_derivative).  With L = T - V,
        d/dt(dT/dqd) - dT/dq + dV/dq = 0,  i.e.
        M = d2T/dqd2,   R = dT/dq - (d/dq (dT/dqd)) qd - dV/dq.
    To keep this fast, only the angles are differentiated in q (T does not
    contain X) and the symmetry of M is used.
    """
    n, N = chain.n, chain.N
    q = sp.Matrix(sp.symbols(f"q0:{N}"))
    qd = sp.Matrix(sp.symbols(f"qd0:{N}"))
    angles = list(q[: n + 2])
    X = q[n + 2:, 0]

    # frames R_{-1}..R_n (list index k + 1)
    R = sym_constant(chain.T[0]) * sym_Rz(q[0])
    frames = [R]
    for k in range(0, n + 1):
        R = R * sym_constant(chain.T[k + 1]) * sym_Rz(q[k + 1])
        frames.append(R)

    T = sp.Integer(0)
    V = sp.Integer(0)
    O = X  # origin of link i
    w = frames[0][:, 2] * qd[0] + frames[1][:, 2] * qd[1]  # imaginary links
    for i in range(1, n + 1):
        R = frames[i + 1]
        v = O.jacobian(q) * qd  # dO_i/dt
        w = w + R[:, 2] * qd[i + 1]  # angular velocity of link i
        w_link = R.T * w  # ... in link-frame components
        m, h, K = chain.m[i - 1], sp.Matrix(chain.h[i - 1]), sym_constant(chain.K[i - 1])
        h_w = R * h
        T += m * v.dot(v) / 2 + v.dot(w.cross(h_w)) + (w_link.T * K * w_link)[0, 0] / 2
        V += chain.g * (m * O + h_w).dot(sp.Matrix(chain.up))
        O = O + chain.l[i - 1] * R[:, 0]

    p = [T.diff(x) for x in qd]  # generalised momenta dT/dqd
    M = sp.zeros(N, N)
    for a in range(N):
        for b in range(a, N):
            M[a, b] = M[b, a] = p[a].diff(qd[b])
    rhs = []
    for a in range(N):
        r_a = -V.diff(q[a])
        if a < n + 2:
            r_a += T.diff(q[a])
        for j, angle in enumerate(angles):
            r_a -= p[a].diff(angle) * qd[j]
        rhs.append(r_a)

    M_fun = sp.lambdify([q, qd], M, modules="numpy", cse=True)
    R_fun = sp.lambdify([q, qd], rhs, modules="numpy", cse=True)
    return (lambda qv: np.array(M_fun(qv, np.zeros(N)), dtype=float),
            lambda qv, qdv: np.array(R_fun(qv, qdv), dtype=float).ravel())


@pytest.mark.parametrize("n, random_twists, tilted", [(1, False, False), (2, True, False), (2, True, True)])
def test_against_symbolic_lagrangian(n, random_twists, tilted):
    """Jacobian-assembled M and Newton-Euler R equal the Euler-Lagrange ones (gravity along -X2, or tilted)."""
    rng = np.random.default_rng(400 + n)
    chain = random_chain(n, rng, random_twists)
    if tilted:
        chain = tilt(chain, rng)
    M_sym, R_sym = lagrangian_equations(chain)
    for _ in range(3):
        q, qd = random_state(n, rng)
        M = chain.mass_matrix(q)
        R = chain.bias(q, qd)
        np.testing.assert_allclose(M, M_sym(q), rtol=1e-10, atol=1e-10 * np.abs(M).max())
        np.testing.assert_allclose(R, R_sym(q, qd), rtol=1e-10, atol=1e-10 * np.abs(R).max())


def test_line_link_rod_matches_symbolic_lagrangian():
    """The paper's rod model (line_link) goes through the same check."""
    rng = np.random.default_rng(450)
    chain = ReferenceChain([line_link(1.3, 0.8, (0.01, 0.02, 0.03))], default_twists(1), 9.81)
    M_sym, R_sym = lagrangian_equations(chain)
    q, qd = random_state(1, rng)
    np.testing.assert_allclose(chain.mass_matrix(q), M_sym(q), rtol=1e-10, atol=1e-12)
    R = chain.bias(q, qd)
    np.testing.assert_allclose(R, R_sym(q, qd), rtol=1e-10, atol=1e-10 * np.abs(R).max())


def test_line_link_against_rigid_link():
    """A thin rod built by hand with the parallel-axis theorem equals line_link."""
    l, mu, J = 1.7, 0.6, np.array([0.01, 0.02, 0.03])
    m = mu * l
    I_com = np.diag([0.0, m * l ** 2 / 12, m * l ** 2 / 12]) + l * np.diag(J)
    for a, b in zip(line_link(l, mu, J), rigid_link(l, m, [l / 2, 0, 0], I_com)):
        np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-15)


# ---------------------------------------------------------------------------
# 5. Point Jacobian
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("n", N_VALUES)
def test_point_jacobian_matches_finite_differences(n):
    rng = np.random.default_rng(500 + n)
    chain = random_chain(n, rng, random_twists=True)
    q, qd = random_state(n, rng)
    J = chain.point_jacobian(q)
    assert J.shape == (n + 1, 3, n + 5)
    eps = 1e-6
    for j in range(n + 5):
        dq = np.zeros(n + 5)
        dq[j] = eps
        fd = (chain.points(q + dq) - chain.points(q - dq)) / (2 * eps)
        np.testing.assert_allclose(J[:, :, j], fd, rtol=0, atol=1e-8)
    # the recursive point velocities agree with the Jacobian
    np.testing.assert_allclose(chain.point_velocities(q, qd), J @ qd, atol=1e-12)
    # the links have their lengths
    lengths = np.linalg.norm(np.diff(chain.points(q), axis=0), axis=1)
    np.testing.assert_allclose(lengths, chain.l, rtol=1e-14)


@pytest.mark.parametrize("n", N_VALUES)
def test_angular_velocity_matches_frame_derivative(n):
    """w_k = sum_{j<=k} z_j thd_j equals vee(Rdot_k R_k^T), Rdot by finite differences."""
    rng = np.random.default_rng(550 + n)
    chain = random_chain(n, rng, random_twists=True)
    q, qd = random_state(n, rng)
    eps = 1e-6
    w, _ = chain.velocities(q, qd)
    frames, ahead, behind = chain.frames(q), chain.frames(q + eps * qd), chain.frames(q - eps * qd)
    for k in range(-1, n + 1):
        Rdot = (ahead[k + 1] - behind[k + 1]) / (2 * eps)
        W = Rdot @ frames[k + 1].T
        np.testing.assert_allclose(W, -W.T, atol=1e-8)
        np.testing.assert_allclose(W, skew(w[k + 1]), atol=1e-8)


# ---------------------------------------------------------------------------
# 6. Momentum conservation without gravity
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("n", [1, 2, 4])
def test_linear_momentum_conserved_without_gravity(n):
    rng = np.random.default_rng(600 + n)
    chain = random_chain(n, rng, random_twists=True)
    chain.g = 0.0
    q0, qd0 = random_state(n, rng)
    N = n + 5

    def rhs(t, y):
        q, qd = y[:N], y[N:]
        return np.concatenate([qd, chain.forward_dynamics(q, qd)])

    sol = solve_ivp(rhs, (0.0, 0.5), np.concatenate([q0, qd0]), method="DOP853",
                    rtol=1e-12, atol=1e-12, dense_output=False, t_eval=np.linspace(0, 0.5, 6))
    assert sol.success
    p0 = chain.linear_momentum(q0, qd0)
    scale = np.linalg.norm(p0)
    for y in sol.y.T[1:]:
        p = chain.linear_momentum(y[:N], y[N:])
        assert np.linalg.norm(p - p0) < 1e-9 * scale
    # and the energy too, as a bonus
    T0 = chain.energy(q0, qd0)[0]
    T1 = chain.energy(sol.y[:N, -1], sol.y[N:, -1])[0]
    assert T1 == pytest.approx(T0, rel=1e-9)
    # the base did move, so the check is not vacuous
    assert np.linalg.norm(sol.y[:N, -1] - q0) > 1e-2


def test_momentum_check_would_catch_gravity():
    """With gravity the momentum does change (the momentum test can fail)."""
    rng = np.random.default_rng(650)
    chain = random_chain(2, rng)
    chain.g = 9.81
    q, qd = random_state(2, rng)
    # dp/dt = total external force = -g sum m e2
    eps = 1e-6
    qdd = chain.forward_dynamics(q, qd)
    dp = (chain.linear_momentum(q + eps * qd, qd + eps * qdd)
          - chain.linear_momentum(q - eps * qd, qd - eps * qdd)) / (2 * eps)
    np.testing.assert_allclose(dp, [0, -9.81 * chain.m.sum(), 0], atol=1e-5)
