"""Compile generated C with cffi (API mode) and cache the extension module.

A module is the model's NAME.c linked with the library in ``runtime/c`` (``gac.h`` and ``gac_*.c``: the hybrid
loop for any model descriptor); cffi is given gac.h's own declarations (``runtime.header``) and the model's.  The
library is compiled once per library text and flags into a cached object
(``library_object``) shared by every model.  Modules live in the shared cache directory
(``codegen.cache.cache_dir``) as ``_gac_KEY<ext>``, KEY a hash of the C source, the header, the cffi
declarations, the library's text, the compiler flags, the Python version and the cffi version; each hash
gets its own module name, so different models never clash in one process.  Beside each module,
``sha256_gac_KEY.txt`` holds its sha256 (``sha256sum`` format).

A cached module is imported only after its sha256 matches the sidecar.  A module that fails the
check or fails to import is corrupted: one line ``cache: rebuilding corrupted entry FILE (REASON)``
is reported and the module is rebuilt.  A build happens in a private temporary directory, under an
exclusive lock on the entry, and the finished module is moved into place with an atomic rename, so
concurrent builds of the same model all succeed.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import shlex
import shutil
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import cffi

from codegen.options import DEFAULT_FLAGS      # the compiler flags of a model that asks for none
from codegen.artifact import text_digest
from codegen.cache import (CacheError, cache_dir, clear_entry, entry_lock, report_corrupted, sha256_of,  # noqa: F401
                           write_atomic)

from .header import library_cdef
SUFFIX = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
LIBRARY_DIR = Path(__file__).resolve().parent / "c"      # the C library every model is compiled with (package data)


def library_files(folder: Path | None = None) -> list[Path]:
    """The library's headers and sources (gac*.h, gac*.c) in ``folder`` (default LIBRARY_DIR), by name."""
    folder = LIBRARY_DIR if folder is None else Path(folder)
    return sorted(path for path in folder.iterdir()
                  if path.name.startswith("gac") and path.suffix in (".c", ".h") and path.is_file())


def copy_library(out_dir: str | Path) -> list[Path]:
    """Copy the library (gac.h, gac_internal.h, gac_*.c) into out_dir (created if needed), beside a model's NAME.c
    (codegen.pipeline.write_model), so that the folder builds with no Python; returns the paths.  Every file goes
    to a temporary name first and all are renamed into place together: a failure leaves no half-written file."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    staged = [(path, out / f".{path.name}.{os.getpid()}.tmp", out / path.name) for path in library_files()]
    try:
        for source, tmp, _ in staged:
            shutil.copyfile(source, tmp)
        for _, tmp, target in staged:
            tmp.replace(target)
    finally:
        for _, tmp, _ in staged:
            tmp.unlink(missing_ok=True)
    return [target for _, _, target in staged]


def library_sources() -> list[Path]:
    """The library's C sources (gac_*.c), compiled beside each model's NAME.c."""
    return [path for path in library_files() if path.suffix == ".c"]


def library_text() -> str:
    """Every library file's name and text, in one string (part of the build key)."""
    return "".join(f"{path.name}\0{path.read_text()}\0" for path in library_files())


class CompilerNotFound(RuntimeError):
    """No working C compiler: the generated model cannot be built."""


class BuildError(RuntimeError):
    """The C compiler rejected the generated code."""


def build_key(texts: str, flags) -> str:
    """The compiled module's key: the model's texts (their codegen.artifact.text_digest), the library and the
    declarations cffi wraps from it, the flags, Python and cffi."""
    digest = hashlib.sha256()
    for part in (texts, library_text(), library_cdef(), " ".join(flags), sys.version, cffi.__version__):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()[:20]


def find_compiler() -> str:
    """The C compiler cffi/setuptools will call, or CompilerNotFound with a clear message."""
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    program = shlex.split(cc)[0]
    if shutil.which(program) is None:
        raise CompilerNotFound(
            f"no C compiler found: tried {program!r} (from $CC or Python's build configuration). "
            "Install gcc or clang (e.g. `apt-get install gcc`) or set CC to a working compiler.")
    return program


def module_files(folder: Path, module_name: str) -> tuple[Path, Path]:
    """The module file and its sha256 sidecar in ``folder``."""
    return folder / f"{module_name}{SUFFIX}", folder / f"sha256{module_name}.txt"


def verify_module(target: Path, sidecar: Path) -> str | None:
    """None if ``target`` matches the sha256 in ``sidecar``, else the reason it does not."""
    try:
        recorded = sidecar.read_text().split()
    except FileNotFoundError:
        return "sha256 sidecar missing"
    except (OSError, UnicodeDecodeError):
        return "sha256 sidecar unreadable"
    if len(recorded) != 2 or recorded[1] != target.name or not re.fullmatch(r"[0-9a-f]{64}", recorded[0]):
        return "sha256 sidecar malformed"
    try:
        data = target.read_bytes()
    except OSError as exc:
        return f"unreadable: {exc.strerror or exc}"
    return None if sha256_of(data) == recorded[0] else "sha256 mismatch"


def compile_model(name: str, header: str, source: str, cdef: str, flags=DEFAULT_FLAGS,
                  progress=None, digest: str | None = None):
    """Return the compiled cffi module (with .ffi and .lib) for this generated model.  ``digest``: the texts'
    codegen.artifact.text_digest if known (GeneratedModel.text_digest()), else computed here.

    ``progress(message)`` is told whether the build was cached or how long it took, and about a
    corrupted entry that is rebuilt (stderr without ``progress``).
    """
    flags = tuple(flags)
    module_name = f"_gac_{build_key(digest or text_digest(header, source, cdef), flags)}"
    if module_name in _LOADED:                     # imported (after its check) earlier in this process
        if progress:
            progress(f"compile: cached {module_name}{SUFFIX}")
        return _LOADED[module_name]
    folder = cache_dir()
    target, sidecar = module_files(folder, module_name)
    with entry_lock(folder, module_name):
        if target.exists():
            problem = verify_module(target, sidecar)
            if problem is None:
                try:
                    module = _import(module_name, target)
                except Exception as exc:  # noqa: BLE001 - any failure to import means a bad file
                    problem = f"import failed: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"
                else:
                    if progress:
                        progress(f"compile: cached {target.name}")
                    return module
            report_corrupted(target.name, problem, progress)
        seconds = _build(name, header, source, cdef, flags, module_name, target, sidecar)
        if progress:
            progress(f"compile: built {target.name} in {seconds:.2f} s")
        try:
            return _import(module_name, target)
        except Exception as exc:  # noqa: BLE001
            raise BuildError(f"the freshly built module {target} cannot be imported: {exc}") from exc


PARALLEL_LINES = 1000     # a model source longer than this is compiled as several units side by side
KERNEL_MARK, END_MARK = "/* ---- kernel ", "/* ---- end of kernels ---- */"


def translation_units(source: str, count: int) -> list[str]:
    """The model's source cut into at most ``count`` translation units at its kernel boundaries (the template's
    marks), balanced by lines: the first holds everything outside the kernels, each starts with the includes
    that precede the first kernel.  A source without the marks is one unit."""
    lines = source.splitlines(keepends=True)
    marks = [i for i, line in enumerate(lines) if line.startswith(KERNEL_MARK)]
    ends = [i for i, line in enumerate(lines) if line.startswith(END_MARK)]
    if count < 2 or len(marks) < 2 or len(ends) != 1:
        return [source]
    head, tail = lines[:marks[0]], lines[ends[0]:]
    groups = [lines[a:b] for a, b in zip(marks, marks[1:] + ends)]
    units = [list(tail)] + [[] for _ in range(count - 1)]
    for group in sorted(groups, key=len, reverse=True):            # largest first, into the lightest unit
        min(units, key=len).extend(group)
    return ["".join(head + unit) for unit in units if unit]


def compiler_command() -> list[str]:
    """The compiler command: $CC as written (it may carry flags) when set, else the program find_compiler finds;
    CompilerNotFound when there is none."""
    program = find_compiler()
    return shlex.split(os.environ["CC"]) if os.environ.get("CC") else [program]


def compile_objects(sources: list[Path], folder: Path, flags) -> list[Path]:
    """Compile C sources to position-independent objects in ``folder`` (which, with the library's folder, is on
    the include path), side by side (one per core)."""
    from concurrent.futures import ThreadPoolExecutor
    import subprocess
    compiler = compiler_command()
    pic = shlex.split(sysconfig.get_config_var("CCSHARED") or "-fPIC")

    def one(path: Path) -> Path:
        obj = folder / f"{path.stem}.o"
        done = subprocess.run([*compiler, *pic, *flags, f"-I{folder}", f"-I{LIBRARY_DIR}", "-c", str(path), "-o",
                               str(obj)], capture_output=True, text=True)
        if done.returncode != 0:
            raise BuildError(f"compiling {path.name} failed: {done.stderr.strip()[-2000:]}")
        return obj
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return list(pool.map(one, sources))


def library_object(flags, progress=None) -> Path:
    """The C library compiled once per library text, flags, compiler and Python: one position-independent object
    in the cache (``gac_lib_KEY.o`` with its sha256 sidecar, checked before use), linked into every model's
    module.  The library's files are compiled as one translation unit (each gac_*.c included in name order), so
    that the loop's calls across them (integrators, events, the impact law) can be inlined as in one file."""
    flags = tuple(flags)
    digest = hashlib.sha256()
    for part in (library_text(), " ".join(flags), " ".join(compiler_command()), sys.version, "one unit"):
        digest.update(part.encode())
        digest.update(b"\0")
    entry = f"gac_lib_{digest.hexdigest()[:20]}"
    folder = cache_dir()
    target, sidecar = folder / f"{entry}.o", folder / f"sha256_{entry}.txt"
    with entry_lock(folder, entry):
        if target.exists():
            problem = verify_module(target, sidecar)
            if problem is None:
                return target
            report_corrupted(target.name, problem, progress)
        start = time.perf_counter()
        workdir = Path(tempfile.mkdtemp(prefix=f"{entry}-", dir=folder))
        try:
            unit = workdir / "gac_library.c"
            unit.write_text("".join(f'#include "{path.name}"\n' for path in library_sources()))
            built = compile_objects([unit], workdir, flags)[0]
            data = built.read_bytes()
            clear_entry(target)
            os.replace(built, target)
            write_atomic(sidecar, f"{sha256_of(data)}  {target.name}\n".encode())
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
        if progress:
            progress(f"compile: built the C library {target.name} in {time.perf_counter() - start:.2f} s")
    return target


def glue_flags(flags) -> list[str]:
    """The flags of the cffi glue (the module's Python wrappers around the C functions): the model's flags, then
    -O0, and -g0 unless they ask for debug information.  The glue only converts arguments, so its optimisation
    does not show in a call, and compiling it unoptimised takes a third of the time (it is most of a model's
    build: about 7,000 lines against the kernels' 1,500)."""
    debug = any(f.startswith("-g") and f != "-g0" for f in flags)
    return [*flags, "-O0", *(() if debug else ("-g0",))]


def _build(name, header, source, cdef, flags, module_name: str, target: Path, sidecar: Path) -> float:
    """Build the module in a temporary directory, move it to ``target``, then write its sidecar: the model's
    source compiled with ``flags`` (a long one, PARALLEL_LINES, as several units side by side, one per core),
    the library's cached object (library_object) and the cffi glue (glue_flags), linked."""
    find_compiler()
    start = time.perf_counter()
    library = library_object(flags)
    workdir = Path(tempfile.mkdtemp(prefix=f"{module_name}-", dir=target.parent))
    try:
        (workdir / f"{name}.h").write_text(header)
        (workdir / f"{name}.c").write_text(source)
        cores = os.cpu_count() or 1
        units = [workdir / f"{name}.c"]
        if cores > 1 and source.count("\n") > PARALLEL_LINES:
            units = []
            for k, text in enumerate(translation_units(source, cores)):
                units.append(workdir / f"{name}_unit{k}.c")
                units[-1].write_text(text)
        objects = [library, *compile_objects(units, workdir, flags)]
        ffi = cffi.FFI()
        ffi.cdef(library_cdef() + cdef)           # the library's declarations from gac.h, then the model's
        ffi.set_source(module_name, f'#include "{name}.h"', extra_objects=list(map(str, objects)),
                       include_dirs=[str(workdir), str(LIBRARY_DIR)], extra_compile_args=glue_flags(flags),
                       libraries=["m"])
        try:
            built = Path(ffi.compile(tmpdir=str(workdir), verbose=False))
        except Exception as exc:  # setuptools raises CompileError / LinkError / VerificationError
            raise BuildError(f"compiling the generated model {name!r} failed: {exc}") from exc
        digest = sha256_of(built.read_bytes())
        clear_entry(target)
        os.replace(built, target)
        write_atomic(sidecar, f"{digest}  {target.name}\n".encode())
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    return time.perf_counter() - start


_LOADED = {}          # module name -> module imported in this process
_FAILED = set()       # module files whose import failed in this process


def _import(module_name: str, path: Path):
    """Import the module file ``path`` as ``module_name``.  A path whose import failed before in this
    process is imported from a fresh copy: the dynamic loader may still hold the old file by name."""
    if path in _FAILED:
        with tempfile.TemporaryDirectory(prefix=".import-", dir=path.parent) as tmp:
            copy = Path(tmp) / path.name
            shutil.copyfile(path, copy)
            module = _exec(module_name, copy)
    else:
        try:
            module = _exec(module_name, path)
        except Exception:
            _FAILED.add(path)
            raise
    _LOADED[module_name] = module
    return module


def _exec(module_name: str, path: Path):
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
