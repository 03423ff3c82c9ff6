"""Trace Pinocchio's articulated-body algorithm with CasADi and write it as C: the peer of `python -m studies peer`.

Run by that study in the interpreter that has the `peer` extra (casadi_kin_dyn, which bundles Pinocchio and
CasADi), possibly another virtual environment:

    python studies/peer_trace.py CHAIN.urdf OUT_DIR        -> OUT_DIR/peer_aba.c, OUT_DIR/peer_ops.json

peer_aba(q, v, tau) -> a is Pinocchio's aba in its own joint order; peer_ops.json counts the traced
operations (add/sub, mul, div, calls) by the rule of codegen/ops.py.  Stand-alone: imports nothing of this
project, so that it runs beside a Pinocchio that needs other versions of numpy or casadi.
"""
from __future__ import annotations

import ctypes
import glob
import json
import os
import sys


def _load_casadi():
    """casadi_kin_dyn's CasADi lives in the cmeel prefix; its shared library is loaded first so that the
    Python module finds it without LD_LIBRARY_PATH."""
    for prefix in glob.glob(os.path.join(sys.prefix, "lib", "python*", "site-packages", "cmeel.prefix")):
        for lib in sorted(glob.glob(os.path.join(prefix, "lib", "libcasadi.so*")), key=len, reverse=True):
            ctypes.CDLL(lib, mode=ctypes.RTLD_GLOBAL)
            break
    import casadi
    from casadi_kin_dyn import casadi_kin_dyn
    return casadi, casadi_kin_dyn


def count_ops(casadi, function) -> dict:
    """add (incl. sub), mul, div and calls among the traced instructions (no copies, constants, negations)."""
    ops = {"add": 0, "mul": 0, "div": 0, "calls": 0}
    kinds = {casadi.OP_ADD: "add", casadi.OP_SUB: "add", casadi.OP_MUL: "mul", casadi.OP_DIV: "div"}
    calls = {getattr(casadi, name) for name in ("OP_SIN", "OP_COS", "OP_SQRT", "OP_TAN", "OP_EXP", "OP_LOG",
                                                  "OP_POW", "OP_ATAN2", "OP_FABS") if hasattr(casadi, name)}
    for k in range(function.n_instructions()):
        op = function.instruction_id(k)
        if op in kinds:
            ops[kinds[op]] += 1
        elif op in calls:
            ops["calls"] += 1
    ops["total"] = sum(ops.values())
    return ops


def main(argv) -> int:
    urdf_path, out = argv
    casadi, casadi_kin_dyn = _load_casadi()
    with open(urdf_path) as handle:
        model = casadi_kin_dyn.CasadiKinDyn(handle.read())
    aba = model.aba()
    nq, nv = model.nq(), model.nv()
    q, v, tau = casadi.SX.sym("q", nq), casadi.SX.sym("v", nv), casadi.SX.sym("tau", nv)
    peer = casadi.Function("peer_aba", [q, v, tau], [aba(q, v, tau)])
    cwd = os.getcwd()
    os.chdir(out)
    try:
        peer.generate("peer_aba.c")
    finally:
        os.chdir(cwd)
    with open(os.path.join(out, "peer_ops.json"), "w") as handle:
        json.dump({"nq": nq, "nv": nv, "joints": list(model.joint_names()), "ops": count_ops(casadi, peer)},
                  handle)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
