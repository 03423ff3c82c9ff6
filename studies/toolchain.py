"""The C toolchain of the studies: one place that picks the compiler and runs it.

    seconds = compile_c([harness, model_c, *library_sources()], folder / "timing",
                        include_dirs=[folder, LIBRARY_DIR])                       # an executable
    seconds = compile_c([model_c], folder, flags=("-O2", "-fstack-usage"), link=False)   # objects in folder

The compiler is the one the runtime builds models with (``runtime.compile.find_compiler``: $CC, else
Python's build configuration, else ``cc``); a missing compiler is ``CompilerNotFound`` and a rejected
source ``BuildError``, both with a message that says what to do.
"""
from __future__ import annotations

import shlex
import subprocess
import time
from pathlib import Path

from codegen.options import DEFAULT_FLAGS
from runtime.compile import BuildError, CompilerNotFound, compiler_command  # noqa: F401

STANDARD = "-std=c99"


def compiler() -> list[str]:
    """The compiler command: $CC as written (it may carry flags) when set, else the program the runtime
    finds; CompilerNotFound when there is none."""
    return compiler_command()


def compiler_version() -> str:
    """The first line of ``CC --version`` (e.g. 'gcc (Debian 12.2.0-14) 12.2.0')."""
    try:
        command = compiler()
        out = subprocess.run([*command, "--version"], capture_output=True, text=True).stdout
        return out.splitlines()[0].strip()
    except (CompilerNotFound, OSError, IndexError):
        return "C compiler ?"


def compile_c(sources, output, *, flags=DEFAULT_FLAGS, include_dirs=(), link: bool = True,
              libraries=("m",)) -> float:
    """Compile C99 sources and return the compiler's wall time in seconds.

    With ``link`` (default) the sources become the executable ``output``; without it every source becomes
    an object file NAME.o in the directory ``output`` (with the compiler's side files, e.g. NAME.su of
    -fstack-usage, beside it).  ``include_dirs`` are searched for headers (-I), ``libraries`` linked (-l)."""
    sources = [Path(s).resolve() for s in sources]
    if not sources:
        raise ValueError("compile_c: no sources")
    output = Path(output).resolve()
    command = [*compiler(), STANDARD, *flags, *(f"-I{Path(d).resolve()}" for d in include_dirs),
               *map(str, sources)]
    if link:
        output.parent.mkdir(parents=True, exist_ok=True)
        command += ["-o", str(output), *(f"-l{lib}" for lib in libraries)]
        cwd = output.parent
    else:
        output.mkdir(parents=True, exist_ok=True)
        command.append("-c")
        cwd = output
    start = time.perf_counter()
    try:
        done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    except OSError as exc:
        raise CompilerNotFound(f"cannot run the C compiler {command[0]!r}: {exc}; install gcc or clang or set "
                               "CC to a working compiler") from exc
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        tail = "\n".join(done.stderr.strip().splitlines()[-20:])
        raise BuildError(f"the C compiler failed (exit {done.returncode}): {shlex.join(command)}\n{tail}")
    return seconds
