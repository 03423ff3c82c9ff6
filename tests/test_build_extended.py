"""The long-double kernels (NAME_*_ld: generalized_momentum, contact_generalized_force, energy) against a 30-digit
evaluation of the same flattened programs they are printed from, and the double kernels against it too."""
from __future__ import annotations

import platform

import mpmath
import numpy as np
import pytest
import sympy as sp

from codegen import interface, kernels
from codegen.flatten import flatten
from codegen.kinematics import ChainSymbols
from codegen.specialise import layout_for
from conftest import chain, random_parameters

DIGITS = 30


def _x87_long_double(ffi) -> bool:
    """The 80-bit x87 extended format (64-bit significand) that the decoding below reads."""
    return platform.machine() in ("x86_64", "AMD64", "i686") and ffi.sizeof("long double") in (12, 16)


def _decode(ffi, array, size: int) -> list:
    """The exact values of ``size`` x87 long doubles as mpmath numbers: 64-bit significand, then sign and 15-bit
    exponent, little-endian."""
    raw, stride = bytes(ffi.buffer(array)), ffi.sizeof("long double")
    values = []
    for i in range(size):
        word = raw[i * stride:i * stride + 10]
        mantissa = int.from_bytes(word[:8], "little")
        top = int.from_bytes(word[8:10], "little")
        sign, exponent = top >> 15, top & 0x7FFF
        value = mpmath.ldexp(mpmath.mpf(mantissa), max(exponent, 1) - 16383 - 63)
        values.append(-value if sign else value)
    return values


def _reference(program, inputs: dict[str, np.ndarray]) -> list:
    """The program's outputs at 30 digits: its assignments in order, every number the double the C kernels read
    (the scene's Floats rounded to doubles, as both printers print them; rationals exact)."""
    env = {}
    for array, values in inputs.items():
        for i, x in enumerate(values):
            env[f"{array}[{i}]"] = mpmath.mpf(float(x))

    def evaluate(expr):
        doubles = {f: sp.Float(float(f), DIGITS + 10) for f in expr.atoms(sp.Float)}
        expr = expr.xreplace(doubles)
        symbols = sorted(expr.free_symbols, key=lambda s: s.name)
        function = sp.lambdify(symbols, expr, modules="mpmath")
        return function(*(env[s.name] for s in symbols))
    for symbol, expr in program.assignments:
        env[symbol.name] = evaluate(expr)
    return [evaluate(sp.sympify(expr)) for expr in program.outputs]


@pytest.mark.parametrize("kernel", interface.EXTENDED_OF)
def test_the_long_double_kernels_evaluate_their_programs_to_1e_18(compiled, kernel):
    scene = chain(3, ("line", "rigid"), twists=True)
    model = compiled(scene, extended=True)
    ffi = model.ffi
    if not _x87_long_double(ffi):
        pytest.skip("long double is not the x87 extended format here")
    chain_symbols = ChainSymbols(scene, False, layout_for(scene, False))
    program = flatten(getattr(kernels, f"{kernel}_kernel")(chain_symbols))
    size = program.kernel.output_size
    rng = np.random.default_rng(11)
    mpmath.mp.dps = DIGITS
    worst_ld = worst_double = 0.0
    for seed in range(3):
        p = random_parameters(scene, 40 + seed)
        q = rng.uniform(-np.pi, np.pi, model.nq)
        v = rng.normal(size=len(model.contact_rows) if kernel == "contact_generalized_force" else model.nq)
        second = "f" if kernel == "contact_generalized_force" else "qd"
        reference = _reference(program, {"q": q, second: v, "p": p})
        out = ffi.new("long double[]", size)
        doubles = np.zeros(size)
        getattr(model.c, f"{kernel}_ld")(model._ptr(q), model._ptr(v), model._ptr(p), out)
        getattr(model.c, kernel)(model._ptr(q), model._ptr(v), model._ptr(p), model._ptr(doubles))
        extended = _decode(ffi, out, size)
        scale = max(abs(x) for x in reference)
        worst_ld = max(worst_ld, max(float(abs(a - b) / scale) for a, b in zip(extended, reference)))
        worst_double = max(worst_double, max(float(abs(mpmath.mpf(float(a)) - b) / scale)
                                             for a, b in zip(doubles, reference)))
    assert worst_ld <= 2e-18, (kernel, worst_ld)
    assert worst_double <= 1e-15, (kernel, worst_double)


def test_a_model_built_without_them_has_none(compiled):
    scene = chain(2)
    model = compiled(scene)                                  # the suite's default: extended=False
    assert not model.options.extended
    assert model.c.model.generalized_momentum_ld == model.ffi.NULL
    assert model.c.model.energy_ld == model.ffi.NULL
    out = model.ffi.new("long double[]", 2)
    q, qd = np.zeros(model.nq), np.zeros(model.nq)
    model.c.energy_ld(model._ptr(q), model._ptr(qd), model._ptr(model.p), out)
    assert all(np.isnan(float(x)) for x in out)              # the stub: NaN
