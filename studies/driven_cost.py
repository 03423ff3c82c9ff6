"""What driving a chain costs: ns per NAME_rhs (C loop) of the built-in n-link chain, passive and with a
spring, a damper and a torque input on every joint, both timed in one C program (alternating batches; the
ratio taken batch by batch); and the simulation time of the shipped driven scene against the same scene
passive (alternating, repeated).

    python -m studies driven [--links 4,8,16] [--repeats 3] [--runs 200]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from .machine import describe
from .toolchain import compiler_version


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies driven", description=__doc__.split("\n\n")[0])
    parser.add_argument("--links", default="4,8,16", help="chain lengths, comma-separated (default 4,8,16)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="alternating repeats of each simulation timing (default 3)")
    parser.add_argument("--runs", type=int, default=200, help="simulations of the driven scene per repeat")
    return parser


def driven_variant(scene):
    from codegen.scene import Joint
    joints = (Joint(5.0, 0.2, 0.5),) * (scene.n - 1)
    inputs = tuple(f"theta_{k}" for k in range(2, scene.n + 1))
    return dataclasses.replace(scene, name=scene.name + "_driven", joints=joints, inputs=inputs)


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from codegen.pipeline import generate
    from codegen.scene import default_scene, load_scene
    from runtime import load_model, simulate
    from .timing import median_range, ratios, time_rhs_side_by_side
    try:
        links = [int(x) for x in args.links.split(",")]
    except ValueError:
        print(f"error: --links: expected integers separated by commas, got {args.links!r}", file=sys.stderr)
        return 2
    if not all(1 <= n <= 64 for n in links) or args.repeats < 1 or args.runs < 1:
        print("error: --links in 1..64, --repeats >= 1, --runs >= 1", file=sys.stderr)
        return 2
    print(f"Machine: {describe(compiler_version())}")
    print("| n | passive ns/rhs | driven ns/rhs | driven / passive | forward dynamics ops passive / driven |")
    print("|---|---|---|---|---|")
    for n in links:
        start = time.perf_counter()
        passive, driven = generate(default_scene(n)), generate(driven_variant(default_scene(n)))
        a, b = time_rhs_side_by_side([passive, driven], [100000, 100000])     # one program, alternating batches
        ratio = ratios(b, a)
        ops = {f.name: f.ops.total for f in passive.functions}["forward_dynamics"], \
            {f.name: f.ops.total for f in driven.functions}["forward_dynamics"]
        print(f"| {n} | {median_range(a, 1)} | {median_range(b, 1)} | {median_range(ratio)} | {ops[0]} / {ops[1]} |",
              flush=True)
        print(f"  (n = {n}: {time.perf_counter() - start:.1f} s)", file=sys.stderr)
    scene = load_scene("driven-fold")
    models = {"driven-fold": load_model(scene),
              "same, passive": load_model(dataclasses.replace(scene, name="fold_passive", joints=(), inputs=()))}
    times = {name: [] for name in models}
    for _ in range(args.repeats):
        for name, model in models.items():
            start = time.perf_counter()
            for _ in range(args.runs):
                run = simulate(model, 1.5, t_eval=[])
            times[name].append((time.perf_counter() - start) / args.runs * 1e3)
            times[name + " impacts"] = len(run.impacts)
    print("\n| scene (1.5 s) | ms per run, median (min-max) | impacts |")
    print("|---|---|---|")
    for name in models:
        t = times[name]
        print(f"| {name} | {np.median(t):.3f} ({min(t):.3f}-{max(t):.3f}) | {times[name + ' impacts']} |")
    return 0
