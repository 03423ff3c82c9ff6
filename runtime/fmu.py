"""Package a scene's model as an FMI 2.0 Co-Simulation FMU: modelDescription.xml, the C sources (the model, the
library gac, the FMI slave gac_fmi2.c) and a shared library built for this platform, zipped into NAME.fmu.

Any FMI 2.0 importer (FMPy, OpenModelica, Simulink, Dymola, a SSP or DCP tool) can then run the chain's hybrid
dynamics: each fmi2DoStep integrates the flight, applies every impact and keeps resting contacts inside the FMU.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from codegen.options import build_options
from codegen.scene import Chains, Scene, SceneError, load_scene

from .compile import (LIBRARY_DIR, PARALLEL_LINES, BuildError, compile_objects, compiler_command, library_files,
                      translation_units)
from .header import fmi2_rows, library_constants
from .horizon import DEFAULT_T_END

FMI2_DIR = LIBRARY_DIR / "fmi2"          # gac_fmi2.c, gac_fmi2.h, fmi2_types.h: the slave, for any model
FLAGS = ("-std=c99", "-O2", "-fvisibility=hidden")   # only the fmi2* functions are exported (GAC_FMI2_EXPORT)
DEFAULT_STEP = 1e-3                      # s: the DefaultExperiment's communication step


def fmi_platform() -> tuple[str, str]:
    """The FMI 2.0 binaries folder and shared-library suffix of this machine, or BuildError."""
    bits64 = sys.maxsize > 2 ** 32
    if sys.platform.startswith("linux"):
        return ("linux64" if bits64 else "linux32"), ".so"
    if sys.platform == "darwin":
        return "darwin64", ".dylib"
    raise BuildError(f"building an FMU binary on {sys.platform!r} is not supported: the FMU's sources/ folder "
                     "holds everything to build it with your compiler (see docs/fmi.md)")


def fmi2_sources() -> list[Path]:
    """The slave's files, shipped in every FMU beside the model and the library."""
    return sorted(path for path in FMI2_DIR.iterdir() if path.suffix in (".c", ".h"))


def build_fmu(scene: Scene | Chains | str | Path, out_dir: str | Path = "build", *, name: str | None = None,
              bake_params: bool = False, specialise: bool = True, rolled: bool | None = None,
              stop_time: float | None = None, step_size: float = DEFAULT_STEP, progress=None) -> Path:
    """Generate (or take from the cache) the scene's model, build it as an FMU in ``out_dir`` and return the
    path of NAME.fmu.  ``stop_time`` and ``step_size`` (s) go into its DefaultExperiment (stop_time: the scene's
    usual horizon by default).  Raises SceneError for a bad scene or argument, CompilerNotFound or BuildError."""
    from codegen.cache import generate_cached       # the generator loads only when an FMU is built
    from codegen.fmu import fmu_texts

    say = progress or (lambda message: None)
    if not isinstance(scene, (Scene, Chains)):
        scene = load_scene(scene)
    if stop_time is None:
        stop_time = DEFAULT_T_END.get(scene.name, 1.0)
    for label, value in (("stop_time", stop_time), ("step_size", step_size)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise SceneError(f"{label}: must be a finite number of seconds > 0, got {value!r}")
    folder, suffix = fmi_platform()
    compiler = compiler_command()
    options = build_options(scene, bake_params=bake_params, specialise=specialise, rolled=rolled)
    model = generate_cached(scene, options, name=name, progress=progress)
    files = {f"{model.name}.h": model.header, f"{model.name}.c": model.source}
    files.update((path.name, path.read_text()) for path in [*library_files(), *fmi2_sources()])
    sources = [*files, f"{model.name}_fmi2.c"]
    files.update(fmu_texts(model, scene, [s for s in sources if s.endswith(".c")], stop_time, step_size,
                            fmi2_rows(), library_constants()))

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"{model.name}.fmu"
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f".{model.name}-fmu-", dir=out) as tmp:
        work = Path(tmp)
        (work / "sources").mkdir()
        for filename, text in files.items():
            (work / ("sources" if filename != "modelDescription.xml" else ".") / filename).write_text(text)
        binary = work / "binaries" / folder / f"{model.name}{suffix}"
        binary.parent.mkdir(parents=True)
        c_files = [work / "sources" / s for s in sources if s.endswith(".c")]
        cores = os.cpu_count() or 1
        if cores > 1 and model.source.count("\n") > PARALLEL_LINES:     # a long model: units side by side
            c_files.remove(work / "sources" / f"{model.name}.c")
            for k, text in enumerate(translation_units(model.source, cores)):
                unit = work / f"{model.name}_unit{k}.c"
                unit.write_text(text)
                c_files.append(unit)
        objects = compile_objects(c_files, work / "sources", FLAGS)       # objects beside the sources, not zipped
        _run([*compiler, "-shared", *map(str, objects), "-lm", "-o", str(binary)], "linking the FMU's shared library")
        say(f"FMU binary {folder}/{binary.name} built in {time.perf_counter() - start:.2f} s")
        staged = work / "package.fmu"
        with zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.write(work / "modelDescription.xml", "modelDescription.xml")
            archive.write(binary, f"binaries/{folder}/{binary.name}")
            for filename in sorted(files):
                if filename != "modelDescription.xml":
                    archive.write(work / "sources" / filename, f"sources/{filename}")
        os.replace(staged, target)
    return target


def _run(command: list[str], what: str) -> None:
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise BuildError(f"{what} failed: {done.stderr.strip()[-2000:]}")
