"""O(n) solve of I_f Theta_ddot = R by an articulated-body recursion (I_f is never formed).

The right-hand side R comes from the Gibbs-Appell recursion (gibbs_appell.right_hand_side: it
already holds gravity and every velocity product).  What is left is a linear solve with the
inertia matrix, and for a chain that solve has the recursive form of Featherstone's
articulated-body algorithm run with zero velocity and zero gravity and the joint forces tau = R
(R. Featherstone, Rigid Body Dynamics Algorithms, Springer 2008, Sect. 7.3): the recursion
factors I_f from the tip to the base, one joint pivot D_k at a time, at O(n) cost.

Spatial quantities of frame k are taken at O_k and written in frame k as pairs of 3-vectors:
    motion  (alpha, a)   angular and linear acceleration of the point O_k,
    force   (N, F)       moment about O_k and force,
    inertia (A, B, C)    f = [[A, B], [B^T, C]] m, with A, C symmetric; a rigid link with the
                         moments of Eq. 4-7 about O_k has A = B2 + B3, B = B1 = skew(h), C = B0 I.
Joint k turns frame k about its z axis; the motion subspace is s = (z, 0), so U = I^A s is the
third column and the pivot D = A_zz.  After the pivot is taken out (I^a = I^A - U U^T / D) the z
row and column of the angular block are exactly zero; they are set to zero, not computed.

Structure exploited (all by exact zeros that sympy carries through the tape): the massless,
zero-length imaginary links -1 and 0 add no inertia and no offset, so their transforms are
rotations only; offsets are along x (^k r = l_k x); the rotation ^{k-1}R_k = T_k Rz(theta_k) is
applied as an exact Rz then the constant twist T_k (free when T_k is a permutation or identity);
with parallel joint axes and links symmetric about their plane, the in-plane and out-of-plane
blocks of every articulated inertia stay uncoupled, so half of the 6 x 6 entries are zeros.
The three translations X are the root joint: their 3 x 3 block (M_tot I in I_f, Eq. II) becomes
the articulated 3 x 3 block of the whole chain, solved by a small straight-line LDL^T.
Coordinates a specialised layout holds fixed are locked joints: no pivot, Theta_ddot = 0.
"""
from __future__ import annotations

import sympy as sp

from . import gibbs_appell
from .kinematics import ChainSymbols, LinkSymbols, Motion, link_offset
from .linalg import ldlt_solve
from .tape import ZERO, Tape, Vec, Mat, add, cross, index_name, matvec, mat_t_vec, transpose

ZERO3 = (ZERO, ZERO, ZERO)
ZERO33 = (ZERO3, ZERO3, ZERO3)


# --- small helpers on 3x3 blocks -----------------------------------------------------------------
def _skew(v: Vec) -> Mat:
    """skew(v) w = v x w."""
    return ((ZERO, -v[2], v[1]), (v[2], ZERO, -v[0]), (-v[1], v[0], ZERO))


def _mm(P: Mat, Q: Mat) -> Mat:
    return tuple(tuple(P[i][0] * Q[0][j] + P[i][1] * Q[1][j] + P[i][2] * Q[2][j] for j in range(3))
                 for i in range(3))


def _madd(P: Mat, Q: Mat) -> Mat:
    return tuple(tuple(P[i][j] + Q[i][j] for j in range(3)) for i in range(3))


def _let_sym(tape: Tape, S, name: str) -> Mat:
    """Let the upper triangle of a symmetric matrix and mirror it."""
    out = [[None] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            out[i][j] = out[j][i] = tape.let(S[i][j], f"{name}_{i}{j}")
    return tuple(tuple(row) for row in out)


def _rotate(P: Mat, Q: Mat, symmetric: bool) -> Mat:
    """P Q P^T (for a symmetric Q only the upper triangle is formed, then mirrored)."""
    PQ = _mm(P, Q)
    out = [[None] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i if symmetric else 0, 3):
            value = PQ[i][0] * P[j][0] + PQ[i][1] * P[j][1] + PQ[i][2] * P[j][2]
            out[i][j] = value
            if symmetric:
                out[j][i] = value
    return tuple(tuple(row) for row in out)


def _is_identity(T: Mat) -> bool:
    return all(T[i][j] == (1 if i == j else 0) for i in range(3) for j in range(3))


# --- the transform between a frame and its parent ------------------------------------------------
class JointTransform:
    """^{k-1}R_k = T_k Rz(theta_k) and the offset ^{k-1}r = O_k - O_{k-1}, applied piecewise."""

    def __init__(self, tape: Tape, chain: ChainSymbols, moments: dict[int, LinkSymbols], k: int, cs=None):
        """``cs``: (cos theta_k, sin theta_k) when already known (default: formed on the tape, the same symbols
        as joint_rotations')."""
        theta = chain.theta(k)
        if cs is None:
            cs = (tape.let(sp.cos(theta), f"c_{index_name(k)}"), tape.let(sp.sin(theta), f"s_{index_name(k)}"))
        self.c, self.s = cs
        c, s = self.c, self.s
        self.Rz = ((c, -s, ZERO), (s, c, ZERO), (ZERO, ZERO, sp.Integer(1)))
        self.T = chain.twists[k + 1]
        self.twisted = not _is_identity(self.T)
        self.r = link_offset(chain, moments, k - 1) if k >= 0 else ZERO3
        self.tag = index_name(k)

    def vec_to_parent(self, v: Vec) -> Vec:
        """A vector of frame k in frame k - 1."""
        v = matvec(self.Rz, v)
        return matvec(self.T, v) if self.twisted else v

    def vec_to_child(self, v: Vec) -> Vec:
        """A vector of frame k - 1 in frame k."""
        if self.twisted:
            v = mat_t_vec(self.T, v)
        return mat_t_vec(self.Rz, v)

    def rotate_z_symmetric(self, tape: Tape, M: Mat) -> Mat:
        """Rz M Rz^T for a symmetric M by the double angle: the xy block turns by 2 theta,
            M'xx = Mxx - m,  M'yy = Myy + m,  M'xy = d s c + Mxy (1 - 2 s^2),  d = Mxx - Myy,
            m = d s^2 + 2 s c Mxy,
        the xz, yz column as a vector, zz unchanged: 9 operations for the block instead of 21 (s^2 and s c
        are shared by every matrix of the joint)."""
        c, s = self.c, self.s
        if not hasattr(self, "_ss"):
            self._ss = tape.let(s * s, f"ss_{self.tag}")
            self._sc = tape.let(s * c, f"sc_{self.tag}")
            self._c2 = tape.let(1 - 2 * self._ss, f"c2_{self.tag}")
        d = M[0][0] - M[1][1]
        m = d * self._ss + 2 * self._sc * M[0][1]
        xx, yy, xy = M[0][0] - m, M[1][1] + m, d * self._sc + M[0][1] * self._c2
        xz, yz = c * M[0][2] - s * M[1][2], s * M[0][2] + c * M[1][2]
        return ((xx, xy, xz), (xy, yy, yz), (xz, yz, M[2][2]))

    def inertia_to_parent(self, tape: Tape, inertia) -> tuple[Mat, Mat, Mat]:
        """(A, B, C) about O_k in frame k -> about O_{k-1} in frame k - 1."""
        A, B, C = inertia
        tag = self.tag
        A, B, C = (_let_sym(tape, self.rotate_z_symmetric(tape, A), f"IzA_{tag}"),
                   tape.let_mat(_rotate(self.Rz, B, False), f"IzB_{tag}"),
                   _let_sym(tape, self.rotate_z_symmetric(tape, C), f"IzC_{tag}"))
        if self.twisted:
            A, B, C = (_let_sym(tape, _rotate(self.T, A, True), f"ItA_{tag}"),
                       tape.let_mat(_rotate(self.T, B, False), f"ItB_{tag}"),
                       _let_sym(tape, _rotate(self.T, C, True), f"ItC_{tag}"))
        if any(x != 0 for x in self.r):
            # shift the reference point by r:  A' = A + Sr B^T - B Sr - Sr C Sr,  B' = B + Sr C
            Sr = _skew(self.r)
            SrC = _mm(Sr, C)
            B_new = tape.let_mat(_madd(B, SrC), f"IsB_{tag}")
            SrBt = _mm(Sr, transpose(B))
            A_new = [[None] * 3 for _ in range(3)]
            for i in range(3):
                for j in range(i, 3):
                    # Sr B^T - B Sr = Sr B^T + (Sr B^T)^T;  Sr C Sr = -Sr C Sr^T
                    value = A[i][j] + SrBt[i][j] + SrBt[j][i] + sum(SrC[i][m] * Sr[j][m] for m in range(3))
                    A_new[i][j] = A_new[j][i] = value
            A = _let_sym(tape, A_new, f"IsA_{tag}")
            B = B_new
        return A, B, C

    def force_to_parent(self, tape: Tape, force) -> tuple[Vec, Vec]:
        """(N, F) about O_k in frame k -> about O_{k-1} in frame k - 1."""
        N, F = force
        F = tape.let_vec(self.vec_to_parent(F), f"pF_{self.tag}")
        N = self.vec_to_parent(N)
        if any(x != 0 for x in self.r):
            N = add(N, cross(self.r, F))
        return tape.let_vec(N, f"pN_{self.tag}"), F

    def motion_to_child(self, tape: Tape, motion) -> tuple[Vec, Vec]:
        """(alpha, a) of O_{k-1} in frame k - 1 -> of O_k in frame k (rigid transport)."""
        alpha, a = motion
        if any(x != 0 for x in self.r):
            a = add(a, cross(alpha, self.r))
        return (tape.let_vec(self.vec_to_child(alpha), f"alpha_{self.tag}"),
                tape.let_vec(self.vec_to_child(a), f"acc_{self.tag}"))


# --- the recursion --------------------------------------------------------------------------------
def _own_inertia(moments: dict[int, LinkSymbols], k: int):
    """(A, B, C) of real link k about O_k (Eq. 4-7); zero for the imaginary links."""
    if k < 1:
        return ZERO33, ZERO33, ZERO33
    B = moments[k]
    m = B.B0
    return B.K, _skew(B.h), ((m, ZERO, ZERO), (ZERO, m, ZERO), (ZERO, ZERO, m))


def _add_inertia(P, Q):
    return tuple(_madd(x, y) for x, y in zip(P, Q))


def _pivot(tape: Tape, inertia, force, tag: str, tau=ZERO):
    """Take joint k's pivot out: U = I s, D = s^T U, u = tau - s^T p with tau the joint's generalised force
    Q_k (inputs, spring, damper; every other load is in p);
    returns the reduced inertia and force handed to the parent, and (W = U / D, u / D) for the
    forward pass."""
    A, B, C = inertia
    N, F = force
    U = (A[0][2], A[1][2], A[2][2], B[2][0], B[2][1], B[2][2])
    Dinv = tape.let(1 / A[2][2], f"Dinv_{tag}")
    W = tuple(sp.Integer(1) if i == 2 else tape.let(x * Dinv, f"W_{tag}_{i}") for i, x in enumerate(U))
    u = tau - N[2]                                                 # = R_k of Eq. 38
    ud = tape.let(u * Dinv, f"ud_{tag}")
    # I^a = I - W U^T; its angular z row and column vanish exactly
    A_red = [[ZERO] * 3 for _ in range(3)]
    for i in range(2):
        for j in range(i, 2):
            A_red[i][j] = A_red[j][i] = A[i][j] - W[i] * U[j]
    B_red = [[ZERO] * 3 for _ in range(3)]
    for i in range(2):
        for j in range(3):
            B_red[i][j] = B[i][j] - W[i] * U[3 + j]
    C_red = [[None] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            C_red[i][j] = C_red[j][i] = C[i][j] - W[3 + i] * U[3 + j]
    inertia = (_let_sym(tape, A_red, f"IaA_{tag}"), tape.let_mat(B_red, f"IaB_{tag}"),
               _let_sym(tape, C_red, f"IaC_{tag}"))
    # p^a = p + W u; its z moment becomes N_z + u = tau exactly (0 for a joint with no generalised force)
    N_red = (N[0] + W[0] * u, N[1] + W[1] * u, tau)
    F_red = tuple(F[i] + W[3 + i] * u for i in range(3))
    force = (tape.let_vec(N_red, f"paN_{tag}"), tape.let_vec(F_red, f"paF_{tag}"))
    return inertia, force, W, ud


def forward_dynamics(tape: Tape, chain: ChainSymbols, moments: dict[int, LinkSymbols],
                     motion: Motion) -> list[sp.Expr]:
    """Theta_ddot (full layout of Eq. 13; 0 for fixed coordinates) solving I_f Theta_ddot = R.

    R is not formed on its own: the loads (S_k, T_k) of Eq. 39-40 (inertia of link k under the
    velocity-product accelerations, gravity included) are the bias forces of the recursion, and
    their accumulation from the tip (Eq. 38-41) is the same pass that accumulates the inertias.
    """
    def loads(k):
        S, T = gibbs_appell.link_loads(tape, moments, motion, k)
        return T, S
    return _solve(tape, chain, moments, loads, chain.generalized_force)


def inertia_solve(tape: Tape, chain: ChainSymbols, moments: dict[int, LinkSymbols], Q: list) -> list[sp.Expr]:
    """I_f^-1 Q (full layout) for generalised forces Q (full layout, 0 on fixed coordinates): the same
    recursion with no motion, no gravity and no loads on the links, only the joint forces Q."""
    return _solve(tape, chain, moments, None, lambda index: Q[index])


def _solve(tape: Tape, chain: ChainSymbols, moments: dict[int, LinkSymbols], loads, force) -> list[sp.Expr]:
    """The articulated-body recursion for I_f x = Q(loads, force): ``loads(k)`` gives the bias load (moment,
    force) of real link k about O_k in frame k (None: no loads), ``force(index)`` the generalised force on
    coordinate ``index`` of the full layout.  Returns x in the full layout (0 for fixed coordinates)."""
    n = chain.n
    free = set(chain.layout.free)
    joints = {k: JointTransform(tape, chain, moments, k) for k in range(-1, n + 1)}
    pivots = {}
    child = None                    # articulated inertia and force of links > k, about O_{k+1} in frame k + 1
    for k in range(n, -2, -1):      # backward: tip to base
        load = loads(k) if (k >= 1 and loads is not None) else None
        child, pivots[k] = backward_step(tape, moments, joints.get(k + 1), k, child, load,
                                         force(k + 1) if k + 1 in free else None)
    qdd = [ZERO] * chain.nq
    inertia, force_k = child
    X_ddot = _root_translations(tape, chain, joints[-1], inertia, force_k, free, force)
    for a in range(3):
        qdd[n + 2 + a] = X_ddot[a]
    motion = (ZERO3, X_ddot)        # of the reference frame at O_1
    for k in range(-1, n + 1):      # forward: base to tip
        motion, value = forward_step(tape, joints[k], pivots[k], motion, k)
        if value is not None:
            qdd[k + 1] = value
    return qdd


def backward_step(tape: Tape, moments: dict[int, LinkSymbols], joint: JointTransform | None, k: int, child,
                  load, tau):
    """One step of the backward pass at frame k: link k's own inertia (Eq. 4-7) and bias load ``load`` (moment,
    force; None: none) plus ``child`` (articulated inertia and force of links > k in frame k + 1, carried to O_k
    by ``joint`` = joint k + 1; None at the tip); then joint k's pivot with generalised force ``tau`` (None: a
    locked joint, which passes everything on).  Returns ((inertia, force) of links >= k with the pivot taken
    out, in frame k) and the pivot (W, u / D) or None."""
    I_k = _own_inertia(moments, k)
    p_k = (load[0], load[1]) if load is not None else (ZERO3, ZERO3)
    if child is not None:
        I_k = _add_inertia(I_k, joint.inertia_to_parent(tape, child[0]))
        N_parent, F_parent = joint.force_to_parent(tape, child[1])
        p_k = (add(p_k[0], N_parent), add(p_k[1], F_parent))
    if tau is None:
        return (I_k, p_k), None
    inertia, force_k, W, ud = _pivot(tape, I_k, p_k, index_name(k), tau)
    return (inertia, force_k), (W, ud)


def forward_step(tape: Tape, joint: JointTransform, pivot, motion, k: int):
    """One step of the forward pass: the motion (alpha, a) of O_{k-1} in frame k - 1 carried to O_k in frame
    k by ``joint`` = joint k, then joint k's acceleration from its pivot (W, u / D) (None: locked, 0).
    Returns the motion of frame k and theta_ddot_k (None when locked)."""
    alpha, acc = joint.motion_to_child(tape, motion)
    if pivot is None:
        return (alpha, acc), None
    W, ud = pivot
    value = tape.let(ud - sum((w * m for w, m in zip(W, alpha + acc)), ZERO), f"qdd_{index_name(k)}")
    return ((alpha[0], alpha[1], alpha[2] + value), acc), value


def _root_translations(tape: Tape, chain: ChainSymbols, joint: JointTransform, inertia, force, free, generalized):
    """X_ddot (reference frame) from the articulated 3 x 3 block of the whole chain at O_1.

    With the chain's articulated inertia (A, B, C) and force (N, F) in frame -1, the translation
    rows of I_f Theta_ddot = R read  ^{ref}R_{-1} (C y + F) = Q_X  with y = ^{-1}X_ddot (Eq. 41),
    Q_X the inputs acting on X1..X3 (reference frame).
    """
    n = chain.n
    _, _, C = inertia
    _, F = force
    Q_X = tuple(generalized(n + 2 + a) for a in range(3))
    if any(x != 0 for x in Q_X):                    # C y = R_{-1}^T Q_X - F
        F = tuple(tape.let(f - q, f"FQ_{a}") for a, (f, q) in enumerate(zip(F, joint.vec_to_child(Q_X))))
    kept = [a for a in range(3) if n + 2 + a in free]
    if len(kept) == 3:              # solve in frame -1, rotate the answer
        lower = {(i, j): C[i][j] for i in range(3) for j in range(i + 1)}
        y = ldlt_solve(tape, lower, [-x for x in F], [0, 1, 2])
        return tuple(tape.let(x, f"Xdd_{a}") for a, x in enumerate(joint.vec_to_parent(tuple(y))))
    # some translations fixed: solve the kept rows of the reference-frame block
    R_ref = _mm(joint.T, joint.Rz)
    C_ref = _rotate(R_ref, C, True)
    rhs = matvec(R_ref, F)
    lower = {(i, j): C_ref[kept[i]][kept[j]] for i in range(len(kept)) for j in range(i + 1)}
    x = ldlt_solve(tape, lower, [-rhs[a] for a in kept], list(range(len(kept))))
    out = [ZERO, ZERO, ZERO]
    for i, a in enumerate(kept):
        out[a] = x[i]
    return tuple(out)


# --- I_f v: the generalised momentum --------------------------------------------------------------
def generalized_momentum(tape: Tape, chain: ChainSymbols, moments: dict[int, LinkSymbols],
                         velocities) -> list[sp.Expr]:
    """I_f v = dT/dv (full layout) for generalised velocities v, by composite momenta at O(n) cost.

    ``velocities``: (omega_k, v_k) of every frame k = -1..n in its own frame (kinematics.link_velocities for
    the velocities v).  Link k's momentum about O_k, in frame k, is H = K omega + h x v (angular) and
    L = B0 v + omega x h (linear), with B0, h, K of Eq. 4-7; summed from the tip and carried to the parent
    like a force, the momentum of links >= k about O_k gives joint k's entry H_z (joint k turns frame k about
    its z axis), and the whole chain's linear momentum the entries of X1..X3 (reference frame)."""
    n = chain.n
    omega, vel = velocities
    joints = {k: JointTransform(tape, chain, moments, k) for k in range(-1, n + 1)}
    h = [ZERO] * chain.nq
    total = None                    # momentum (H, L) of links >= k about O_k in frame k
    for k in range(n, -2, -1):
        tag = index_name(k)
        if k >= 1:
            B = moments[k]
            w, v = omega[k], vel[k]
            own = (add(matvec(B.K, w), cross(B.h, v)), add(tuple(B.B0 * x for x in v), cross(w, B.h)))
        else:
            own = (ZERO3, ZERO3)
        if total is not None:
            H_parent, L_parent = joints[k + 1].force_to_parent(tape, total)
            own = (add(own[0], H_parent), add(own[1], L_parent))
        total = (tape.let_vec(own[0], f"Hm_{tag}"), tape.let_vec(own[1], f"Lm_{tag}"))
        h[k + 1] = total[0][2]
    L_ref = joints[-1].vec_to_parent(total[1])
    for a in range(3):
        h[n + 2 + a] = L_ref[a]
    return h
