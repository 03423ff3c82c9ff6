"""The flight equations I_f(Theta) Theta_ddot = R(Theta, Theta_dot) by a Lagrangian expansion, for comparison
with the recursive Gibbs-Appell route (codegen.gibbs_appell).  Same scene, same coordinates (the full
layout of Eq. 13 or the scene's specialised Layout), same parameter array, same C interface.

1. The kinetic and potential energies are written out as explicit sympy expressions of q, qd and p:
   the kinematics helpers (reference_frames, point_positions, point_velocities, link moments B0, h, K)
   run on an :class:`InlineTape`, which records nothing and returns every expression itself, so no
   intermediate gets a symbol.  Per real link i, with v = velocity of O_i, w = angular velocity and
   R = ^{ref}R_i (all in the reference frame),

       T_i = 1/2 B0 v.v + v.(w x R h) + 1/2 (R^T w)^T K (R^T w),     V_i = -g (B0 O_i + R h) . d

   (d the scene's gravity direction, -X2 by default).

   The expressions are nested, not multiplied out (no ``expand``): multiplying out would only make
   them larger.  Fixed coordinates are numbers and zero parameters are 0, exactly as in ChainSymbols.
2. The Euler-Lagrange equations of the free coordinates are expanded by differentiation:

       d/dt dT/dqd_i = sum_j d2T/(dqd_i dq_j) qd_j + sum_j d2T/(dqd_i dqd_j) qdd_j      (chain rule)
       d/dt dT/dqd_i - dT/dq_i + dV/dq_i = 0,

   arranged as I_f qdd = R:  I_f[i][j] = d2T/(dqd_i dqd_j) (the coefficient of qdd_j) and
   R_i = -(sum_j d2T/(dqd_i dq_j) qd_j - dT/dq_i + dV/dq_i), the sign convention of the Gibbs-Appell
   ``bias`` kernel.  Only the lower triangle of I_f is differentiated (Schwarz: it is symmetric).
   The derivatives are sympy's own rules (sum, product, power, sin/cos; anything else goes to
   ``sympy.diff``) applied by :class:`Differentiator`, which remembers the derivative of every shared
   subexpression: ``sympy.diff`` gives the same expressions but walks a shared subexpression again at
   every occurrence (and asks for its free symbols at every level), which made n = 6 take minutes.
3. The results become Kernel objects (mass_matrix, bias, forward_dynamics: a dense straight-line LDL^T
   with X1, X2, X3 eliminated first) that go through the same flatten (one CSE pass), printer and
   templates as the Gibbs-Appell kernels; the other kernels (contacts, energy) are the model's own.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import sympy as sp

from . import kernels
from .kinematics import ChainSymbols
from .linalg import ldlt_solve
from .scene import Scene
from .tape import Tape


class InlineTape(Tape):
    """A tape that records nothing: ``let`` returns the expression itself, so the kinematics helpers
    build explicit expressions of q, qd and p instead of a straight-line program."""

    def let(self, expr, name: str) -> sp.Expr:
        return sp.sympify(expr)


def energies(chain: ChainSymbols) -> tuple[sp.Expr, sp.Expr]:
    """Kinetic and potential energy T, V as explicit expressions (kernels.energy_expressions on an InlineTape)."""
    return kernels.energy_expressions(InlineTape(), chain)


class Differentiator:
    """d(expr)/dx with one memo per variable, shared by every expression differentiated."""

    def __init__(self):
        self._memo: dict[sp.Symbol, dict[sp.Expr, sp.Expr]] = {}

    def __call__(self, expr: sp.Expr, x: sp.Symbol) -> sp.Expr:
        return self._d(sp.sympify(expr), x, self._memo.setdefault(x, {}))

    def _d(self, e: sp.Expr, x: sp.Symbol, memo: dict) -> sp.Expr:
        if e.is_Atom:
            return sp.Integer(1) if e == x else sp.Integer(0)
        found = memo.get(e)
        if found is not None:
            return found
        if e.is_Add:
            result = sp.Add(*[self._d(a, x, memo) for a in e.args])
        elif e.is_Mul:                                            # product rule, as Mul._eval_derivative
            args = list(e.args)
            terms = []
            for k, a in enumerate(args):
                da = self._d(a, x, memo)
                if da != 0:
                    terms.append(sp.Mul(*(args[:k] + [da] + args[k + 1:])))
            result = sp.Add(*terms)
        elif e.is_Pow and e.exp.is_Number:
            db = self._d(e.base, x, memo)
            result = sp.Integer(0) if db == 0 else e.exp * e.base ** (e.exp - 1) * db
        elif isinstance(e, sp.sin):
            du = self._d(e.args[0], x, memo)
            result = sp.Integer(0) if du == 0 else sp.cos(e.args[0]) * du
        elif isinstance(e, sp.cos):
            du = self._d(e.args[0], x, memo)
            result = sp.Integer(0) if du == 0 else -sp.sin(e.args[0]) * du
        else:
            result = sp.diff(e, x)
        memo[e] = result
        return result


@dataclass
class Expansion:
    """I_f qdd = R of the free coordinates (indices into layout.free), as explicit expressions."""

    lower: dict[tuple[int, int], sp.Expr]     # I_f[i][j] for j <= i
    R: list[sp.Expr]
    T: sp.Expr
    V: sp.Expr
    seconds: float

    def inertia(self, i: int, j: int) -> sp.Expr:
        return self.lower[(max(i, j), min(i, j))]


def euler_lagrange(chain: ChainSymbols, progress=None) -> Expansion:
    """Expand the Euler-Lagrange equations of the chain's free coordinates (module docstring, step 2)."""
    say = progress or (lambda message: None)
    start = time.perf_counter()
    free = chain.layout.free
    q = [chain.q[i] for i in free]
    qd = [chain.qd[i] for i in free]
    N = len(free)
    T, V = energies(chain)
    say(f"lagrange: T and V written out ({time.perf_counter() - start:.1f} s)")
    diff = Differentiator()
    lower, R = {}, []
    for i in range(N):
        p_i = diff(T, qd[i])                                      # generalised momentum dT/dqd_i
        for j in range(i + 1):
            lower[(i, j)] = diff(p_i, qd[j])                      # coefficient of qdd_j in d/dt p_i
        dp_dt = sp.Add(*[diff(p_i, q[j]) * qd[j] for j in range(N)])   # the rest of d/dt p_i
        R.append(-(dp_dt - diff(T, q[i]) + diff(V, q[i])) + chain.generalized_force(free[i], springs=False))
        say(f"lagrange: equation {i + 1}/{N} expanded ({time.perf_counter() - start:.1f} s)")
    return Expansion(lower, R, T, V, time.perf_counter() - start)


# ---------------------------------------------------------------------------
# kernels (same names, inputs and outputs as codegen.kernels's)
# ---------------------------------------------------------------------------
def mass_matrix_kernel(chain: ChainSymbols, expansion: Expansion) -> kernels.Kernel:
    N = chain.layout.nq
    k = kernels.Kernel("mass_matrix", "Flight inertia matrix I_f(Theta), full, row-major (Lagrangian expansion: "
                     "d2T/dqd_i dqd_j).", ("q", "p"), "M", N * N, Tape())
    k.values = [expansion.inertia(i, j) for i in range(N) for j in range(N)]
    return k


def bias_kernel(chain: ChainSymbols, expansion: Expansion) -> kernels.Kernel:
    N = chain.layout.nq
    k = kernels.Kernel("bias", "Right-hand side R(Theta, Theta_dot) of I_f Theta_ddot = R (Lagrangian expansion: "
                     "-(d2T/dqd dq qd - dT/dq + dV/dq) + Q, springs in V).", ("q", "qd", "u", "p"), "R", N, Tape())
    k.values = list(expansion.R)
    return k


def forward_dynamics_kernel(chain: ChainSymbols, expansion: Expansion) -> kernels.Kernel:
    free = chain.layout.free
    N = len(free)
    k = kernels.Kernel("forward_dynamics", "Theta_ddot solving I_f Theta_ddot = R (Lagrangian expansion), by a "
                     "dense straight-line LDL^T.", ("q", "qd", "u", "p"), "qdd", N, Tape())
    lower = {(i, j): k.tape.let(e, f"M_{i}_{j}") for (i, j), e in expansion.lower.items()}
    R = [k.tape.let(e, f"R_{i}") for i, e in enumerate(expansion.R)]
    translations = [a for a, i in enumerate(free) if i >= chain.n + 2]
    order = translations + [a for a in range(N) if a not in translations]    # X first (Eq. II block)
    k.values = ldlt_solve(k.tape, lower, R, order)
    return k


DYNAMICS = {"mass_matrix": mass_matrix_kernel, "bias": bias_kernel, "forward_dynamics": forward_dynamics_kernel}


def build_kernels(scene: Scene, bake_params: bool = False, progress=None, layout=None,
                  dense: bool | None = True) -> list[kernels.Kernel]:
    """Every kernel of the scene, with the dynamics (mass_matrix, bias, forward_dynamics) from the
    Lagrangian expansion and the others (contacts, energy, the operators) from codegen.kernels, in the
    model's order.  The dense kernels are always generated (they are what this expansion is compared by);
    ``dense`` False is refused."""
    if dense is False:
        raise ValueError("dense: the Lagrangian formulation always generates the dense kernels")
    chain = ChainSymbols(scene, bake_params, layout)
    if progress:
        progress("lagrange expansion")
    expansion = euler_lagrange(chain, progress)
    built = []
    for builder in kernels.builders(dense=True, fused=False, tangent=False):   # the library forms the fused ones;
                                                                               # no tangent of this expansion
        name = builder.__name__.removesuffix("_kernel")
        if progress:
            progress(name)
        built.append(DYNAMICS[name](chain, expansion) if name in DYNAMICS else builder(chain))
    missing = set(DYNAMICS) - {k.name for k in built}
    if missing:
        raise RuntimeError(f"codegen.kernels has no kernel builder for {sorted(missing)}: cannot substitute "
                           "the Lagrangian dynamics")
    return built
