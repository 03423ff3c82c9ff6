"""General against specialised models on the paper's two scenes, as a Markdown table.

    python -m studies specialise [--repeat 21]

Columns: operation counts of the forward dynamics and of all kernels, nanoseconds per right-hand side
(a C timing loop), the end-to-end simulation time from Python (DOP853, rtol = 1e-10, every impact),
and the largest difference of the impact times between the two models (both at rtol = 1e-13, so that the
integration error does not hide the comparison).
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

import codegen
from codegen.scene import load_scene
from runtime.model import load_model
from runtime.simulate import simulate

from .timing import time_call, time_rhs

T_END = {"paper-case1": 1.5, "paper-case2": 1.75}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies specialise", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=21)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    print("| scene | model | coordinates | forward dynamics ops | all kernels ops | ns per rhs (C loop) "
          "| simulation ms (DOP853, rtol 1e-10) | impacts | max impact-time difference s (rtol 1e-13) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, t_end in T_END.items():
        scene = load_scene(name)
        times = {}
        for label, specialise in (("general", False), ("specialised", True)):
            generated = codegen.generate(scene, specialise=specialise)
            ops = {f.name: f.ops.total for f in generated.functions}
            ns = time_rhs(generated).median
            model = load_model(scene, specialise=specialise)
            timing = time_call(lambda: simulate(model, t_end, method="dop853", rtol=1e-10, atol=1e-12, t_eval=[]),
                               args.repeat)
            result = timing.result
            tight = simulate(model, t_end, method="dop853", rtol=1e-13, atol=1e-15, t_eval=[])
            times[label] = np.array([i.t for i in tight.impacts])
            diff = ""
            if label == "specialised":
                a, b = times["general"], times["specialised"]
                diff = f"{np.abs(a - b).max():.1e}" if len(a) == len(b) else "different count"
            print(f"| {name} | {label} | {generated.layout.nq} | {ops['forward_dynamics']:,} | {sum(ops.values()):,} | "
                  f"{ns:.0f} | {timing.median * 1e3:.3f} | {len(result.impacts)} | {diff} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
