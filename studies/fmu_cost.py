"""python -m studies fmu: what a run costs through the FMI 2.0 FMU (python -m runtime fmu) against the same run
from Python (runtime.simulate), both sampling the coordinates at every communication point.

The FMU is driven by FMPy's FMU2Slave, as an importer drives it: fmi2DoStep to each communication point, then
fmi2GetReal of q.  Timed: the stepping only (instantiation, which loads the shared library, is apart).  The two
runs are checked to agree (impacts and final state) before they are timed.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time

import numpy as np

from .machine import describe
from .timing import time_call
from .toolchain import compiler_version


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies fmu", description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="paper-case1", help="shipped scene or scene file (default paper-case1)")
    parser.add_argument("--t-end", type=float, default=1.5, help="run length in s (default 1.5)")
    parser.add_argument("--steps", default="0.01,0.001", help="communication steps in s (default 0.01,0.001)")
    parser.add_argument("--repeats", type=int, default=11, help="timed runs per row (default 11)")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
    except ImportError:
        print("error: this study runs the FMU with FMPy: pip install -e '.[fmi]'", file=sys.stderr)
        return 2
    try:
        steps = [float(x) for x in args.steps.split(",")]
    except ValueError:
        print(f"error: --steps: expected numbers separated by commas, got {args.steps!r}", file=sys.stderr)
        return 2
    if not all(h > 0 and args.t_end / h <= 1e6 for h in steps) or args.t_end <= 0 or args.repeats < 1:
        print("error: --t-end and --steps must be > 0 (at most 1e6 steps per run), --repeats >= 1", file=sys.stderr)
        return 2
    from runtime import load_model, simulate
    from runtime.fmu import build_fmu

    model = load_model(args.scene)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        path = build_fmu(args.scene, tmp)
        print(f"built {path.name} in {time.perf_counter() - start:.2f} s (model text from the cache)", file=sys.stderr)
        md = read_model_description(str(path))
        refs = [v.valueReference for v in md.modelVariables if v.name.startswith("q.")]
        slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path), unzipdir=f"{tmp}/unzipped"),
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="study")
        slave.instantiate()
        print(f"Machine: {describe(compiler_version())}")
        print("| communication step s | FMU (FMPy) ms per run (spread) | runtime.simulate ms (spread) | ratio "
              "| impacts | max abs difference of q at the end |")
        print("|---|---|---|---|---|---|")
        for h in steps:
            n = int(round(args.t_end / h))

            def fmu_run():
                slave.reset()
                slave.setupExperiment(startTime=0.0)
                slave.enterInitializationMode()
                slave.exitInitializationMode()
                t0 = time.perf_counter()
                q = None
                for k in range(n):
                    slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
                    q = slave.getReal(refs)
                elapsed = time.perf_counter() - t0
                return elapsed, np.array(q), slave.getInteger([1])[0]

            t_eval = np.arange(n + 1) * h
            first = fmu_run()
            result = simulate(model, n * h, t_eval=t_eval)
            difference = float(np.max(np.abs(first[1] - result.q[-1, list(model.layout.free)])))
            if first[2] != len(result.impacts):
                print(f"error: the FMU had {first[2]} impacts, simulate {len(result.impacts)}", file=sys.stderr)
                return 1
            fmu_times = [fmu_run()[0] for _ in range(args.repeats)]
            py = time_call(lambda: simulate(model, n * h, t_eval=t_eval), repeat=args.repeats)
            fmu_median = float(np.median(fmu_times))
            print(f"| {h:g} | {1e3 * fmu_median:.2f} ({1e3 * (max(fmu_times) - min(fmu_times)):.2f}) | "
                  f"{1e3 * py.median:.2f} ({1e3 * py.spread:.2f}) | {fmu_median / py.median:.1f} | {first[2]} | "
                  f"{difference:.1e} |")
        slave.terminate()
        slave.freeInstance()
    return 0


if __name__ == "__main__":
    sys.exit(main())
