"""The forward-mode tangent of the forward dynamics (codegen.tangent), as derived and run as Python (no C): against
complex-step differentiation of the forward-dynamics program itself (exact to round-off, no step to choose), and
entry by entry against sympy's own differentiation of the tape; test_build_tangents.py checks the compiled C."""
from __future__ import annotations

import cmath

import numpy as np
import pytest
import sympy as sp

from codegen import tangent
from codegen.flatten import flatten
from codegen.kernels import forward_dynamics_kernel, forward_dynamics_tangent_kernel
from codegen.kinematics import ChainSymbols
from codegen.specialise import layout_for
from conftest import chain, driven_free_chain, random_parameters, random_states, tilted
from derived import python_function


def _programs(scene):
    symbols = ChainSymbols(scene, False, layout_for(scene, False))
    primal, tangent_kernel = forward_dynamics_kernel(symbols), forward_dynamics_tangent_kernel(symbols)
    return (python_function(flatten(primal), primal.inputs, cmath),
            python_function(flatten(tangent_kernel), tangent_kernel.inputs))


@pytest.mark.parametrize("tilt", [False, True])
def test_tangent_against_complex_step(tilt):
    """Im f(x + i h v) / h = f'(x) v + O(h^2) with no cancellation: at h = 1e-30 it is the derivative to round-off.
    Every parameter moves, g among them (d/dg along -X2, or along a random gravity_direction with ``tilt``)."""
    scene = tilted(driven_free_chain(), seed=61) if tilt else driven_free_chain()
    complex_program, tangent_program = _programs(scene)
    rng = np.random.default_rng(61)
    nparam = len(scene.parameter_vector())
    for trial, (q, qd) in enumerate(random_states(3, 61, 3)):
        p, u = random_parameters(scene, seed=6100 + trial), rng.normal(size=scene.nu) * 2
        dq, dqd, du = rng.normal(size=8), rng.normal(size=8), rng.normal(size=scene.nu)
        dp = rng.normal(size=nparam) * p * 0.1            # relative directions: every parameter moves
        h = 1e-30
        stepped = complex_program(list(q + 1j * h * dq), list(qd + 1j * h * dqd), list(u + 1j * h * du),
                                  list(p + 1j * h * dp))
        expected = np.imag(np.array(stepped, dtype=complex)) / h
        got = np.array(tangent_program(list(q), list(qd), list(u), list(p), list(dq), list(dqd), list(du), list(dp)))
        assert np.max(np.abs(got - expected)) < 1e-12 * np.max(np.abs(expected))


def test_tangent_entries_against_sympy_diff():
    """Each tangent entry (the chain rule on one short expression, with primal symbols reused) equals sympy.diff of
    that entry along the tangents of its arguments, the whole program evaluated at random inputs and seeds."""
    scene = chain(2, ("rigid",))
    primal = forward_dynamics_kernel(ChainSymbols(scene, False, layout_for(scene, False)))
    tape, values, inputs, tangents = tangent.tangent(primal.tape, primal.values, primal.inputs)
    rng = np.random.default_rng(62)
    point = {}                                          # every input and seed at random, every entry evaluated
    for symbol, expr in tape.assignments:
        for s in expr.free_symbols - set(point):
            point[s] = sp.Float(rng.uniform(0.5, 1.5))
        point[symbol] = expr.xreplace(point)
    checked = 0
    for symbol, expr in primal.tape.live(primal.values):
        reference = sum((sp.diff(expr, x) * tangents[x] for x in expr.free_symbols if x in tangents), sp.Integer(0))
        ours = tangents.get(symbol, sp.Integer(0))
        a, b = float(ours.xreplace(point)), float(reference.xreplace(point))
        assert abs(a - b) <= 1e-12 * max(1.0, abs(b)), (symbol, expr)
        checked += 1
    assert checked > 100
