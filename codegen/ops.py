"""Operation counts of generated straight-line code, by the rule the C printer follows.

Counting rule (after CSE, on the code as emitted):
  * an n-term sum costs n - 1 adds (a subtraction is an add; negations are free, they fold
    into subtractions or into the sign of a literal);
  * an n-factor product costs n - 1 muls; a numeric coefficient other than +-1 is a factor;
  * integer powers x**k are expanded into k - 1 muls (the printer writes x*x*...);
  * a division (any negative power) costs one div, the denominator's own product its muls;
  * sqrt, sin, cos and any other function call count as calls (sqrt and trig listed apart);
  * copies (t = x) cost nothing.
Every operation is counted where it stands in the emitted code: a subexpression that CSE shared is
counted once, at its temporary.

Before CSE, :func:`raw_count_ops` gives sympy's own ``count_ops`` (visual=False) of a list of
expressions: every node of each expression *tree* counts, so a subexpression that occurs k times counts
k times (sympy's rules: an n-term Add is n - 1 ADD/SUB, a Mul n - 1 MUL, a negation NEG, a division DIV,
a power POW, a function call one).  This is the size of the expressions a derivation hands to CSE, and it
shows how much an expansion repeats itself.  It is computed with memoisation on shared subexpressions,
so it takes time proportional to the DAG, not the tree; a test checks it against sympy.count_ops.
"""
from __future__ import annotations

import sys
from collections import Counter

import sympy as sp
from sympy.core.function import _coeff_isneg
from sympy.simplify.radsimp import fraction

from .artifact import OpCount  # noqa: F401  (the count type lives with the generated text)





def count_expr(expr: sp.Expr, tally: Counter) -> None:
    """Add the operations of one expression to ``tally``."""
    if expr.is_Atom:
        return
    if expr.is_Add:
        tally["add"] += len(expr.args) - 1
        for arg in expr.args:
            count_expr(arg, tally)
        return
    if expr.is_Mul:
        coefficient, factors = expr.as_coeff_mul()
        numerator, denominator = [], []
        for factor in factors:
            if factor.is_Pow and factor.exp.is_Number and factor.exp < 0:
                denominator.append(sp.Pow(factor.base, -factor.exp))
            else:
                numerator.append(factor)
        if abs(coefficient) != 1:
            numerator.append(coefficient)          # printed as a double literal
        tally["mul"] += max(len(numerator) - 1, 0) + max(len(denominator) - 1, 0)
        if denominator:
            tally["div"] += 1
        for factor in numerator + denominator:
            count_expr(factor, tally)
        return
    if expr.is_Pow:
        base, exponent = expr.args
        if exponent.is_Integer:
            k = abs(int(exponent))
            tally["mul"] += k - 1
            if exponent < 0:
                tally["div"] += 1
        elif exponent == sp.Rational(1, 2):
            tally["sqrt"] += 1
        elif exponent == sp.Rational(-1, 2):
            tally["sqrt"] += 1
            tally["div"] += 1
        else:
            tally["other_calls"] += 1
        count_expr(base, tally)
        return
    if isinstance(expr, (sp.sin, sp.cos)):
        tally["trig"] += 1
    elif isinstance(expr, sp.Function):
        tally["other_calls"] += 1
    for arg in expr.args:
        count_expr(arg, tally)


def count_ops(expressions) -> OpCount:
    tally = Counter()
    for expr in expressions:
        count_expr(expr, tally)
    return OpCount(tally["add"], tally["mul"], tally["div"], tally["sqrt"], tally["trig"], tally["other_calls"])


def raw_count_ops(expressions) -> int:
    """sympy.count_ops(expressions, visual=False), memoised on shared subexpressions (same value)."""
    memo: dict = {}
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 100000))
    try:
        return sum(_sympy_ops(sp.sympify(e), memo) for e in expressions)
    finally:
        sys.setrecursionlimit(limit)


def _sympy_ops(a, memo) -> int:
    """The tree count of sympy.count_ops for one node, following its loop rule by rule."""
    cached = memo.get(a)
    if cached is None:
        cached = memo[a] = _sympy_ops_node(a, memo)
    return cached


def _sympy_ops_node(a, memo) -> int:
    ops = 0
    if a.is_Rational:
        return 0 if a is sp.S.One else int(a.p < 0) + int(a.q != 1)
    if a.is_Mul:
        if _coeff_isneg(a):
            ops += 1                                                       # NEG
            a = a.as_two_terms()[1] if a.args[0] is sp.S.NegativeOne else -a
        numerator, denominator = fraction(a)
        if numerator.is_Integer:
            return ops + 1 + int(bool(numerator < 0)) + _sympy_ops(denominator, memo)   # DIV (+ NEG)
        if denominator is not sp.S.One:
            if not denominator.is_Integer:
                ops += _sympy_ops(denominator, memo)
            return ops + 1 + _sympy_ops(numerator, memo)                   # DIV
    elif a.is_Add:
        terms = a.args
        negative = [_coeff_isneg(t) for t in terms]
        ops += len(terms) - 1                                              # ADD or SUB
        ops += sum(_sympy_ops(-t if neg else t, memo) for t, neg in zip(terms, negative))
        if all(negative):
            ops += 1                                                       # NEG
        return ops
    if a.is_Pow and a.exp is sp.S.NegativeOne:
        return ops + 1 + _sympy_ops(a.base, memo)                          # DIV
    if a == sp.S.Exp1:
        return ops + 1
    if a.is_Pow and a.base == sp.S.Exp1:
        return ops + 1 + _sympy_ops(a.exp, memo)
    if a.is_Mul:
        ops += len(a.args) - 1
    elif a.args and (a.is_Pow or a.is_Function or isinstance(a, sp.Derivative)):
        ops += 1
    if not a.is_Symbol:
        ops += sum(_sympy_ops(arg, memo) for arg in a.args)
    return ops
