"""Command line: python -m codegen [--links N | --scene FILE] [--out DIR] [--name NAME] [--bake-params]"""
from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path

from runtime.compile import BuildError, CompilerNotFound, compile_model, copy_library, library_sources

from .cache import CacheError, cache_dir, generate_cached
from .charts import chart_b_scene
from .interface import ROLLED_MIN_LINKS
from .options import build_options
from .outputs import output_dir_problem
from .pipeline import write_model, write_standalone
from .scene import MAX_LINKS, MAX_LINKS_REASON, Scene, SceneError, default_scene, is_c_identifier, load_scene, shipped_scene_names
from .specialise import check_not_singular, layout_for



def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m codegen",
        description="Generate C99 for the flight and impact dynamics of an n-link chain confined in a box "
                    "(recursive Gibbs-Appell; sympy -> CSE -> Jinja templates), then compile it with cffi.",
        epilog="Examples:\n"
               "  python -m codegen --links 4                 # built-in 4-link scene -> generated/chain4.{h,c}\n"
               "  python -m codegen --scene paper-case2       # a shipped scene -> generated/paper_case2.{h,c}\n"
               "  python -m codegen --scene my.toml --name robot --bake-params   # -> build/robot.{h,c}\n"
               f"Shipped scenes: {', '.join(shipped_scene_names())}.\n"
               "The generated text and the compiled module go to the cache that runtime.load_model reads "
               "($GIBBS_APPELL_CACHE, else ~/.cache/gibbs-appell-chains), so loading the same scene with "
               "the same options afterwards derives and compiles nothing.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--links", type=int, metavar="N",
                        help=f"use the built-in N-link scene (1 <= N <= {MAX_LINKS}): Table 1 links "
                             "(l = 1 m, mu = 1 kg/m), planar closed-polygon start, walls of a box that holds it; "
                             "N = 4 is the paper's case study 1 (default: 4)")
    source.add_argument("--scene", metavar="FILE",
                        help="a scene file (.toml or .json, see README) or a shipped scene name")
    parser.add_argument("--out", metavar="DIR",
                        help="directory for NAME.h and NAME.c, created if missing (default: generated/ for "
                             "--links and shipped scenes, build/ for a scene file; both relative to the "
                             "current directory)")
    parser.add_argument("--name", metavar="NAME",
                        help="C prefix and file name of the model (default: the scene's name)")
    parser.add_argument("--bake-params", action="store_true",
                        help="bake the scene's numeric parameters into the code as constants "
                             "(default: a runtime parameter array p)")
    parser.add_argument("--general", action="store_true",
                        help="generate the general model: no scene-driven specialisation (planar reduction, "
                             "zero parameters built in)")
    parser.add_argument("--one-chart", action="store_true",
                        help="leave a free base's second chart out (half the code; a run that reaches the gimbal "
                             "lock then stops there)")
    parser.add_argument("--tangent", action="store_true",
                        help="also generate the tangent kernels (exact derivatives: NAME_forward_dynamics_tangent "
                             "and gac_linearize, the run's sensitivities gac_sens_attach); straight-line forward "
                             "dynamics then, about twice the derivation time")
    parser.add_argument("--no-extended", action="store_true",
                        help="leave out the long-double variants of generalized_momentum, contact_generalized_force "
                             "and energy (NAME_*_ld): the impact's accuracy is then measured in double, coarser on "
                             "ill-conditioned chains")
    parser.add_argument("--explain", action="store_true",
                        help="print what the model leaves out for this scene and why, then stop")
    parser.add_argument("--urdf", metavar="FILE",
                        help="write the scene's chain as URDF to FILE (root link floating, revolute joints about z, a "
                             "fixed tip link), say what URDF cannot hold, then stop")
    parser.add_argument("--standalone", action="store_true",
                        help="also write NAME_example.c (simulates the scene and prints its impacts), a Makefile "
                             "and a CMakeLists.txt: everything needed to build and embed it with no Python")
    loops = parser.add_mutually_exclusive_group()
    loops.add_argument("--rolled", dest="rolled", action="store_true", default=None,
                       help="emit the forward dynamics with loops over the scene's run of identical links (small "
                            f"code; the default from {ROLLED_MIN_LINKS} links on)")
    loops.add_argument("--unrolled", dest="rolled", action="store_false",
                       help="emit the forward dynamics as straight-line code per link (the default below "
                            f"{ROLLED_MIN_LINKS} links)")
    parser.add_argument("--no-compile", action="store_true",
                        help="skip the cffi compile check/build of the generated code")
    return parser


def parse_args(argv=None) -> argparse.Namespace:
    return build_parser().parse_args(argv)


def out_dir_problem(value: str) -> str:
    """'' when --out can be created (with its parents) and written, else what is wrong and what to do."""
    problem = output_dir_problem("--out", value)
    return f"{problem}; give a directory that exists or can be created" if problem else ""


def default_out(args: argparse.Namespace) -> str:
    """build/ for a scene file, generated/ for a shipped scene or --links."""
    return "build" if args.scene is not None and Path(args.scene).exists() else "generated"


def loops_note(scene, layout, options, args) -> str:
    """How the forward dynamics will be emitted: rolled over which links, or unrolled and why."""
    if not options.rolled:
        if args.rolled is not None:
            return "straight-line code per link (--unrolled)"
        if options.tangent and scene.n >= ROLLED_MIN_LINKS:
            return "straight-line code per link (--tangent: the tangent kernels need it)"
        return f"straight-line code per link (--rolled for loops; the default from {ROLLED_MIN_LINKS} links on)"
    from .kinematics import ChainSymbols
    from .rolled import ROLL_MIN_RUN, find_run
    run = find_run(ChainSymbols(scene, options.bake_params, layout))
    if run is None:
        return (f"straight-line code per link: no run of {ROLL_MIN_RUN} identical links between link 2 and link "
                "n - 1 to loop over")
    return f"loops over links {run[0]}..{run[1]}, straight-line code for the others"


def write_urdf(scene, path: str) -> int:
    """--urdf FILE: the scene's chain as URDF (codegen.urdf), with a note for each thing URDF cannot hold."""
    from .outputs import output_file_problem
    from .urdf import scene_to_urdf
    problem = output_file_problem("--urdf", path)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    text, notes = scene_to_urdf(scene)
    try:
        Path(path).write_text(text)
    except OSError as exc:
        print(f"error: --urdf: cannot write {path}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    print(f"wrote {path}: {scene.n} links, {scene.n - 1} joints")
    for note in notes:
        print(f"  note: {note}")
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["ops"]:                      # a study, not a generation: python -m studies ops
        print(f"error: 'ops' is a study: run {shlex.join(['python', '-m', 'studies', *argv])}", file=sys.stderr)
        return 2
    args = parse_args(argv)
    t0 = time.perf_counter()

    def progress(message: str) -> None:
        print(f"[{time.perf_counter() - t0:7.2f} s] {message}", file=sys.stderr, flush=True)

    try:
        if args.scene:
            scene = load_scene(args.scene)
        else:
            n = 4 if args.links is None else args.links
            if not 1 <= n <= MAX_LINKS:
                raise SceneError(f"--links: must be in 1..{MAX_LINKS}, got {n} ({MAX_LINKS_REASON})")
            scene = default_scene(n)
        if args.name is not None:
            if not is_c_identifier(args.name):
                raise SceneError(f"--name: must be a C identifier of 1..48 characters, got {args.name!r}")
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for warning in scene.warnings:                # values that suggest a slip of units: said, not refused
        print(f"warning: {warning}", file=sys.stderr)

    try:
        options = build_options(scene, bake_params=args.bake_params, specialise=not args.general, rolled=args.rolled,
                                chart_b=not args.one_chart, tangent=args.tangent, extended=not args.no_extended)
    except ValueError as exc:
        print(f"error: --{exc}", file=sys.stderr)
        return 2
    try:
        layout = layout_for(scene, specialise=options.specialise)
        if not isinstance(scene, Scene):            # several chains: what does not compose yet is refused here
            from .combine import chain_options
            chain_options(options)
            if args.urdf:
                raise SceneError("--urdf: a scene of several chains has no URDF form (a URDF file holds one chain)")
        else:
            check_not_singular(scene, layout)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if options.rolled_required and loops_note(scene, layout, options, args).startswith("straight"):
        print(f"error: --rolled: {loops_note(scene, layout, options, args)}", file=sys.stderr)
        return 2
    if args.urdf:
        return write_urdf(scene, args.urdf)
    if args.explain:
        print(f"scene {scene.name}: n = {scene.n}; the model keeps {layout.nq} of {scene.nq} coordinates")
        for note in layout.notes:
            print(f"  - {note}")
        print(f"  - parameters: {'baked in as constants' if options.bake_params else 'a runtime array p'}")
        print(f"  - forward dynamics: {loops_note(scene, layout, options, args)}")
        if chart_b_scene(scene, layout) is not None:
            print("  - a second base chart for the gimbal lock: " + ("left out (--one-chart)" if args.one_chart else
                                                                      "generated (NAME_b_*, NAME_model_b)"))
        print("  - tangent kernels (exact derivatives): " + ("generated (--tangent)" if options.tangent else
                                                              "left out (--tangent adds them)"))
        print("  - long-double kernels for the impact's accuracy: " + ("generated (--no-extended leaves them out)"
                                                                       if options.extended else
                                                                       "left out (--no-extended)"))
        return 0

    out = args.out if args.out is not None else default_out(args)
    problem = out_dir_problem(out)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    try:
        cache_dir()
    except CacheError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2

    progress(f"scene {scene.name}: n = {scene.n} links, {layout.nq} of {scene.nq} coordinates, "
             f"{len(scene.walls)} walls, {len(layout.contacts)} contacts")
    model = generate_cached(scene, options, name=args.name, progress=progress, refresh=True)
    try:
        paths = write_model(model, out) + copy_library(out)           # the model, and the library it builds with
        if args.standalone:
            paths += write_standalone(model, scene, out, [path.name for path in library_sources()])
    except OSError as exc:
        print(f"error: --out: cannot write into {out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    timings = dict(model.timings)
    if not args.no_compile:
        start = time.perf_counter()
        try:
            compile_model(model.name, model.header, model.source, model.cdef, progress=progress,
                          digest=model.text_digest())
        except (CompilerNotFound, BuildError, CacheError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 3
        timings["compile"] = time.perf_counter() - start

    print(f"wrote {', '.join(str(p) for p in paths)}")
    print("operation counts (after CSE): total = add + mul + div + calls")
    width = max(len(f.name) for f in model.functions)
    for f in model.functions:
        o = f.ops
        print(f"  {f.name:{width}s} {o.total:7d} = {o.add} + {o.mul} + {o.div} + {o.calls}")
    print("timings: " + ", ".join(f"{stage} {seconds:.2f} s" for stage, seconds in timings.items()))
    return 0
