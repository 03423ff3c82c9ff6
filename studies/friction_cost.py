"""python -m studies friction: what friction at resting contacts costs, and what its regularisation velocity v_s
buys: the shipped scene rough-floor (a chain thrown onto a rough floor: impacts, sliding, rest) run with the floor
smooth and rough at several v_s, each a freshly generated model, with sticking (the default) and with the
regularisation alone (stick=False); steps, right-hand sides, time, the energy friction
took, where the chain stopped, and the energy balance's residual."""
from __future__ import annotations

import argparse
import dataclasses
import sys

from .machine import describe
from .timing import time_call
from .toolchain import compiler_version


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies friction", description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="rough-floor", help="shipped scene or scene file (default rough-floor)")
    parser.add_argument("--t-end", type=float, default=4.0, help="run length in s (default 4)")
    parser.add_argument("--velocities", default="1e-2,1e-3,1e-4",
                        help="regularisation velocities v_s in m/s (default 1e-2,1e-3,1e-4)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per row (default 5)")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from codegen.scene import SceneError, load_scene
    from runtime import load_model, simulate
    try:
        velocities = [float(v) for v in args.velocities.split(",")]
        scene = load_scene(args.scene)
    except ValueError:
        print(f"error: --velocities: expected numbers separated by commas, got {args.velocities!r}", file=sys.stderr)
        return 2
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if not any(w.friction > 0 for w in scene.walls):
        print(f"error: --scene: {scene.name} has no wall with friction", file=sys.stderr)
        return 2
    smooth = dataclasses.replace(scene, name=f"{scene.name}_smooth",
                                 walls=tuple(dataclasses.replace(w, friction=0.0) for w in scene.walls))
    rows = [("smooth", smooth, True)]
    for vs in velocities:
        try:
            variant = dataclasses.replace(scene, friction_velocity=vs)
            rows += [(f"v_s = {vs:g} m/s, stick", variant, True), (f"v_s = {vs:g} m/s, regularised", variant, False)]
        except SceneError as exc:
            print(f"error: --velocities: {exc}", file=sys.stderr)
            return 2
    n = scene.n
    print(f"Machine: {describe(compiler_version())}")
    print(f"{scene.name}, {args.t_end:g} s, DOPRI5 rtol 1e-8 (median of {args.repeats} runs, spread in brackets)")
    print("| floor | steps | rhs | ms per run | impacts | sticks / slips | friction loss J | X1 at the end m "
          "| energy residual J |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, variant, stick in rows:
        model = load_model(variant, progress=lambda m: print(f"  {m}", file=sys.stderr))
        timing = time_call(lambda: simulate(model, args.t_end, t_eval=[args.t_end], stick=stick), repeat=args.repeats)
        result = timing.result
        if not result.success:
            print(f"error: {label}: {result.message}", file=sys.stderr)
            return 1
        print(f"| {label} | {result.n_steps} | {result.n_rhs} | {1e3 * timing.median:.1f} ({1e3 * timing.spread:.1f}) "
              f"| {len(result.impacts)} | {result.n_sticks} / {result.n_slips} | {result.loss_friction:.4g} | {result.q[-1, n + 2]:.6f} "
              f"| {result.energy_residual:.1e} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
