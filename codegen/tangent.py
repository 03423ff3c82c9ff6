"""Forward-mode differentiation of a straight-line program: the tangent of a kernel, on its own tape.

A kernel's tape is a list of short assignments s = f(x_1..x_k) over the kernel's input arrays and earlier tape
symbols (codegen.tape).  Its tangent along a direction (one seed per input: dq, dqd, du, dp) follows the chain rule
entry by entry, in tape order:

    ds = sum_i  df/dx_i (x_1..x_k) dx_i            (dx = the seed of an input, the tangent of an earlier entry)

each partial derivative taken on the entry's own short expression (the chain rule over its sums, products, powers,
sin and cos; sympy.diff for anything else), so the tangent program has a few
entries per entry of the original: its size is O(size of the tape), O(n) per direction for the O(n) articulated
forward dynamics.  A partial derivative that is a primal entry's expression again (cos(q[1]) next to sin(q[1]),
s**-1 of a division) is given that entry's symbol; a fractional power b**r differentiates as r s / b db, reusing s.
A tangent that is identically 0 (an entry depending on no seeded input) gets no entry.  Then the kernel is flattened
(DCE + CSE) like any other (codegen.flatten).

Only the inputs that are symbols get seeds: with baked parameters p holds no symbol and dp is ignored, and a
parameter a specialised model builds in as 0 has no dp entry's effect either.
"""
from __future__ import annotations

import sympy as sp

from .tape import Tape

ZERO = sp.Integer(0)
TANGENT_PREFIX = "d"           # the seed array of input array a is "d" + a (dq, dqd, du, dp), tangents d_<symbol>


def seeds(live, values, inputs: tuple[str, ...]) -> dict[sp.Symbol, sp.Symbol]:
    """The seed of every input symbol the live tape entries or the outputs read: a[i] -> da[i] for each input
    array a."""
    found: dict[sp.Symbol, sp.Symbol] = {}
    defined = {s for s, _ in live}
    for expr in [e for _, e in live] + list(values):
        for symbol in sp.sympify(expr).free_symbols:
            if symbol in defined or symbol in found:
                continue
            array, bracket, index = symbol.name.partition("[")
            if not bracket or array not in inputs:
                raise ValueError(f"symbol {symbol} is neither a tape entry nor an entry of an input array {inputs}")
            found[symbol] = sp.Symbol(f"{TANGENT_PREFIX}{array}[{index}", real=True)
    return found


def _differential(expr: sp.Expr, symbol: sp.Symbol | None, tangents: dict) -> sp.Expr:
    """d(expr) = sum_i d expr/dx_i dx_i over the symbols x_i with a tangent, by the chain rule on expr's tree (sums,
    products, integer powers, sin, cos; anything else by sympy.diff).  ``symbol`` (expr's own tape symbol, or None)
    stands for expr in the derivative of a fractional power."""
    if expr.is_Pow and symbol is not None and expr.exp.is_Rational and not expr.exp.is_Integer:
        base, r = expr.args
        return r * symbol / base * _differential(base, None, tangents)       # d(b^r) = r b^r / b db
    return _d(expr, tangents)


def _d(expr: sp.Expr, tangents: dict) -> sp.Expr:
    if expr.is_Symbol:
        return tangents.get(expr, ZERO)
    if expr.is_Number:
        return ZERO
    if expr.is_Add:
        return sp.Add(*(_d(a, tangents) for a in expr.args))
    if expr.is_Mul:                                  # d(a_1 .. a_k) = sum_i a_1 .. d(a_i) .. a_k
        terms = []
        for i, a in enumerate(expr.args):
            da = _d(a, tangents)
            if da != 0:
                terms.append(sp.Mul(*expr.args[:i], da, *expr.args[i + 1:]))
        return sp.Add(*terms)
    if expr.is_Pow and expr.exp.is_Integer:          # d(b^k) = k b^(k-1) db
        base, k = expr.args
        db = _d(base, tangents)
        return ZERO if db == 0 else k * base ** (k - 1) * db
    if isinstance(expr, (sp.sin, sp.cos)):
        (arg,) = expr.args
        da = _d(arg, tangents)
        return ZERO if da == 0 else (sp.cos(arg) if isinstance(expr, sp.sin) else -sp.sin(arg)) * da
    total = ZERO
    for x in expr.free_symbols:                      # any other function: sympy's partial derivatives
        dx = tangents.get(x)
        if dx is not None:
            total += sp.diff(expr, x) * dx
    return total


def tangent(tape: Tape, values, inputs: tuple[str, ...]):
    """The directional derivative of the outputs ``values`` of ``tape`` (reading the arrays ``inputs``): a new tape
    holding the primal entries the outputs need (dead ones dropped) and then the tangent entries, the outputs'
    tangents, the inputs of the tangent program (``inputs``, then their seeds: d + each array's name), and the
    tangent of every symbol (input or primal entry) that has a nonzero one: (tape, derivatives, inputs, tangents)."""
    live = tape.live(values)
    seed = seeds(live, values, inputs)
    out = Tape()
    primal = {}                                    # a primal entry's expression -> its symbol
    for symbol, expr in live:
        out.assignments.append((symbol, expr))
        out._used_names.add(symbol.name)
        out._memo[expr] = symbol
        primal[expr] = symbol
    tangents: dict[sp.Expr, sp.Expr] = dict(seed)
    for symbol, expr in live:
        d = _differential(expr, symbol, tangents).xreplace(primal)
        if d != 0:
            tangents[symbol] = out.let(d, f"{TANGENT_PREFIX}_{symbol.name}")
    derivatives = [_differential(sp.sympify(v), None, tangents).xreplace(primal) for v in values]
    return out, derivatives, tuple(inputs) + tuple(TANGENT_PREFIX + a for a in inputs), tangents
