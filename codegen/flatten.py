"""Turn a kernel's tape into flat, dead-code-free, common-subexpression-eliminated straight-line code.

Steps: keep only the tape entries the outputs need; run one sympy ``cse`` pass over all of them
and the outputs together; then interleave CSE temporaries and tape entries in dependency order.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .kernels import Kernel


@dataclass
class Program:
    """Straight-line code: ``assignments`` in order, then ``output[i] = outputs[i]``."""

    kernel: Kernel
    assignments: list[tuple[sp.Symbol, sp.Expr]]
    outputs: list[sp.Expr]


def live_assignments(kernel: Kernel) -> list[tuple[sp.Symbol, sp.Expr]]:
    """Dead-code elimination: the tape entries the outputs depend on, in tape order."""
    return kernel.tape.live(kernel.values)


def flatten(kernel: Kernel) -> Program:
    live = live_assignments(kernel)
    expressions = [e for _, e in live] + list(kernel.values)
    temporaries = sp.numbered_symbols("x", real=True)
    replacements, reduced = sp.cse(expressions, symbols=temporaries, order="none")
    tape_part = [(s, e) for (s, _), e in zip(live, reduced[:len(live)])]
    outputs = reduced[len(live):]
    assignments = _in_dependency_order(replacements, tape_part)
    # outputs go through the same pass as pseudo-assignments (symbol None)
    fixed = _atomic_power_bases(assignments + [(None, o) for o in outputs], temporaries)
    assignments = [(s, e) for s, e in fixed if s is not None]
    outputs = [e for s, e in fixed if s is None]
    return Program(kernel, assignments, outputs)


def _atomic_power_bases(assignments, temporaries):
    """Give every non-atomic base of an integer power its own temporary, so that the printer's
    expansion x**3 -> x*x*x never repeats work (and the operation count stays exact)."""
    out = []
    for symbol, expr in assignments:
        powers = [p for p in expr.atoms(sp.Pow) if not p.base.is_Atom and p.exp.is_Integer]
        for power in sorted(powers, key=sp.default_sort_key):
            base = next(temporaries)
            out.append((base, power.base))
            expr = expr.xreplace({power.base: base})
        out.append((symbol, expr))
    return out


def _in_dependency_order(replacements, tape_part):
    """Emit each CSE temporary just before its first use; tape entries keep their order.

    A temporary replaces part of some tape expression, so it only depends on tape symbols
    defined before that expression: emitting on first use is always valid.
    """
    pending = dict(replacements)
    emitted = []
    done = set()

    def emit(symbol):
        if symbol in done or symbol not in pending:
            return
        expr = pending[symbol]
        for dependency in sorted(expr.free_symbols, key=lambda s: s.name):
            emit(dependency)
        emitted.append((symbol, expr))
        done.add(symbol)

    for symbol, expr in tape_part:
        for dependency in sorted(expr.free_symbols, key=lambda s: s.name):
            emit(dependency)
        emitted.append((symbol, expr))
        done.add(symbol)
    for symbol, _ in replacements:   # temporaries used only by the outputs
        emit(symbol)
    return emitted
