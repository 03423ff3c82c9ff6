"""The derivation without C: a scene's kernels (codegen.kernels) flattened (codegen.flatten) and run as Python.

``DerivedModel`` answers the kernel calls of ``runtime.CompiledModel`` (same names, arguments and shapes) from
the straight-line programs the C is printed from, so tests of the derivation need no compiler.  Each kernel is
derived, flattened and turned into a Python function on first use and kept for the session.
"""
from __future__ import annotations

import math

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from codegen import kernels as kernel_builders, lagrange
from codegen.flatten import flatten
from codegen.kinematics import ChainSymbols
from codegen.specialise import layout_for


class _Printer(PythonCodePrinter):
    """Python for the flattened programs: symbols keep their C spelling (q[0], p[3], x12, t_5)."""

    def _print_Symbol(self, expr):
        return expr.name


_PRINTER = _Printer({"fully_qualified_modules": True, "standard": "python3"})


def python_function(program, inputs: tuple[str, ...], math_module=math):
    """A flattened kernel (codegen.flatten.Program) as a Python function of its input arrays, returning a list;
    ``math_module`` cmath evaluates it in complex arithmetic (complex-step differentiation)."""
    lines = [f"def kernel({', '.join(inputs)}):"]
    lines += [f"    {symbol.name} = {_PRINTER.doprint(expr)}" for symbol, expr in program.assignments]
    lines.append("    return [" + ", ".join(_PRINTER.doprint(sp.sympify(o)) for o in program.outputs) + "]")
    env = {"math": math_module}
    exec("\n".join(lines), env)
    return env["kernel"]


_FUNCTIONS: dict[tuple, object] = {}


class DerivedModel:
    """The kernels of ``scene`` as derived (no C): the subset of CompiledModel's kernel calls.  ``formulation``
    'lagrange' takes mass_matrix, bias and forward_dynamics from the Euler-Lagrange expansion (codegen.lagrange)."""

    def __init__(self, scene, specialise: bool = False, bake_params: bool = False, formulation: str = "gibbs_appell"):
        self.scene, self.specialise, self.bake_params = scene, specialise, bake_params
        self.formulation = formulation
        self.expansion = None
        self.layout = layout_for(scene, specialise)
        self.chain = None                                  # ChainSymbols, made on first use
        self.n, self.nq = scene.n, self.layout.nq
        self.p = scene.parameter_vector()
        self.nu = scene.nu
        self.contacts = list(self.layout.contacts)
        self.contact_rows = list(self.layout.contact_rows)

    def function(self, name: str, solver: str | None = None):
        key = (self.scene, self.specialise, self.bake_params, self.formulation, name, solver)
        if key not in _FUNCTIONS:
            if self.chain is None:
                self.chain = ChainSymbols(self.scene, self.bake_params, self.layout)
            if self.formulation == "lagrange" and name in lagrange.DYNAMICS:
                if self.expansion is None:
                    self.expansion = lagrange.euler_lagrange(self.chain)
                kernel = lagrange.DYNAMICS[name](self.chain, self.expansion)
            else:
                builder = getattr(kernel_builders, f"{name}_kernel")
                kernel = builder(self.chain, solver) if solver else builder(self.chain)
            _FUNCTIONS[key] = python_function(flatten(kernel), kernel.inputs)
        return _FUNCTIONS[key]

    def _call(self, name, *args, solver=None, **arrays):
        return np.array(self.function(name, solver)(*args, **arrays), dtype=float)

    def _params(self, p):
        return list(self.p if p is None else p)

    def _inputs(self, u):
        return list(np.zeros(max(self.nu, 1)) if u is None else u)

    # -- the kernels, shaped as CompiledModel's ----------------------------------------------------
    def mass_matrix(self, q, p=None):
        return self._call("mass_matrix", list(q), self._params(p)).reshape(self.nq, self.nq)

    def bias(self, q, qd, p=None, u=None):
        return self._call("bias", list(q), list(qd), self._inputs(u), self._params(p))

    def forward_dynamics(self, q, qd, p=None, u=None, solver: str = "articulated"):
        return self._call("forward_dynamics", list(q), list(qd), self._inputs(u), self._params(p), solver=solver)

    def power(self, q, qd, p=None, u=None):
        P = self._call("power", list(q), list(qd), self._inputs(u), self._params(p))
        return float(P[0]), float(P[1])

    def inertia_solve(self, q, Q, p=None):
        return self._call("inertia_solve", list(q), list(Q), self._params(p))

    def generalized_momentum(self, q, qd, p=None):
        return self._call("generalized_momentum", list(q), list(qd), self._params(p))

    def contact_generalized_force(self, q, f, p=None):
        return self._call("contact_generalized_force", list(q), list(f), self._params(p))

    def contact_points(self, q, p=None):
        return self._call("contact_points", list(q), self._params(p)).reshape(self.n + 1, 3)

    def contact_velocities(self, q, qd, p=None):
        return self._call("contact_velocities", list(q), list(qd), self._params(p)).reshape(self.n + 1, 3)

    def contact_jacobian(self, q, p=None):
        return self._call("contact_jacobian", list(q), self._params(p)).reshape(len(self.contact_rows), self.nq)

    def contact_bias(self, q, qd, p=None):
        return self._call("contact_bias", list(q), list(qd), self._params(p))

    def contact_gaps(self, q, p=None):
        return self._call("contact_gaps", list(q), self._params(p))

    def energy(self, q, qd, p=None):
        E = self._call("energy", list(q), list(qd), self._params(p))
        return float(E[0]), float(E[1])

    def forward_dynamics_energy(self, q, qd, p=None, u=None):
        y = self._call("forward_dynamics_energy", list(q), list(qd), self._inputs(u), self._params(p))
        return y[:self.nq], float(y[self.nq]), float(y[self.nq + 1])

    def forward_dynamics_tangent(self, q, qd, dq, dqd, p=None, u=None, du=None, dp=None):
        du = list(np.zeros(max(self.nu, 1)) if du is None else du)
        dp = list(np.zeros(len(self.p)) if dp is None else dp)
        return self._call("forward_dynamics_tangent", list(q), list(qd), self._inputs(u), self._params(p), list(dq),
                          list(dqd), du, dp)
