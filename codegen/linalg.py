"""Straight-line LDL^T solve of I_f Theta_ddot = R (I_f is never inverted symbolically).

The factorisation is written onto the tape entry by entry, so known zeros are skipped.  The
elimination order puts X1, X2, X3 first: their block of I_f is M_tot I (Eq. II), so eliminating
them first costs three divisions by the same pivot and leaves a dense Schur complement on the
angles.
"""
from __future__ import annotations

import sympy as sp

from .tape import Tape


def ldlt_solve(tape: Tape, lower: dict[tuple[int, int], sp.Expr], rhs: list[sp.Expr],
               order: list[int]) -> list[sp.Expr]:
    """Solve A x = rhs for symmetric positive definite A given by its lower triangle.

    ``order`` is the elimination order (a permutation of range(N)).  Returns x in the
    original order.  No pivoting: A is positive definite away from the gimbal lock.
    """
    N = len(order)

    def A(i, j):  # entry of the permuted matrix
        a, b = order[i], order[j]
        return lower[(max(a, b), min(a, b))]

    L = {}       # unit lower factor
    dinv = []    # 1 / D_i
    for i in range(N):
        u = {}   # u_ij = L_ij D_j
        for j in range(i):
            value = A(i, j) - sum((u[k] * L[(j, k)] for k in range(j)), sp.Integer(0))
            u[j] = tape.let(value, f"u_{i}_{j}")
            L[(i, j)] = tape.let(u[j] * dinv[j], f"L_{i}_{j}")
        D = tape.let(A(i, i) - sum((u[k] * L[(i, k)] for k in range(i)), sp.Integer(0)), f"D_{i}")
        dinv.append(tape.let(1 / D, f"Dinv_{i}"))
    z = []
    for i in range(N):           # L z = b
        z.append(tape.let(rhs[order[i]] - sum((L[(i, k)] * z[k] for k in range(i)), sp.Integer(0)),
                          f"z_{i}"))
    x = [None] * N
    for i in reversed(range(N)):  # D L^T x = z
        value = z[i] * dinv[i] - sum((L[(k, i)] * x[k] for k in range(i + 1, N)), sp.Integer(0))
        x[i] = tape.let(value, f"sol_{i}")
    solution = [None] * N
    for i, original in enumerate(order):
        solution[original] = x[i]
    return solution
