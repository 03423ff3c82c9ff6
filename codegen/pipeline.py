"""derive -> flatten (DCE + CSE) -> render: the whole generator for one scene, with timings."""
from __future__ import annotations

import os
import time
from dataclasses import replace
from pathlib import Path

from .charts import chart_b_scene
from .emit import GeneratedModel, assemble_model, render_extended, render_function, render_standalone
from .options import BuildOptions, build_options
from .flatten import flatten, live_assignments
from .ops import raw_count_ops
from . import interface, kernels, lagrange
from .scene import Scene, SceneError
from .specialise import check_not_singular, layout_for


FORMULATIONS = {"gibbs_appell": kernels.build_kernels, "lagrange": lagrange.build_kernels}
DYNAMICS_KERNELS = ("mass_matrix", "bias", "forward_dynamics")


def _quiet(message: str) -> None:
    pass


def generate(scene: Scene, options: BuildOptions | None = None, *, name: str | None = None, progress=_quiet,
             workers: int | None = None) -> GeneratedModel:
    """Generate the C model of ``scene`` with ``options`` (codegen.options.build_options; None: the scene's
    defaults).  ``progress(message)`` is called as stages advance.  The returned model has .header, .source,
    .cdef, .functions (with op counts), .options, .layout and .timings (seconds per stage: derive, cse, render).

    ``workers``: processes that derive, flatten and render the kernels side by side (each kernel is derived on
    its own tape, so they are independent); None: one per core (at most MAX_WORKERS) from
    PARALLEL_MIN_LINKS links on, else 1.  Workers are forked, so only a single-threaded process uses them
    (another generates serially).  The result is the same text whatever the number.
    """
    options = build_options(scene) if options is None else options
    name = name or scene.name
    if not isinstance(scene, Scene):                       # several chains in one box (codegen.combine)
        from .combine import generate_chains
        return generate_chains(scene, options, name, progress, workers, _generate)
    model = _generate(scene, name, options, progress, workers, layout_for(scene, options.specialise))
    wanted = options.chart_b and options.formulation == "gibbs_appell"
    scene_b = chart_b_scene(scene, model.layout) if wanted else None
    if scene_b is None:
        return model
    # chart B: the same chain with T_-1 turned a right angle (codegen.charts), its loop kernels only (no dense
    # ones), their tangents where chart A has them (the sensitivities go on through a switch) and their long-double
    # variants where chart A has them (an impact on chart B measures its accuracy with them), in the same NAME.c as
    # NAME_b_* and the descriptor NAME_model_b
    start = time.perf_counter()
    progress("chart B")
    model_b = _generate(scene_b, f"{name}_b", replace(options, dense=False), progress, workers,
                        model.layout)
    return assemble_model(scene, name, model.functions, options, model.layout, chart_b=(scene_b, model_b.functions),
                          timings=dict(model.timings, chart_b=time.perf_counter() - start))


def _generate(scene, name, options: BuildOptions, progress, workers, layout) -> GeneratedModel:
    """One chart's model: its kernels derived, flattened and rendered, then assembled."""
    check_not_singular(scene, layout)
    if workers is None:
        workers = min(os.cpu_count() or 1, MAX_WORKERS) if scene.n >= PARALLEL_MIN_LINKS else 1
    if workers > 1 and options.formulation == "gibbs_appell" and _can_fork():
        return _generate_in_parallel(scene, name, options, layout, workers, progress)
    timings = {}
    start = time.perf_counter()
    looped = _rolled_function(scene, options, layout) if options.rolled else None
    straight = _wants_fused(scene, options, layout)
    choices = {"fused": straight, "tangent": straight and options.tangent} \
        if options.formulation == "gibbs_appell" else {}
    if looped is not None:
        choices["skip"] = ("forward_dynamics",)
    derived = FORMULATIONS[options.formulation](scene, options.bake_params,
                                                progress=lambda k: progress(f"derive {k}"), layout=layout,
                                                dense=options.dense, **choices)
    timings["derive"] = time.perf_counter() - start

    start = time.perf_counter()
    programs = []
    for kernel in derived:
        progress(f"cse {kernel.name} ({len(kernel.tape.assignments)} tape entries)")
        programs.append(flatten(kernel))
    timings["cse"] = time.perf_counter() - start

    start = time.perf_counter()
    progress("render")
    functions = [render_function(p, options.split_size(p.kernel.name)) for p in programs]
    if looped is not None:
        functions.insert(_kernel_position("forward_dynamics", options.dense), looped)
    if options.extended:                         # the long-double variants, from the same programs (interface order)
        extended = {p.kernel.name: p for p in programs if p.kernel.name in interface.EXTENDED_OF}
        functions += [render_extended(extended[kernel]) for kernel in interface.EXTENDED_OF if kernel in extended]
    timings["render"] = time.perf_counter() - start
    return assemble_model(scene, name, functions, options, layout, timings=timings)


def raw_dynamics_ops(scene: Scene, options: BuildOptions | None = None, progress=_quiet) -> dict[str, int]:
    """sympy's ``count_ops`` of each dynamics kernel (mass_matrix, bias, forward_dynamics) before CSE: what the
    formulation hands to CSE (a study's measure of the expansion; name -> int)."""
    options = build_options(scene, dense=True) if options is None else options
    layout = layout_for(scene, options.specialise)
    derived = FORMULATIONS[options.formulation](scene, options.bake_params, layout=layout, dense=True,
                                                **({"fused": False, "tangent": False}
                                                   if options.formulation == "gibbs_appell" else {}))
    raw = {}
    for kernel in derived:
        if kernel.name in DYNAMICS_KERNELS:
            progress(f"raw count_ops {kernel.name}")
            raw[kernel.name] = raw_kernel_ops(kernel)
    return raw


_NO_RUN = ("rolled: the scene's links 2..n - 1 (n = {n}) hold no run of codegen.rolled.ROLL_MIN_RUN identical links "
           "(same kind, twists, joint spring, damper and inputs) to loop over; leave rolled unset or False")


def _kernel_position(name: str, dense: bool) -> int:
    return [b.__name__.removesuffix("_kernel") for b in kernels.builders(dense)].index(name)


def _wants_fused(scene, options: BuildOptions, layout) -> bool:
    """Whether the fused kernels (codegen.interface.FUSED_KERNELS) are generated: where the forward dynamics is
    straight-line code.  Where it is to be rolled (the scene has a run of identical links) the library forms them
    from the two kernels, so a long chain's model stays small; decided from the run alone, the same way whether
    the kernels are generated side by side or not."""
    if not options.rolled:
        return True
    from . import rolled
    from .kinematics import ChainSymbols
    return rolled.find_run(ChainSymbols(scene, options.bake_params, layout)) is None


def _rolled_function(scene, options: BuildOptions, layout):
    """forward_dynamics with loops over the scene's run of identical links, rendered; without such a run None, or
    a SceneError when the loops were required (options.rolled_required: asked for, not the default)."""
    from . import rolled
    from .kinematics import ChainSymbols
    chain = ChainSymbols(scene, options.bake_params, layout)
    built = rolled.rolled_kernel(chain)
    if built is None:
        if options.rolled_required:
            raise SceneError(_NO_RUN.format(n=scene.n))
        return None
    return rolled.render("forward_dynamics", rolled.summary(built), ("q", "qd", "u", "p"), "qdd", layout.nq, built)


PARALLEL_MIN_LINKS = 24     # below this, starting worker processes costs more than it saves
MAX_WORKERS = 4


def _can_fork() -> bool:
    """Worker processes are forked (a spawned one would re-run the caller's main module, which need not be a
    file): only from a process with a single thread, where a fork is safe."""
    import multiprocessing
    import threading
    return "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1


def _kernel_job(job):
    """Derive, flatten and render one kernel (in a worker process): (rendered functions: the kernel, then its
    long-double variant when options.extended asks for it; stage seconds)."""
    scene, options, layout, builder_name = job
    from .kinematics import ChainSymbols
    builder = next(b for b in kernels.KERNEL_BUILDERS if b.__name__ == builder_name)
    start = time.perf_counter()
    if options.rolled and builder_name == "forward_dynamics_kernel":
        function = _rolled_function(scene, options, layout)
        if function is not None:
            return [function], (time.perf_counter() - start, 0.0, 0.0)
    kernel = builder(ChainSymbols(scene, options.bake_params, layout))
    derived = time.perf_counter()
    program = flatten(kernel)
    flattened = time.perf_counter()
    functions = [render_function(program, options.split_size(kernel.name))]
    if options.extended and kernel.name in interface.EXTENDED_OF:
        functions.append(render_extended(program))
    return functions, (derived - start, flattened - derived, time.perf_counter() - flattened)


def _generate_in_parallel(scene, name, options: BuildOptions, layout, workers, progress):
    """_generate's kernels in ``workers`` processes."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    straight = _wants_fused(scene, options, layout)
    builders = kernels.builders(options.dense, straight, straight and options.tangent)
    start = time.perf_counter()
    progress(f"derive, cse and render {len(builders)} kernels in {workers} processes")
    functions, seconds = {}, [0.0, 0.0, 0.0]
    context = multiprocessing.get_context("fork")        # _can_fork: this process has one thread
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        jobs = {pool.submit(_kernel_job, (scene, options, layout, b.__name__)): b for b in builders}
        for done in as_completed(jobs):
            rendered, stages = done.result()
            functions.update((function.name, function) for function in rendered)
            seconds = [a + b for a, b in zip(seconds, stages)]
            progress(f"  {rendered[0].name}: {len(rendered[0].lines)} lines ({sum(stages):.2f} s)")
    wall = time.perf_counter() - start
    ordered = [functions[b.__name__.removesuffix("_kernel")] for b in builders]
    ordered += [functions[name] for name in interface.EXTENDED_KERNELS if name in functions]
    timings = {"derive": seconds[0], "cse": seconds[1], "render": seconds[2], "parallel_wall": wall}
    return assemble_model(scene, name, ordered, options, layout, timings=timings)


def raw_kernel_ops(kernel) -> int:
    """sympy count_ops of what a kernel hands to CSE: its live tape entries and its distinct outputs."""
    expressions = [e for _, e in live_assignments(kernel)] + list(dict.fromkeys(kernel.values))
    return raw_count_ops(expressions)


def write_model(model: GeneratedModel, out_dir: str | Path) -> list[Path]:
    """Write NAME.h and NAME.c into out_dir (created if needed); returns the paths.  They build with the C library
    (gac.h, gac_*.c), which the build layer copies beside them: runtime.compile.copy_library."""
    return _write_files(out_dir, {f"{model.name}.h": model.header, f"{model.name}.c": model.source})


def write_standalone(model: GeneratedModel, scene: Scene, out_dir: str | Path,
                     library_sources: list[str]) -> list[Path]:
    """Write the example program, Makefile and CMakeLists.txt next to the model and its library copy;
    ``library_sources``: the file names of the library's C sources (runtime.compile.library_sources)."""
    return _write_files(out_dir, render_standalone(scene, model.name, library_sources, model.layout))


def _write_files(out_dir: str | Path, files: dict[str, str]) -> list[Path]:
    """Write every file to a temporary name first, then rename them all into place: a failure
    (disk full, permissions) leaves no half-written file behind."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    staged = []
    try:
        for filename, text in files.items():
            tmp = out / f".{filename}.{os.getpid()}.tmp"
            staged.append((tmp, out / filename))
            tmp.write_text(text)
        for tmp, path in staged:
            tmp.replace(path)
    finally:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
    return [path for _, path in staged]
