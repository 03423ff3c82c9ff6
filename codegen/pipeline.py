"""derive -> flatten (DCE + CSE) -> render: the whole generator for one scene, with timings."""
from __future__ import annotations

import time
from pathlib import Path

from .emit import GeneratedModel, render_model, render_standalone
from .flatten import flatten
from .model import build_kernels
from .scene import Scene
from .specialise import check_not_singular, layout_for


def _quiet(message: str) -> None:
    pass


def generate(scene: Scene, name: str | None = None, bake_params: bool = False,
             progress=_quiet, specialise: bool = True) -> GeneratedModel:
    """Generate the C model of ``scene``.  ``progress(message)`` is called as stages advance.

    ``specialise`` (default) leaves out what the scene does not need (see codegen.specialise);
    False gives the general model.  The returned model has .header, .source, .cdef, .functions
    (with op counts), .layout and .timings (seconds per stage: derive, cse, render).
    """
    name = name or scene.name
    layout = layout_for(scene, specialise)
    check_not_singular(scene, layout)
    timings = {}
    start = time.perf_counter()
    kernels = build_kernels(scene, bake_params, progress=lambda k: progress(f"derive {k}"), layout=layout)
    timings["derive"] = time.perf_counter() - start

    start = time.perf_counter()
    programs = []
    for kernel in kernels:
        progress(f"cse {kernel.name} ({len(kernel.tape.assignments)} tape entries)")
        programs.append(flatten(kernel))
    timings["cse"] = time.perf_counter() - start

    start = time.perf_counter()
    progress("render")
    model = render_model(scene, name, programs, bake_params, layout)
    timings["render"] = time.perf_counter() - start
    model.timings = timings
    return model


def write_model(model: GeneratedModel, out_dir: str | Path) -> list[Path]:
    """Write NAME.h and NAME.c into out_dir (created if needed); returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"{model.name}.h", out / f"{model.name}.c"]
    for path, text in zip(paths, (model.header, model.source)):
        path.write_text(text)
    return paths


def write_standalone(model: GeneratedModel, scene: Scene, out_dir: str | Path) -> list[Path]:
    """Write the example program, Makefile and CMakeLists.txt next to the model."""
    out = Path(out_dir)
    paths = []
    for filename, text in render_standalone(scene, model.name).items():
        path = out / filename
        path.write_text(text)
        paths.append(path)
    return paths
