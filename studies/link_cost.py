"""python -m studies links: what link-link contacts cost.  Each capsule scene is run with its link pairs as contacts (as
shipped) and with none (the same scene with ``[contacts] links = []``: the same links, radii, walls and stops, so the
end spheres still touch the walls; only the pairs' gap functions, their events and their impacts are gone), both
models built once and timed alternately in one process, repeat by repeat; the ratio of wall times is taken repeat by
repeat (median and range), with the steps and right-hand sides of each run.  Where no pair strikes in the run, both
runs are the same motion (said in the "same run" column) and the ratio is the cost of watching the pairs alone; where
pairs strike, the run without them lets the links pass through each other, so the two are different motions.
Besides the scenes, a chain of --links capsule links (radius 0.02 m, (n - 1)(n - 2) / 2 pairs) thrown nearly straight
onto a floor, stops at +-1.5 rad on its joints, whose pairs come close but never strike in the run.

    python -m studies links [--scenes capsule-chain,capsule-fold] [--links 8] [--t-end 2] [--repeats 5] [--runs 20]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from .machine import describe
from .toolchain import compiler_version

SAME_STATE = 1e-9          # final q, qd of the two runs within this (relative): the same motion


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies links", description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", default="capsule-chain,capsule-fold",
                        help="shipped scenes or scene files with capsule links, comma-separated "
                             "(default capsule-chain,capsule-fold)")
    parser.add_argument("--links", type=int, default=8,
                        help="links of the thrown straight capsule chain (3..16; 0: none; default 8)")
    parser.add_argument("--t-end", type=float, default=2.0, help="run length in s (default 2)")
    parser.add_argument("--repeats", type=int, default=5, help="alternating repeats of the timing (default 5)")
    parser.add_argument("--runs", type=int, default=20, help="runs of each model per repeat (default 20)")
    return parser


def capsule_line(n: int):
    """n capsule links of 0.25 m (radius 0.02 m, stops at +-1.5 rad, restitution 0.3 at the stops, 0.5 at the walls
    and between links) in a planar chain, nearly straight and tilted 0.1 rad, thrown to the right from 1 m above the
    floor of a 3.5 m wide box, turning at 0.5 rad/s."""
    from codegen.scene import Joint, LineLink, Scene, Wall, coordinate_names
    names = coordinate_names(n)
    q0, qd0 = np.zeros(n + 5), np.zeros(n + 5)
    q0[names.index("theta_-1")], q0[names.index("theta_1")] = -np.pi / 2, -np.pi / 2 + 0.1
    q0[names.index("X1")], q0[names.index("X2")] = 0.5, 1.0
    qd0[names.index("X1")], qd0[names.index("theta_1")] = 1.0, 0.5
    return Scene(name=f"capsule_line{n}", links=(LineLink(0.25, 1.0, (1e-4, 1e-4, 1e-4), 0.02),) * n,
                 joints=(Joint(lower=-1.5, upper=1.5, limit_restitution=0.3),) * (n - 1),
                 walls=(Wall("x1_min", 0.0, 0.5), Wall("x1_max", 3.5, 0.5), Wall("x2_min", 0.0, 0.5)),
                 q0=tuple(q0), qd0=tuple(qd0), link_restitution=0.5)


def without_pairs(scene):
    """The scene with no link pair as a contact (``[contacts] links = []``)."""
    return dataclasses.replace(scene, name=f"{scene.name}_nopairs"[:48], contact_pairs=())


def strikes(result) -> int:
    return sum(any(c.kind == "link" for c in impact.contacts) for impact in result.impacts)


def same_motion(a, b) -> bool:
    if [len(i.contacts) for i in a.impacts] != [len(i.contacts) for i in b.impacts]:
        return False
    scale = max(1.0, float(np.abs(a.q_final).max()), float(np.abs(a.qd_final).max()))
    return (float(np.abs(a.q_final - b.q_final).max()) <= SAME_STATE * scale
            and float(np.abs(a.qd_final - b.qd_final).max()) <= SAME_STATE * scale)


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from codegen.scene import SceneError, load_scene
    from runtime import load_model, simulate
    if not args.t_end > 0 or args.repeats < 1 or args.runs < 1 or not (args.links == 0 or 3 <= args.links <= 16):
        print("error: --t-end > 0, --repeats >= 1, --runs >= 1, --links 0 or in 3..16", file=sys.stderr)
        return 2
    scenes = []
    for name in filter(None, args.scenes.split(",")):
        try:
            scene = load_scene(name.strip())
        except SceneError as exc:
            print(f"error: --scenes: {exc}", file=sys.stderr)
            return 2
        if not scene.link_pairs():
            print(f"error: --scenes: {scene.name} has no link pair that can strike (capsule links, not adjacent)",
                  file=sys.stderr)
            return 2
        scenes.append((name.strip(), scene))
    if args.links:
        scenes.append((f"{args.links} capsules thrown straight", capsule_line(args.links)))
    print(f"Machine: {describe(compiler_version())}")
    print(f"{args.t_end:g} s a run, DOPRI5 rtol 1e-8 (the defaults), {args.runs} runs a repeat, {args.repeats} repeats "
          "alternating; ms per run and ratio: median (min-max) over the repeats")
    print("| scene | link pairs | with pairs: ms per run | without: ms per run | with / without (time) "
          "| steps with / without | rhs with / without | rhs ratio | impacts with / without | link strikes | same run |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for label, scene in scenes:
        models = [load_model(scene), load_model(without_pairs(scene))]
        results = [simulate(model, args.t_end, t_eval=[]) for model in models]       # warm-up, and the records
        for result in results:
            if result.status != 0:
                print(f"error: {label}: {result.message}", file=sys.stderr)
                return 1
        times = [[], []]
        for _ in range(args.repeats):
            for k, model in enumerate(models):
                start = time.perf_counter()
                for _ in range(args.runs):
                    simulate(model, args.t_end, t_eval=[])
                times[k].append((time.perf_counter() - start) / args.runs * 1e3)
        ratio = [a / b for a, b in zip(*times)]
        with_, without = results

        def spread(values, digits):
            return f"{np.median(values):.{digits}f} ({min(values):.{digits}f}-{max(values):.{digits}f})"
        print(f"| {label} | {len(scene.link_pairs())} | {spread(times[0], 3)} | {spread(times[1], 3)} "
              f"| {spread(ratio, 3)} | {with_.n_steps} / {without.n_steps} | {with_.n_rhs} / {without.n_rhs} "
              f"| {with_.n_rhs / without.n_rhs:.3f} | {len(with_.impacts)} / {len(without.impacts)} | {strikes(with_)} | "
              f"{'yes' if same_motion(with_, without) else 'no'} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
