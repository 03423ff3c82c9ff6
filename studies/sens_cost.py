"""What the sensitivities of a run cost: `simulate(..., sensitivities=k directions)` against the plain run on the
scene of docs/simulation.md's table (a twisted 3-link chain, slender, rigid, slender -- the test suite's
chain(3, ("line", "rigid"), twists=True) -- thrown in a box of half-width 3 m with g = 0 and random restitutions,
tests/test_sim_sensitivities.py's box run of seed 6: 3 impacts over 1.5 s at rtol 1e-10, DOPRI5).  The directions
are the first k of q0 of the model's coordinates, then qd0.  Process time per run, median of --repeats runs; the
k variants interleaved run by run, and the whole measured --passes times.

    python -m studies sensitivities [--k 0,1,4,12] [--repeats 9] [--passes 2]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

BOX = 3.0
SCENE_SEED = 5322          # the test suite's seed of chain(3, ("line", "rigid"), twists=True)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies sensitivities", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--k", default="0,1,4,12", help="numbers of directions, comma-separated; 0: the plain run "
                        "(default 0,1,4,12)")
    parser.add_argument("--repeats", type=int, default=9, help="timed runs per k and pass (default 9)")
    parser.add_argument("--passes", type=int, default=2, help="times the whole measurement is made (default 2)")
    return parser


def scene():
    """The suite's chain(3, ("line", "rigid"), twists=True) (tests/conftest.py's random_scene of its seed)."""
    from codegen.scene import WALL_NAMES, LineLink, RigidLink, Scene, Wall
    from . import reference
    rng = np.random.default_rng(SCENE_SEED)
    links = []
    for kind in ("line", "rigid", "line"):
        if kind == "line":
            links.append(LineLink(rng.uniform(0.2, 2.0), rng.uniform(0.1, 3.0), tuple(rng.uniform(0.0, 1e-2, 3))))
            continue
        l, m, h, K = reference.random_link(rng)
        com = h / m
        inertia = K - m * (com @ com * np.eye(3) - np.outer(com, com))
        links.append(RigidLink(l, m, tuple(com), tuple(map(tuple, (inertia + inertia.T) / 2))))
    twists = tuple(tuple(map(tuple, reference.random_rotation(rng))) for _ in range(2))
    walls = tuple(Wall(w, -50.0 if w.endswith("min") else 50.0, rng.uniform(0, 1)) for w in WALL_NAMES)
    return Scene(name="chain3_line_rigid_tw", links=links, twists=twists, gravity=rng.uniform(0, 12), walls=walls,
                 q0=(0.0,) * 8)


def box_run(seed: int = 6):
    """The box run of tests/test_sim_sensitivities.py: (parameter overrides, q0, qd0)."""
    rng = np.random.default_rng(seed)
    over = {"g": 0.0}
    for axis in ("x1", "x2", "x3"):
        over[f"wall_{axis}_min"], over[f"wall_{axis}_max"] = -BOX, BOX
        over[f"e_{axis}_min"], over[f"e_{axis}_max"] = rng.uniform(0.5, 1.0, 2)
    q0 = np.zeros(8)
    q0[2:5] = rng.uniform(-0.5, 0.5, 3)
    q0[5:8] = -0.3
    qd0 = rng.normal(0, 2.0, 8)
    qd0[:2] *= 0.2
    return over, q0, qd0


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        ks = sorted({int(k) for k in args.k.split(",")})
    except ValueError:
        print(f"--k: expected numbers like 0,1,4,12, got {args.k!r}", file=sys.stderr)
        return 2
    from codegen.scene import coordinate_names
    from runtime import load_model, simulate
    model = load_model(scene(), tangent=True)
    own = [coordinate_names(model.n)[i] for i in model.layout.free]
    directions = [f"q0[{c}]" for c in own] + [f"qd0[{c}]" for c in own]
    if ks[0] < 0 or ks[-1] > len(directions) or args.repeats < 1 or args.passes < 1:
        print(f"--k: each in 0..{len(directions)}; --repeats, --passes >= 1", file=sys.stderr)
        return 2
    over, q0, qd0 = box_run()
    options = dict(p=model.parameters(over), q0=q0, qd0=qd0, rtol=1e-10, atol=1e-12)

    def run(k):
        return simulate(model, 1.5, sensitivities=directions[:k] if k else None, **options)

    check = run(max(ks))
    print(f"# {model.name}: nq = {model.nq}, {len(check.impacts)} impacts, {check.n_steps} steps over 1.5 s; "
          f"sensitivities {check.sensitivity_status if max(ks) else 'none'}")
    print("pass | " + " | ".join(f"k = {k}: ms (x plain)" for k in ks))
    for number in range(args.passes):
        samples = {k: [] for k in ks}
        for _ in range(args.repeats):
            for k in ks:
                start = time.process_time()
                run(k)
                samples[k].append(time.process_time() - start)
        median = {k: 1e3 * statistics.median(v) for k, v in samples.items()}
        base = median.get(0)
        print(f"{number + 1} | " + " | ".join(
            f"{median[k]:.2f}" + (f" ({median[k] / base:.1f})" if base else "") for k in ks))
    return 0


if __name__ == "__main__":
    sys.exit(main())
