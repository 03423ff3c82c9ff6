"""The flight-phase equations I_f(Theta) Theta_ddot = R(Theta, Theta_dot) by the recursive
Gibbs-Appell route (paper Sect. 3.1-3.2).

The Gibbs function of link i (Eq. 3, with the typos of Eq. 2 and 8 corrected) is

    S_i = 1/2 B0 a.a - a^T B1 wd - a^T w~ B1 w + 1/2 wd^T (B2 + B3) wd + wd^T w~ (B2 + B3) w

with a = ^i r_ddot_{O_i}, w = ^i omega_i, wd = ^i omega_dot_i, so that

    dS/dq_ddot_j = sum_i  (da_i/dq_ddot_j) . (B0 a_i - B1 wd_i - w~_i B1 w_i)          (Eq. 8, 9)
                        + (dwd_i/dq_ddot_j) . (B1 a_i + (B2+B3) wd_i + w~_i (B2+B3) w_i)

(the paper prints wd instead of w in the last term of both brackets of Eq. 8).  The partial
derivatives are Eq. 21-23: dwd_i/dtheta_ddot_j = ^iR_j z, da_i/dtheta_ddot_j = (^iR_j z) x ^i r_{O_i/O_j},
da_i/dX_ddot_j = ^iR_ref X_j.

Right-hand side (Eq. 38-41).  With S_i, T_i of Eq. 39-40 and z_j . (r x S) = (z_j x r) . S,

    R_theta_j = - z_j . sum_{i >= j} (T_i + r_{O_i/O_j} x S_i) + Q_j,     R_X = - sum_i ^{ref}R_i S_i + Q_X,

with Q the generalised forces other than gravity (inputs, joint springs and dampers): by Eq. 10-11 the
Gibbs-Appell equations read dS/dq_ddot_j = Q_j, so Q adds to R as it is.

The sums over i >= j are accumulated from the tip (the change of summation order of
Eq. 31-36): F_j = S_j + ^jR_{j+1} F_{j+1},  N_j = T_j + ^jR_{j+1} N_{j+1} + r_j x ^jR_{j+1} F_{j+1}.

Inertia matrix (Eq. I, II, 24-30, 37).  The coefficient of theta_ddot_k in equation j sums, over
the links i >= max(j, k), the moments B0, B1, B2 + B3 transported to a common frame: the
matrices sigma (Eq. 24, the B2 + B3 part), psi, xi, gamma, U (Eq. 25-30, the B1 and B0 parts).
For k >= j all of them are moments of the sub-chain k..n about O_k, so they are accumulated
once from the tip as composite moments (B0^c_k, h^c_k, K^c_k), and column k of I_f is obtained
by carrying the unit-acceleration load of the sub-chain, (n, f) = (K^c_k z, z x h^c_k), down the
chain: row j <- z . n in frame j.  The translational block is M_tot I (Eq. II, 37) and the
X rows are ^{ref}R_{-1} f (Eq. 29-30).  Only the lower triangle is computed (I_f is symmetric).
"""
from __future__ import annotations

import sympy as sp

from .kinematics import ChainSymbols, LinkSymbols, Motion, link_offset, to_parent
from .tape import E_Z, ZERO, Tape, Vec, add, cross, index_name, matvec, scale


# ---------------------------------------------------------------------------
# right-hand side R (Eq. 38-41)
# ---------------------------------------------------------------------------
def link_loads(tape: Tape, moments: dict[int, LinkSymbols], motion: Motion, i: int) -> tuple[Vec, Vec]:
    """^i S_i and ^i T_i of Eq. 39-40 for real link i (with B1 v = h x v)."""
    B = moments[i]
    w, wd, a = motion.omega[i], motion.omega_dot_v[i], motion.acc_v[i]
    h, K = B.h, B.K
    # S = B0 a - B1 wd - w~ B1 w
    S = tape.let_vec(add(scale(B.B0, a), add(scale(-1, cross(h, wd)),
                                             scale(-1, cross(w, tape.let_vec(cross(h, w), f"hw_{i}"))))),
                     f"S_{i}")
    # T = B1 a + (B2 + B3) wd + w~ (B2 + B3) w
    Kw = tape.let_vec(matvec(K, w), f"Kw_{i}")
    T = tape.let_vec(add(cross(h, a), add(matvec(K, wd), cross(w, Kw))), f"T_{i}")
    return S, T


def right_hand_side(tape: Tape, chain: ChainSymbols, rotations, moments, motion: Motion) -> list[sp.Expr]:
    """R(Theta, Theta_dot) of Eq. 12, in the state order of Eq. 13/14."""
    n = chain.n
    R = [None] * chain.nq
    F = N = None   # load of links > k, in frame k + 1
    for k in range(n, -2, -1):
        tag = index_name(k)
        if k >= 1:
            S, T = link_loads(tape, moments, motion, k)
        else:
            S = T = (ZERO, ZERO, ZERO)
        if F is not None:
            F_parent = tape.let_vec(to_parent(rotations[k + 1], F), f"Fp_{tag}")
            N_parent = to_parent(rotations[k + 1], N)
            S = add(S, F_parent)
            T = add(T, add(N_parent, cross(link_offset(chain, moments, k), F_parent)))
        F, N = tape.let_vec(S, f"F_{tag}"), tape.let_vec(T, f"N_{tag}")
        R[k + 1] = -N[2] + chain.generalized_force(k + 1)              # Eq. 38 (+ Q_k, Eq. 10-11)
    F_ref = to_parent(rotations[-1], F)
    for a in range(3):
        R[n + 2 + a] = -F_ref[a] + chain.generalized_force(n + 2 + a)  # Eq. 41 (+ Q_X)
    return R


# ---------------------------------------------------------------------------
# inertia matrix I_f (Eq. I, II, 24-30, 37)
# ---------------------------------------------------------------------------
def composite_moments(tape: Tape, chain: ChainSymbols, rotations, moments):
    """B0^c_k, h^c_k, K^c_k: moments of links k..n about O_k in frame k, for k = -1..n."""
    mass, first, inertia = {}, {}, {}
    for k in range(chain.n, -2, -1):
        tag = index_name(k)
        own = moments.get(k)
        m = own.B0 if own else ZERO
        h = own.h if own else (ZERO, ZERO, ZERO)
        K = [list(row) for row in own.K] if own else [[ZERO] * 3 for _ in range(3)]
        if k < chain.n:
            R = rotations[k + 1]
            r = link_offset(chain, moments, k)
            m_out = mass[k + 1]
            h_out = tape.let_vec(matvec(R, first[k + 1]), f"hcd_{tag}")      # h^c_{k+1} in frame k
            K_out = _rotate_symmetric(R, inertia[k + 1])                  # R K^c_{k+1} R^T
            m = m + m_out
            h = add(h, add(h_out, scale(m_out, r)))
            # parallel axis from O_{k+1} to O_k (r = O_{k+1} - O_k):
            #   K += m (|r|^2 I - r r^T) + 2 (r.h) I - r h^T - h r^T
            rr, rh = r[0] ** 2 + r[1] ** 2 + r[2] ** 2, r[0] * h_out[0] + r[1] * h_out[1] + r[2] * h_out[2]
            for a in range(3):
                for b in range(a, 3):
                    shift = m_out * ((rr if a == b else 0) - r[a] * r[b]) \
                        + (2 * rh if a == b else 0) - r[a] * h_out[b] - h_out[a] * r[b]
                    K[a][b] = K[a][b] + K_out[a][b] + shift
        mass[k] = tape.let(m, f"Bc0_{tag}")
        first[k] = tape.let_vec(h, f"hc_{tag}")
        for a in range(3):
            for b in range(a, 3):
                K[a][b] = K[b][a] = tape.let(K[a][b], f"Kc_{tag}_{'xyz'[a]}{'xyz'[b]}")
        inertia[k] = tuple(tuple(row) for row in K)
    return mass, first, inertia


def _rotate_symmetric(R, K):
    """R K R^T for symmetric K (upper triangle computed, mirrored)."""
    RK = [[R[a][0] * K[0][b] + R[a][1] * K[1][b] + R[a][2] * K[2][b] for b in range(3)] for a in range(3)]
    out = [[None] * 3 for _ in range(3)]
    for a in range(3):
        for b in range(a, 3):
            out[a][b] = out[b][a] = RK[a][0] * R[b][0] + RK[a][1] * R[b][1] + RK[a][2] * R[b][2]
    return out


def inertia_matrix(tape: Tape, chain: ChainSymbols, rotations, moments) -> dict[tuple[int, int], sp.Expr]:
    """Lower triangle {(row, col): value} of I_f in the state order of Eq. 13."""
    n, nq = chain.n, chain.nq
    mass, first, inertia = composite_moments(tape, chain, rotations, moments)
    M = {}
    for k in range(-1, n + 1):                       # column of theta_ddot_k
        tag = index_name(k)
        col = k + 1
        h, K = first[k], inertia[k]
        nvec = (K[0][2], K[1][2], K[2][2])          # K^c_k z       (sigma, Eq. 24)
        fvec = cross(E_Z, h)                         # z x h^c_k     (xi, gamma, Eq. 27-30)
        M[(col, col)] = nvec[2]
        for j in range(k - 1, -2, -1):               # carry the load down to frame j
            R = rotations[j + 1]
            fvec = tape.let_vec(to_parent(R, fvec), f"f_{tag}_{index_name(j)}")
            nvec = add(to_parent(R, nvec), cross(link_offset(chain, moments, j), fvec))
            nvec = tape.let_vec(nvec, f"n_{tag}_{index_name(j)}")
            M[(col, j + 1)] = nvec[2]                # psi, U terms (Eq. 25-26)
        f_ref = to_parent(rotations[-1], fvec)
        for a in range(3):
            M[(n + 2 + a, col)] = tape.let(f_ref[a], f"M_X{a + 1}_{tag}")
    for a in range(3):                               # Eq. II: M_tot I
        for b in range(a + 1):
            M[(n + 2 + a, n + 2 + b)] = mass[-1] if a == b else ZERO
    lower = {}
    for (i, j), value in M.items():
        lower[(max(i, j), min(i, j))] = value
    assert len(lower) == nq * (nq + 1) // 2
    return lower
