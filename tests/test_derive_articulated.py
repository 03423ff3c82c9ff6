"""The O(n) articulated-body forward dynamics against the dense route (I_f of Eq. I/II and an LDL^T)
and against the independent reference model, without compiling: the straight-line programs are
evaluated as Python."""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from sympy.printing.pycode import pycode

from studies import reference
from conftest import chain, random_parameters, reference_of, tilted
from codegen.flatten import flatten
from codegen.kinematics import ChainSymbols
from codegen.kernels import forward_dynamics_kernel
from codegen.ops import count_ops
from codegen.scene import default_scene
from codegen.specialise import layout_for


def run_program(program, q, qd, p) -> np.ndarray:
    """Execute a flattened kernel as Python (symbols are named like the C arrays: q[0], p[3], ...)."""
    env = {"q": list(q), "qd": list(qd), "p": list(p), "math": math}
    lines = [f"{symbol.name} = {pycode(expr)}" for symbol, expr in program.assignments]
    lines.append("out = [" + ", ".join(pycode(sp.sympify(o)) for o in program.outputs) + "]")
    exec("\n".join(lines), env)
    return np.array(env["out"], dtype=float)


def solve_both(scene, specialise, q, qd, p):
    layout = layout_for(scene, specialise)
    chain = ChainSymbols(scene, False, layout)
    out = {}
    for solver in ("articulated", "dense"):
        out[solver] = run_program(flatten(forward_dynamics_kernel(chain, solver)),
                                  layout.reduce(q), layout.reduce(qd), p)
    return out, layout


@pytest.mark.parametrize("n,tilt", [(1, False), (2, False), (3, False), (3, True),
                                    pytest.param(5, False, marks=pytest.mark.slow)])
@pytest.mark.parametrize("kinds", [("line",), ("line", "rigid")])
def test_articulated_matches_dense_and_reference_on_random_3d_chains(n, kinds, tilt):
    """``tilt``: gravity along a random direction (gravity_direction) instead of -X2."""
    scene = tilted(chain(n, kinds, twists=True), seed=n) if tilt else chain(n, kinds, twists=True)
    rng = np.random.default_rng(n)
    for trial in range(3):
        p = random_parameters(scene, seed=700 * n + trial)
        q, qd = reference.random_state(n, rng)
        out, _ = solve_both(scene, False, q, qd, p)
        expected = reference_of(scene, p).forward_dynamics(q, qd)
        scale = np.max(np.abs(expected))
        assert np.max(np.abs(out["articulated"] - expected)) < 1e-10 * scale
        assert np.max(np.abs(out["articulated"] - out["dense"])) < 1e-10 * scale


@pytest.mark.parametrize("n", [1, 3, 6])
def test_locked_coordinates_of_a_planar_layout(n):
    """Specialised planar layout: theta_-1, theta_0 and X3 are locked joints of the recursion."""
    scene = default_scene(n)
    layout = layout_for(scene, True)
    assert len(layout.free) == n + 2
    rng = np.random.default_rng(n)
    q, qd = np.array(scene.q0, dtype=float), np.array(scene.qd0, dtype=float)
    free = list(layout.free)
    q[free] += rng.normal(size=len(free))
    qd[free] = rng.normal(size=len(free))
    p = np.array(scene.parameter_vector())
    out, _ = solve_both(scene, True, q, qd, p)
    expected = layout.reduce(reference_of(scene, p).forward_dynamics(q, qd))
    scale = np.max(np.abs(expected))
    assert np.max(np.abs(out["articulated"] - expected)) < 1e-10 * scale
    assert np.max(np.abs(out["articulated"] - out["dense"])) < 1e-10 * scale


def test_cost_grows_linearly_with_n():
    """O(n): each added link costs the same number of operations (the dense route grows as n^3)."""
    def ops(n, solver):
        scene = default_scene(n)
        chain = ChainSymbols(scene, False, layout_for(scene, False))
        program = flatten(forward_dynamics_kernel(chain, solver))
        return count_ops([e for _, e in program.assignments] + list(program.outputs)).total
    a4, a8, a12 = ops(4, "articulated"), ops(8, "articulated"), ops(12, "articulated")
    assert abs((a12 - a8) - (a8 - a4)) <= 0.02 * (a8 - a4)
    d4, d8, d12 = ops(4, "dense"), ops(8, "dense"), ops(12, "dense")
    assert (d12 - d8) > 1.3 * (d8 - d4)        # superlinear (the O(n^3) LDL^T)
    assert a12 < d12
