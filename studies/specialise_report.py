"""General against specialised models on the paper's two scenes, as a Markdown table.

    python -m studies specialise [--repeat 21]

Columns: operation counts of the forward dynamics and of all kernels, nanoseconds per right-hand side
(a C timing loop; the general and the specialised model of a scene in one program, alternating batches, and
their ratio batch by batch), the end-to-end simulation time from Python (DOP853, rtol = 1e-10, every impact;
the two models in alternating turns, the median of 5 runs per turn, and their ratio turn by turn), and the
largest difference of the impact times between the two models (both at rtol = 1e-13, so that the
integration error does not hide the comparison).
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

import codegen
from codegen.options import build_options
from codegen.scene import load_scene
from runtime.model import load_model
from runtime.simulate import simulate

from .machine import describe
from .timing import Timing, median_range, ratios, time_call, time_rhs_side_by_side
from .toolchain import compiler_version

T_END = {"paper-case1": 1.5, "paper-case2": 1.75}
RUNS_PER_TURN = 5          # simulations per model and turn (their median is the turn's sample)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies specialise", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=21,
                        help=f"alternating turns of the two models' simulations, {RUNS_PER_TURN} runs each (default 21)")
    parser.add_argument("--scenes", default=",".join(T_END),
                        help=f"the shipped scenes to compare, separated by commas (default {','.join(T_END)})")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.repeat < 1:
        print(f"error: --repeat: must be >= 1, got {args.repeat}", file=sys.stderr)
        return 2
    scenes = args.scenes.split(",")
    unknown = [name for name in scenes if name not in T_END]
    if unknown:
        print(f"error: --scenes: {unknown[0]!r} is not one of {', '.join(T_END)}", file=sys.stderr)
        return 2
    print(f"Machine: {describe(compiler_version())}")
    print("| scene | model | coordinates | forward dynamics ops | all kernels ops | ns per rhs (C loop) "
          "| general / specialised per rhs | simulation ms (DOP853, rtol 1e-10) | general / specialised run "
          "| impacts | max impact-time difference s (rtol 1e-13) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in scenes:
        t_end = T_END[name]
        scene = load_scene(name)
        kinds = (("general", False), ("specialised", True))
        generated = {label: codegen.generate(scene, build_options(scene, specialise=specialise),
                                                    name=f"{scene.name}_{label}")
                     for label, specialise in kinds}
        rhs = dict(zip(generated, time_rhs_side_by_side(list(generated.values()), [100000, 100000])))
        rhs_ratio = ratios(rhs["general"], rhs["specialised"])
        models = {label: load_model(scene, specialise=specialise) for label, specialise in kinds}
        runs = {label: [] for label in models}
        for _ in range(args.repeat):                       # alternating, so load on the machine hits both alike
            for label, model in models.items():
                timing = time_call(lambda: simulate(model, t_end, method="dop853", rtol=1e-10, atol=1e-12,
                                                    t_eval=[]), RUNS_PER_TURN)
                runs[label].append(timing.median)
        run_ratio = Timing(tuple(g / s for g, s in zip(runs["general"], runs["specialised"])))
        results = {label: simulate(model, t_end, method="dop853", rtol=1e-10, atol=1e-12, t_eval=[])
                   for label, model in models.items()}
        tight = {label: np.array([i.t for i in simulate(model, t_end, method="dop853", rtol=1e-13, atol=1e-15,
                                                        t_eval=[]).impacts])
                 for label, model in models.items()}
        a, b = tight["general"], tight["specialised"]
        diff = f"{np.abs(a - b).max():.1e}" if len(a) == len(b) else "different count"
        for label in models:
            ops = {f.name: f.ops.total for f in generated[label].functions}
            ratio_cells = [median_range(rhs_ratio), median_range(run_ratio), diff] if label == "specialised" \
                else ["", "", ""]
            print(f"| {name} | {label} | {generated[label].layout.nq} | {ops['forward_dynamics']:,} | "
                  f"{sum(ops.values()):,} | {median_range(rhs[label], 0)} | {ratio_cells[0]} | "
                  f"{np.median(runs[label]) * 1e3:.3f} | {ratio_cells[1]} | {len(results[label].impacts)} | "
                  f"{ratio_cells[2]} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
