"""Compile generated C with cffi (API mode) and cache the extension module.

Builds are cached in a user cache directory (``$GIBBS_APPELL_CACHE``, else
``$XDG_CACHE_HOME/gibbs-appell-chains``, else ``~/.cache/gibbs-appell-chains``), keyed by a hash
of the C source, the header, the cffi declarations, the compiler flags, the Python version and the
cffi version; each hash gets its own module name, so different models never clash in one process.
A build happens in a private temporary directory and the finished module is moved into place with
an atomic rename, so concurrent builds of the same model both succeed.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import shlex
import shutil
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import cffi

DEFAULT_FLAGS = ("-O2",)


class CompilerNotFound(RuntimeError):
    """No working C compiler: the generated model cannot be built."""


class BuildError(RuntimeError):
    """The C compiler rejected the generated code."""


def cache_dir() -> Path:
    if os.environ.get("GIBBS_APPELL_CACHE"):
        base = Path(os.environ["GIBBS_APPELL_CACHE"])
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "gibbs-appell-chains"
    base.mkdir(parents=True, exist_ok=True)
    return base


def build_key(header: str, source: str, cdef: str, flags) -> str:
    digest = hashlib.sha256()
    for part in (header, source, cdef, " ".join(flags), sys.version, cffi.__version__):
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


def compile_model(name: str, header: str, source: str, cdef: str, flags=DEFAULT_FLAGS,
                  progress=None):
    """Return the compiled cffi module (with .ffi and .lib) for this generated model.

    ``progress(message)`` is told whether the build was cached or how long it took.
    """
    flags = tuple(flags)
    key = build_key(header, source, cdef, flags)
    module_name = f"_gac_{key}"
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    target = cache_dir() / f"{module_name}{suffix}"
    if target.exists():
        if progress:
            progress(f"compile: cached {target.name}")
        return _load(module_name, target)
    find_compiler()
    start = time.perf_counter()
    workdir = Path(tempfile.mkdtemp(prefix=f"{module_name}-", dir=cache_dir()))
    try:
        (workdir / f"{name}.h").write_text(header)
        (workdir / f"{name}.c").write_text(source)
        ffi = cffi.FFI()
        ffi.cdef(cdef)
        ffi.set_source(module_name, f'#include "{name}.h"', sources=[str(workdir / f"{name}.c")],
                       include_dirs=[str(workdir)], extra_compile_args=list(flags), libraries=["m"])
        try:
            built = Path(ffi.compile(tmpdir=str(workdir), verbose=False))
        except Exception as exc:  # setuptools raises CompileError / LinkError / VerificationError
            raise BuildError(f"compiling the generated model {name!r} failed: {exc}") from exc
        os.replace(built, target)          # atomic: a concurrent build of the same key is harmless
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    if progress:
        progress(f"compile: built {target.name} in {time.perf_counter() - start:.2f} s")
    return _load(module_name, target)


_LOADED = {}


def _load(module_name: str, path: Path):
    if module_name in _LOADED:
        return _LOADED[module_name]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    _LOADED[module_name] = module
    return module
