"""python -m runtime simulate --scene paper-case1 [--t-end T] [--method M] [--rtol R --atol A | --dt H]
                              [--json FILE] [--plot DIR]"""
from __future__ import annotations

import argparse
import json
import math
import re
import shlex
import sys
import time
from pathlib import Path

from codegen.scene import MAX_LINKS, shipped_scene_names

from .compile import BuildError, CacheError, CompilerNotFound
from .model import load_model
from codegen.outputs import output_dir_problem, output_file_problem
from .horizon import scene_and_horizon
from .model import CHOSEN_LAWS
from .simulate import DEFAULT_ATOL, DEFAULT_RTOL, METHODS, RTOL_MIN, simulate

STUDIES = ("precision", "stress", "fuzz")     # studies: python -m studies STUDY
TABLE_ROWS = 20        # impacts and contact events printed in full up to this many, else the first and last half

# The simulate() arguments a message may advise changing, as this command's options
CLI_OPTIONS = {"max_impacts": "--max-impacts", "max_steps": "--max-steps", "max_wall_time": "--max-wall-time",
               "rtol": "--rtol", "atol": "--atol", "reduce dt": "reduce --dt"}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m runtime",
                                     description="Run hybrid (flight + impact) simulations of generated models.")
    commands = parser.add_subparsers(dest="command", required=True)
    sim = commands.add_parser("simulate", help="simulate a scene and print its impact table",
                              description="Simulate a scene: flight in compiled code, impacts by Eq. 48 "
                                          "(complementarity form when a contact would pull).",
                              epilog=f"Shipped scenes: {', '.join(shipped_scene_names())}.")
    which = sim.add_mutually_exclusive_group()
    which.add_argument("--scene", default=None, help="shipped scene name, .toml/.json scene file, or .urdf file (its "
                       "chain in a default box: docs/scenes.md) (default paper-case1)")
    which.add_argument("--links", type=int, default=None, metavar="N",
                       help=f"the built-in N-link chain of python -m codegen --links N (1..{MAX_LINKS}; N = 4 is the "
                            "paper's case study 1)")
    sim.add_argument("--t-end", type=float, default=None,
                     help="end time in s (default: 1.5 for paper-case1, 1.75 for paper-case2, else 1.0)")
    sim.add_argument("--method", choices=METHODS, default="dopri5", help="integrator (default dopri5)")
    sim.add_argument("--rtol", type=float, default=DEFAULT_RTOL,
                     help=f"dopri5/dop853 relative tolerance (default {DEFAULT_RTOL:g})")
    sim.add_argument("--atol", type=float, default=DEFAULT_ATOL,
                     help=f"dopri5/dop853 absolute tolerance (default {DEFAULT_ATOL:g})")
    sim.add_argument("--dt", type=float, default=None, help="rk4 step in s (required for rk4; the paper used 1e-5)")
    sim.add_argument("--samples-dt", type=float, default=1e-3,
                     help=f"output sample spacing in s (default 1e-3; at most {MAX_SAMPLES:,} samples)")
    sim.add_argument("--json", metavar="FILE", help="write the result (impacts, final state, energies) as JSON")
    sim.add_argument("--plot", metavar="DIR", help="write PNG plots (time histories, impact configurations)")
    sim.add_argument("--charts", action="store_true", help="kept for old command lines: near the gimbal lock "
                     "theta_0 = +-pi/2 the C loop switches to the model's second base chart by default")
    sim.add_argument("--no-charts", action="store_true", help="stop at the gimbal lock of the base chart instead")
    sim.add_argument("--impact-law", choices=CHOSEN_LAWS, default="gdi",
                     help="the impact law at walls with friction: gdi (default; never gains energy), newton-coulomb "
                          "(can gain energy: the run then stops) or frictionless")
    sim.add_argument("--no-stick", action="store_true", help="points resting on rough walls take the regularised "
                     "friction alone (below friction_velocity a viscous force) instead of sticking")
    sim.add_argument("--max-impacts", type=int, default=10000, metavar="N",
                     help="stop the run after this many impacts (default 10000)")
    sim.add_argument("--max-steps", type=int, default=10_000_000, metavar="N",
                     help="integrator steps allowed between two events (default 10000000; 0: unbounded)")
    sim.add_argument("--all-impacts", action="store_true",
                     help=f"print every impact (default: all up to {TABLE_ROWS}, else the first and last "
                          f"{TABLE_ROWS // 2})")
    sim.add_argument("--max-wall-time", type=float, default=None, metavar="S",
                     help="stop the run after S seconds of wall time, saying where the time went")
    sim.add_argument("--input", metavar="U1,U2", default=None,
                     help="constant inputs of a driven scene, one per actuated coordinate in the order of the "
                          "scene's inputs list (N m on an angle, N on a translation; default 0)")
    sim.add_argument("--param", metavar="NAME=VALUE", action="append", default=[],
                     help="override one parameter by name (repeatable), e.g. --param e_x2_min=0.5 "
                          "--param stiffness_2=30")
    outputs = sim.add_argument_group("sample exports")
    outputs.add_argument("--csv", metavar="FILE", help="write the samples (t, q, qd, inputs, joint points O_i) as CSV")
    outputs.add_argument("--npz", metavar="FILE", help="write the samples and the impacts as a numpy .npz")
    outputs.add_argument("--animate", metavar="FILE", help="write an animation of the run (.gif, or .mp4 with ffmpeg)")
    outputs.add_argument("--fps", type=int, default=30, help="frames per second of --animate (default 30)")
    outputs.add_argument("--film-strip", metavar="FILE", help="write the chain at --film-times side by side (PNG)")
    outputs.add_argument("--film-times", metavar="T1,T2,...", default=None,
                         help="times of the --film-strip panels in s (default: 5 evenly spaced)")

    sweep = commands.add_parser(
        "sweep", help="run a grid or random sample over parameters and start coordinates",
        description="Sweep parameters (NAME) and start coordinates (q.NAME, qd.NAME) of a scene; runs in parallel "
                    "(threads, processes or a Dask cluster) and writes DIR/runs.csv, DIR/runs.npz, DIR/sweep.png.",
        epilog="Example: python -m runtime sweep --scene paper-case1 --vary e_x2_min=0.05:1:20 "
               "--vary q.theta_2=-0.1:0.1:10 --workers 2 --out sweep")
    sweep.add_argument("--scene", default="paper-case1", help="shipped scene name or .toml/.json file")
    sweep.add_argument("--vary", action="append", default=[], metavar="NAME=LO:HI:N", required=True,
                       help="vary a parameter or q.NAME / qd.NAME over N values from LO to HI (repeatable, at most 6: "
                            "a grid; sweep.png draws the third and later as panels)")
    sweep.add_argument("--samples", type=int, default=None, metavar="N",
                       help="N random points, uniform in the --vary ranges, instead of the grid")
    sweep.add_argument("--seed", type=int, default=0, help="random seed of --samples (default 0)")
    sweep.add_argument("--t-end", type=float, default=None, help="end time of every run in s (default: the scene's)")
    sweep.add_argument("--workers", type=int, default=2, help="local worker processes (default 2; 1: serial)")
    sweep.add_argument("--threads", action="store_true", help="local threads instead of processes")
    sweep.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help="run on this Dask scheduler (tcp://host:8786), or 'local': a Dask LocalCluster of "
                            "--workers processes started for the sweep")
    sweep.add_argument("--rtol", type=float, default=DEFAULT_RTOL, help=f"relative tolerance (default {DEFAULT_RTOL:g})")
    sweep.add_argument("--atol", type=float, default=DEFAULT_ATOL, help=f"absolute tolerance (default {DEFAULT_ATOL:g})")
    sweep.add_argument("--out", metavar="DIR", required=True, help="folder for runs.csv, runs.npz and sweep.png")

    fmu = commands.add_parser(
        "fmu", help="package a scene's model as an FMI 2.0 Co-Simulation FMU (DIR/NAME.fmu)",
        description="Build NAME.fmu: modelDescription.xml, the C sources and a shared library for this platform. "
                    "Each fmi2DoStep runs the hybrid loop (flight, impacts, resting contact) inside the FMU.",
        epilog="Example: python -m runtime fmu --scene driven-fold --out build   (then e.g. fmpy simulate "
               "build/driven_fold.fmu)")
    fmu.add_argument("--scene", default="paper-case1", help="shipped scene name or .toml/.json file")
    fmu.add_argument("--out", metavar="DIR", default="build", help="folder for NAME.fmu (default build)")
    fmu.add_argument("--name", metavar="NAME", default=None, help="model identifier (default: the scene's name)")
    fmu.add_argument("--bake-params", action="store_true",
                     help="bake the parameters into the code (the FMU then has no parameter variables p.*)")
    fmu.add_argument("--general", action="store_true", help="the general model (no scene-driven specialisation)")
    fmu.add_argument("--t-end", type=float, default=None,
                     help="stop time of the FMU's default experiment in s (default: the scene's usual horizon)")
    fmu.add_argument("--step", type=float, default=1e-3,
                     help="communication step of the default experiment in s (default 0.001)")
    return parser


MAX_SAMPLES = 10_000_000     # output samples of one run (each 2 nq doubles): 1 GB for a 4-link chain


def tolerance_problem(rtol: float, atol: float) -> str | None:
    """The message for --rtol/--atol outside what the C loop accepts (GAC_RTOL_MIN <= rtol < 1, atol > 0)."""
    if not (RTOL_MIN <= rtol < 1):
        return f"--rtol: must be a tolerance in [{RTOL_MIN:g}, 1), got {rtol}"
    if not (0 < atol < 1e300):
        return f"--atol: must be a finite tolerance > 0, got {atol}"
    return None


def in_cli_words(message: str) -> str:
    """A simulate() message with the arguments it advises changing named as this command's options."""
    for word, option in CLI_OPTIONS.items():
        message = re.sub(rf"(?<![\w-]){re.escape(word)}(?![\w])", option, message)
    return message


def smallest_spacing(t_end: float) -> float:
    """The smallest sample spacing, to 3 significant digits, that keeps t_end / spacing + 1 <= MAX_SAMPLES."""
    spacing = t_end / (MAX_SAMPLES - 1)
    scale = 10.0 ** (math.floor(math.log10(spacing)) - 2)
    spacing = math.ceil(spacing / scale) * scale
    while t_end / spacing + 1 > MAX_SAMPLES:       # round-off of the rounding itself
        spacing += scale
    return float(f"{spacing:.6g}")


def simulate_arguments_problem(args, t_end: float) -> str:
    """What is wrong with the simulate command's numbers and output paths ('' when nothing is), checked
    before the model is built so that a bad argument costs nothing and writes nothing."""
    if not (math.isfinite(t_end) and t_end >= 0):
        return f"--t-end: must be a finite time >= 0 s, got {t_end}"
    if not (math.isfinite(args.samples_dt) and args.samples_dt > 0):
        return f"--samples-dt: must be a finite spacing > 0 s, got {args.samples_dt}"
    samples = t_end / args.samples_dt + 1
    if samples > MAX_SAMPLES:
        return (f"--samples-dt: {args.samples_dt:g} s over t_end = {t_end:g} s asks for {samples:.3g} samples; at most "
                f"{MAX_SAMPLES:,} (give --samples-dt >= {smallest_spacing(t_end):.6g} s)")
    problem = tolerance_problem(args.rtol, args.atol)
    if problem:
        return problem
    if args.dt is not None and not (math.isfinite(args.dt) and args.dt > 0):
        return f"--dt: must be a finite step > 0 s, got {args.dt}"
    if args.method == "rk4" and args.dt is None:
        return "--dt: rk4 needs a step (e.g. --dt 1e-5, the paper's)"
    if args.max_impacts < 1:
        return f"--max-impacts: must be an integer >= 1, got {args.max_impacts}"
    if args.max_steps < 0:
        return f"--max-steps: must be an integer >= 0 (0: unbounded), got {args.max_steps}"
    if args.max_wall_time is not None and not (math.isfinite(args.max_wall_time) and args.max_wall_time > 0):
        return f"--max-wall-time: must be a finite time > 0 s, got {args.max_wall_time}"
    if args.charts and args.no_charts:
        return "--charts and --no-charts: give at most one"
    if args.input is not None:
        try:
            values = [float(v) for v in args.input.split(",")]
        except ValueError:
            return f"--input: expected numbers separated by commas, got {args.input!r}"
        if not all(math.isfinite(v) for v in values):
            return f"--input: must be finite, got {args.input!r}"
    for item in args.param:
        name, _, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            return f"--param: expected NAME=VALUE with a number, got {item!r}"
        if not name or not math.isfinite(number):
            return f"--param: expected NAME=VALUE with a finite number, got {item!r}"
    if args.animate or args.film_strip:
        import importlib.util
        if importlib.util.find_spec("matplotlib") is None:
            return "--animate/--film-strip: needs matplotlib, which is not installed (pip install -e \".[plot]\")"
    if args.animate:
        from .animate import animation_problem
        problem = animation_problem(args.animate)
        if problem:
            return problem
        if not 1 <= args.fps <= 120:
            return f"--fps: must be in 1..120, got {args.fps}"
    if args.film_times is not None:
        try:
            times = [float(x) for x in args.film_times.split(",")]
        except ValueError:
            return f"--film-times: expected times in s separated by commas, got {args.film_times!r}"
        if not times or len(times) > 26 or not all(0.0 <= x <= t_end for x in times):
            return f"--film-times: 1 to 26 times within [0, t_end = {t_end:g}] s, got {args.film_times!r}"
    for option in ("json", "csv", "npz", "animate", "film_strip"):
        if getattr(args, option):
            problem = output_file_problem(f"--{option.replace('_', '-')}", getattr(args, option))
            if problem:
                return problem
    if args.plot:
        import importlib.util
        if importlib.util.find_spec("matplotlib") is None:
            return "--plot: needs matplotlib, which is not installed (pip install -e \".[plot]\")"
        return output_dir_problem("--plot", args.plot)
    return ""


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] and argv[0] in STUDIES:
        print(f"error: {argv[0]!r} is a study: run {shlex.join(['python', '-m', 'studies', *argv])}", file=sys.stderr)
        return 2
    args = build_parser().parse_args(argv)
    if args.command == "sweep":
        return sweep_main(args)
    if args.command == "fmu":
        return fmu_main(args)
    loaded = scene_and_horizon(args)
    if loaded is None:
        return 2
    scene, t_end = loaded
    problem = simulate_arguments_problem(args, t_end)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    try:
        progress = lambda m: print(f"  {m}", file=sys.stderr, flush=True)  # noqa: E731
        model = load_model(scene, progress=progress)
    except (CompilerNotFound, BuildError, CacheError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    prepared = time.perf_counter() - start
    import numpy as np
    t_eval = np.unique(np.r_[np.arange(0.0, t_end, args.samples_dt), t_end]) if t_end > 0 else np.array([0.0])
    try:
        start = time.perf_counter()
        u = None if args.input is None else [float(v) for v in args.input.split(",")]
        p = {name: float(value) for name, _, value in (item.partition("=") for item in args.param)} or None
        result = simulate(model, t_end, method=args.method, rtol=args.rtol, atol=args.atol, dt=args.dt,
                          t_eval=t_eval, charts=not args.no_charts, max_wall_time=args.max_wall_time, u=u, p=p,
                          max_impacts=args.max_impacts, max_steps=args.max_steps, impact_law=args.impact_law,
                          stick=not args.no_stick)
        elapsed = time.perf_counter() - start
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.scene and str(args.scene).lower().endswith(".urdf"):
        print(f"scene {scene.name}: {scene.description}")
    print(f"scene {scene.name}: n = {scene.n}, t_end = {t_end} s, method {args.method}"
          + (f" dt = {args.dt}" if args.method == "rk4" else f" rtol = {args.rtol} atol = {args.atol}"))
    limit = None if args.all_impacts else TABLE_ROWS
    print(result.impact_table(limit))
    if getattr(result, "contact_events", None):
        print(result.contact_event_table(limit))
    if limit is not None and max(len(result.impacts), len(getattr(result, "contact_events", ()))) > limit:
        print("(every impact and contact event: --all-impacts, or --json FILE)")
    print(f"status {result.status}: {in_cli_words(result.message)}")
    if result.status != 0 and args.no_charts and "gimbal lock" in result.message:
        print("hint: without --no-charts the run continues on a second chart")
    print(result.energy_summary())
    print(f"steps {result.n_steps} (rejected {result.n_rejected}), rhs evaluations {result.n_rhs}, "
          f"simulation {elapsed * 1e3:.2f} ms, model ready in {prepared:.2f} s")
    for warning in result.warnings:
        if warning not in scene.warnings:         # the scene's own were printed when it was loaded
            print(f"warning: {warning}", file=sys.stderr)
    if args.json:
        try:
            Path(args.json).write_text(json.dumps(result.to_json(), indent=1))
        except OSError as exc:
            print(f"error: --json: cannot write {args.json}: {exc.strerror or exc}", file=sys.stderr)
            return 2
        print(f"wrote {args.json}")
    if args.animate:
        from .animate import animate
        frames = animate(result, scene, args.animate, fps=args.fps,
                         progress=lambda m: print(f"  animate: {m}", file=sys.stderr, flush=True),
                         model=model, p=model.parameters(p))
        print(f"wrote {args.animate} ({frames} frames)")
    if args.film_strip:
        from .animate import film_strip
        times = ([float(x) for x in args.film_times.split(",")] if args.film_times
                 else list(np.linspace(0.0, result.t[-1] if len(result.t) else 0.0, 5)))
        film_strip(result, scene, args.film_strip, times, model=model, p=model.parameters(p))
        print(f"wrote {args.film_strip}")
    for option, writer in (("csv", "write_csv"), ("npz", "write_npz")):
        if getattr(args, option):
            from . import export
            try:
                getattr(export, writer)(result, getattr(args, option), scene)
            except OSError as exc:
                print(f"error: --{option}: cannot write {getattr(args, option)}: {exc.strerror or exc}", file=sys.stderr)
                return 2
            print(f"wrote {getattr(args, option)}")
    if args.plot:
        from .plots import plot_all
        try:
            paths = plot_all(model, result, args.plot)
        except RuntimeError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        print("wrote " + ", ".join(str(p) for p in paths))
    return 0 if result.success else 1


def sweep_main(args) -> int:
    """python -m runtime sweep: check every argument, build the model, run, write the table and the plot."""
    import math
    from .sweep import build_runs, check_names, parse_vary, plot_sweep
    loaded = scene_and_horizon(args)
    if loaded is None:
        return 2
    scene, t_end = loaded
    try:
        varies = [parse_vary(text) for text in args.vary]
        check_names(varies, scene.parameter_names(), scene.n)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    problems = [
        (not (math.isfinite(t_end) and t_end >= 0), f"--t-end: must be a finite time >= 0 s, got {t_end}"),
        (args.samples is not None and not 1 <= args.samples <= 10_000_000,
         f"--samples: must be in 1..10000000, got {args.samples}"),
        (args.workers < 1 or args.workers > 1024, f"--workers: must be in 1..1024, got {args.workers}"),
        (bool(tolerance_problem(args.rtol, args.atol)), tolerance_problem(args.rtol, args.atol)),
    ]
    count = args.samples or math.prod(v.count for v in varies)
    problems.append((count > 10_000_000, f"--vary: the grid has {count:,} runs; at most 10,000,000"))
    problems.append((bool(output_dir_problem("--out", args.out)), output_dir_problem("--out", args.out)))
    import importlib.util
    for module, extra in (("tqdm", "ensemble"), ("matplotlib", "plot")):
        problems.append((importlib.util.find_spec(module) is None,
                         f"sweep: needs {module}, which is not installed (pip install -e \".[{extra}]\")"))
    if args.scheduler:
        problems.append((importlib.util.find_spec("distributed") is None,
                         "--scheduler: needs dask.distributed (pip install -e \".[ensemble]\")"))
    for bad, message in problems:
        if bad:
            print(f"error: {message}", file=sys.stderr)
            return 2
    from .ensemble import simulate_many
    try:
        model = load_model(scene, progress=lambda m: print(f"  {m}", file=sys.stderr, flush=True))
    except (CompilerNotFound, BuildError, CacheError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    runs = build_runs(varies, args.samples, args.seed)
    where = (f"Dask scheduler {args.scheduler}" if args.scheduler else
             f"{args.workers} local {'threads' if args.threads else 'processes'}" if args.workers > 1 else "serially")
    print(f"sweep {scene.name}: {len(runs):,} runs of {t_end} s, {where}", file=sys.stderr)
    cluster = client = None
    if args.scheduler == "local":
        from distributed import Client, LocalCluster
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        study = simulate_many(model, runs, t_end, workers=args.workers, processes=not args.threads,
                              client=client or args.scheduler, keep="final", progress=True, rtol=args.rtol,
                              atol=args.atol, t_eval=[])
    finally:
        if client is not None:
            client.close()
            cluster.close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    study.to_csv(out / "runs.csv")
    study.to_npz(out / "runs.npz")
    plot_sweep(study, varies, out / "sweep.png")
    failed = sum(1 for row in study.rows if row["status"] != 0)
    print(f"{len(runs):,} runs in {study.seconds:.2f} s ({len(runs) / max(study.seconds, 1e-9):,.0f} runs/s), "
          f"{failed} stopped early or refused; wrote {out / 'runs.csv'}, {out / 'runs.npz'}, {out / 'sweep.png'}")
    return 0


def fmu_main(args) -> int:
    """python -m runtime fmu: build DIR/NAME.fmu and say where it is."""
    from codegen.scene import SceneError, is_c_identifier
    from .fmu import build_fmu
    import math
    problem = output_dir_problem("--out", args.out)
    for option, value in (("--t-end", args.t_end), ("--step", args.step)):
        if not problem and value is not None and not (math.isfinite(value) and value > 0):
            problem = f"{option}: must be a finite time > 0 s, got {value}"
    if not problem and args.name is not None and not is_c_identifier(args.name):
        problem = f"--name: must be a C identifier of 1..48 characters, got {args.name!r}"
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    progress = lambda m: print(f"  {m}", file=sys.stderr, flush=True)  # noqa: E731
    try:
        path = build_fmu(args.scene, args.out, name=args.name, bake_params=args.bake_params,
                         specialise=not args.general, stop_time=args.t_end, step_size=args.step, progress=progress)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (CompilerNotFound, BuildError, CacheError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} kB, FMI 2.0 Co-Simulation) in "
          f"{time.perf_counter() - start:.2f} s")
    return 0
