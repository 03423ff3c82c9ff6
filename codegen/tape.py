"""A straight-line program under construction, and the small 3-vector algebra used to fill it.

The recursions of the paper produce the same intermediate quantities over and over
(rotation entries, omega_k, the velocity-product accelerations, ...).  Substituting them
into each other would make the expressions grow exponentially with n.  Instead every
intermediate gets its own symbol the moment it is produced (``Tape.let``), so each
expression on the tape stays a few operations long.  Trivial values (numbers, symbols,
their negations) are never given a symbol: they are passed through, so that structural
zeros and ones (zero-length imaginary links, permutation twists, massless links)
propagate and vanish symbolically.  Identical expressions are given the same symbol.
"""
from __future__ import annotations

import sympy as sp

Vec = tuple  # three sympy expressions
Mat = tuple  # three rows of three sympy expressions


def _is_trivial(expr: sp.Expr) -> bool:
    if expr.is_Atom:
        return True
    return expr.is_Mul and len(expr.args) == 2 and expr.args[0] == -1 and expr.args[1].is_Atom


class Tape:
    """An ordered list of assignments ``symbol = expression``."""

    def __init__(self):
        self.assignments: list[tuple[sp.Symbol, sp.Expr]] = []
        self._memo: dict[sp.Expr, sp.Symbol] = {}
        self._used_names: set[str] = set()

    def let(self, expr, name: str) -> sp.Expr:
        """Record ``name = expr`` and return the new symbol (or expr itself when trivial)."""
        expr = sp.sympify(expr)
        if _is_trivial(expr):
            return expr
        if expr in self._memo:
            return self._memo[expr]
        negated = -expr
        if negated in self._memo:
            return -self._memo[negated]
        symbol = sp.Symbol(self._unique(name), real=True)
        self.assignments.append((symbol, expr))
        self._memo[expr] = symbol
        return symbol

    def live(self, values) -> list[tuple[sp.Symbol, sp.Expr]]:
        """Dead-code elimination: the entries the expressions ``values`` depend on, in tape order."""
        definitions = dict(self.assignments)
        needed = set()
        stack = [s for value in values for s in sp.sympify(value).free_symbols if s in definitions]
        while stack:
            symbol = stack.pop()
            if symbol in needed:
                continue
            needed.add(symbol)
            stack.extend(s for s in definitions[symbol].free_symbols if s in definitions and s not in needed)
        return [(s, e) for s, e in self.assignments if s in needed]

    def let_vec(self, v, name: str) -> Vec:
        return tuple(self.let(x, f"{name}_{axis}") for x, axis in zip(v, "xyz"))

    def let_mat(self, m, name: str) -> Mat:
        return tuple(tuple(self.let(m[i][j], f"{name}_{i}{j}") for j in range(3)) for i in range(3))

    def _unique(self, name: str) -> str:
        candidate, k = name, 1
        while candidate in self._used_names:
            k += 1
            candidate = f"{name}_{k}"
        self._used_names.add(candidate)
        return candidate


def index_name(k: int) -> str:
    """Index k as it appears in a C identifier: -1 -> 'm1'."""
    return f"m{-k}" if k < 0 else str(k)


# --- 3-vector and 3x3-matrix algebra on tuples of sympy expressions -------------------
ZERO = sp.Integer(0)
E_X = (sp.Integer(1), ZERO, ZERO)
E_Y = (ZERO, sp.Integer(1), ZERO)
E_Z = (ZERO, ZERO, sp.Integer(1))


def add(a: Vec, b: Vec) -> Vec:
    return tuple(x + y for x, y in zip(a, b))


def sub(a: Vec, b: Vec) -> Vec:
    return tuple(x - y for x, y in zip(a, b))


def scale(s, a: Vec) -> Vec:
    return tuple(s * x for x in a)


def dot(a: Vec, b: Vec):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def matvec(m: Mat, v: Vec) -> Vec:
    return tuple(dot(row, v) for row in m)


def mat_t_vec(m: Mat, v: Vec) -> Vec:
    """m^T v."""
    return tuple(m[0][j] * v[0] + m[1][j] * v[1] + m[2][j] * v[2] for j in range(3))


def matmul(a: Mat, b: Mat) -> Mat:
    return tuple(tuple(sum((a[i][k] * b[k][j] for k in range(3)), ZERO) for j in range(3))
                 for i in range(3))


def transpose(m: Mat) -> Mat:
    return tuple(tuple(m[j][i] for j in range(3)) for i in range(3))


def column(m: Mat, j: int) -> Vec:
    return (m[0][j], m[1][j], m[2][j])


def to_exact(matrix) -> Mat:
    """A numeric 3x3 matrix as sympy numbers; exact 0 and +-1 stay exact integers."""
    def conv(x: float):
        if x in (0.0, 1.0, -1.0):
            return sp.Integer(int(x))
        return sp.Float(repr(float(x)), 17)
    return tuple(tuple(conv(x) for x in row) for row in matrix)
