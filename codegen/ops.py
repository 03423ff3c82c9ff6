"""Operation counts of generated straight-line code, by the rule the C printer follows.

Counting rule (after CSE, on the code as emitted):
  * an n-term sum costs n - 1 adds (a subtraction is an add; negations are free, they fold
    into subtractions or into the sign of a literal);
  * an n-factor product costs n - 1 muls; a numeric coefficient other than +-1 is a factor;
  * integer powers x**k are expanded into k - 1 muls (the printer writes x*x*...);
  * a division (any negative power) costs one div, the denominator's own product its muls;
  * sqrt, sin, cos and any other function call count as calls (sqrt and trig listed apart);
  * copies (t = x) cost nothing.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class OpCount:
    add: int = 0
    mul: int = 0
    div: int = 0
    sqrt: int = 0
    trig: int = 0
    other_calls: int = 0

    @property
    def calls(self) -> int:
        return self.sqrt + self.trig + self.other_calls

    @property
    def total(self) -> int:
        return self.add + self.mul + self.div + self.calls

    def __add__(self, other: "OpCount") -> "OpCount":
        return OpCount(*(a + b for a, b in zip(self.as_tuple(), other.as_tuple())))

    def as_tuple(self):
        return (self.add, self.mul, self.div, self.sqrt, self.trig, self.other_calls)

    def as_dict(self) -> dict:
        return {"add": self.add, "mul": self.mul, "div": self.div, "calls": self.calls, "total": self.total}

    def __str__(self) -> str:
        return f"{self.total} ops ({self.add} add, {self.mul} mul, {self.div} div, {self.calls} calls)"


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
