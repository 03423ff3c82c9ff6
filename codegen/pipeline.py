"""derive -> flatten (DCE + CSE) -> render: the whole generator for one scene, with timings."""
from __future__ import annotations

import os
import time
from pathlib import Path

from .artifact import library_files
from .emit import GeneratedModel, render_model, render_standalone
from .flatten import flatten, live_assignments
from .ops import raw_count_ops
from . import kernels, lagrange
from .scene import Scene
from .specialise import check_not_singular, layout_for


FORMULATIONS = {"gibbs_appell": kernels.build_kernels, "lagrange": lagrange.build_kernels}
DYNAMICS_KERNELS = ("mass_matrix", "bias", "forward_dynamics")


def _quiet(message: str) -> None:
    pass


def generate(scene: Scene, name: str | None = None, bake_params: bool = False,
             progress=_quiet, specialise: bool = True, formulation: str = "gibbs_appell",
             raw_ops: bool = False, dense: bool | None = None, split_lines: int | None = None) -> GeneratedModel:
    """Generate the C model of ``scene``.  ``progress(message)`` is called as stages advance.

    ``specialise`` (default) leaves out what the scene does not need (see codegen.specialise);
    False gives the general model.  The returned model has .header, .source, .cdef, .functions
    (with op counts), .layout and .timings (seconds per stage: derive, cse, render).

    ``formulation`` chooses how the dynamics kernels (mass_matrix, bias, forward_dynamics) are derived:
    "gibbs_appell" (the paper's recursion, codegen.kernels) or "lagrange" (an explicit Euler-Lagrange
    expansion, codegen.lagrange, for comparison); the other kernels are the same.  ``raw_ops`` also
    records sympy's ``count_ops`` of each dynamics kernel before CSE in ``.raw_ops`` (name -> int).

    ``dense``: generate the dense kernels mass_matrix, bias, contact_jacobian (O(n^2) code; the hybrid loop
    does not need them); None (default) does for n <= codegen.interface.DENSE_MAX_LINKS, and otherwise the
    model forms them at run time from its O(n) kernels.  ``split_lines``: cut kernels longer than this into
    parts (None: codegen.emit's defaults).
    """
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation: must be one of {', '.join(FORMULATIONS)}, got {formulation!r}")
    name = name or scene.name
    layout = layout_for(scene, specialise)
    check_not_singular(scene, layout)
    timings = {}
    start = time.perf_counter()
    if formulation == "lagrange" and dense is None:
        dense = True
    derived = FORMULATIONS[formulation](scene, bake_params, progress=lambda k: progress(f"derive {k}"),
                                        layout=layout, dense=dense)
    timings["derive"] = time.perf_counter() - start
    raw = {}
    if raw_ops:
        for kernel in derived:
            if kernel.name in DYNAMICS_KERNELS:
                progress(f"raw count_ops {kernel.name}")
                raw[kernel.name] = raw_kernel_ops(kernel)

    start = time.perf_counter()
    programs = []
    for kernel in derived:
        progress(f"cse {kernel.name} ({len(kernel.tape.assignments)} tape entries)")
        programs.append(flatten(kernel))
    timings["cse"] = time.perf_counter() - start

    start = time.perf_counter()
    progress("render")
    model = render_model(scene, name, programs, bake_params, layout, split_lines)
    timings["render"] = time.perf_counter() - start
    model.timings = timings
    model.formulation = formulation
    model.raw_ops = raw
    return model


def raw_kernel_ops(kernel) -> int:
    """sympy count_ops of what a kernel hands to CSE: its live tape entries and its distinct outputs."""
    expressions = [e for _, e in live_assignments(kernel)] + list(dict.fromkeys(kernel.values))
    return raw_count_ops(expressions)


def write_model(model: GeneratedModel, out_dir: str | Path) -> list[Path]:
    """Write NAME.h and NAME.c into out_dir (created if needed), with a copy of the C library they build
    with (gac.h, gac_internal.h, gac_*.c from runtime/c); returns the paths."""
    files = {f"{model.name}.h": model.header, f"{model.name}.c": model.source}
    files.update((path.name, path.read_text()) for path in library_files())
    return _write_files(out_dir, files)


def write_standalone(model: GeneratedModel, scene: Scene, out_dir: str | Path) -> list[Path]:
    """Write the example program, Makefile and CMakeLists.txt next to the model (and its library copy)."""
    sources = [path.name for path in library_files() if path.suffix == ".c"]
    return _write_files(out_dir, render_standalone(scene, model.name, sources, model.layout))


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
