"""The studies' timer: the median and spread of repeated runs, from Python or from a C loop.

    timing = time_call(lambda: simulate(model, 1.5, t_eval=[]), repeat=21)   # timing.median, .spread (s)
    timing = time_call(run, budget=0.5, clock=time.process_time)           # as many runs as fit in 0.5 s
    ns = time_rhs(generated_model).median                                  # ns per NAME_rhs call, in C
"""
from __future__ import annotations

import statistics
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from codegen.artifact import GeneratedModel

from .toolchain import compile_c

MIN_REPEAT, MAX_REPEAT = 3, 21


@dataclass(frozen=True)
class Timing:
    """Timed samples (seconds, or whatever unit they were taken in): their median and spread (max - min),
    and the result of the first, untimed-by-default call."""

    samples: tuple
    result: object = None

    @property
    def median(self) -> float:
        return statistics.median(self.samples)

    @property
    def spread(self) -> float:
        return max(self.samples) - min(self.samples)

    @property
    def runs(self) -> int:
        return len(self.samples)


def time_call(fn: Callable[[], object], repeat: int | None = None, *, budget: float | None = None,
              clock: Callable[[], float] = time.perf_counter, min_repeat: int = MIN_REPEAT,
              max_repeat: int = MAX_REPEAT) -> Timing:
    """Call ``fn`` once (the warm-up; its result is kept), then ``repeat`` more times, each timed on ``clock``.

    With ``budget`` (seconds of ``clock``) instead of ``repeat``: as many timed calls as fit in the budget at
    the warm-up's pace, between ``min_repeat`` and ``max_repeat``; a warm-up that alone takes the budget is
    the only sample (so ``budget=0`` times a single call)."""
    start = clock()
    result = fn()
    first = clock() - start
    if repeat is None:
        if budget is None:
            raise ValueError("time_call: give repeat or budget")
        if first >= budget:
            return Timing((first,), result)
        repeat = int(min(max_repeat, max(min_repeat, budget / max(first, 1e-6))))
    if repeat < 1:
        raise ValueError(f"time_call: repeat must be >= 1, got {repeat}")
    samples = []
    for _ in range(repeat):
        start = clock()
        fn()
        samples.append(clock() - start)
    return Timing(tuple(samples), result)


# ---------------------------------------------------------------------------
# NAME_rhs in a C loop (no Python in the loop)
# ---------------------------------------------------------------------------
BATCHES = 7

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include "{name}.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

int main(int argc, char **argv)
{{
    double p[{NAME}_NPARAM], q[{NAME}_NQ], qd[{NAME}_NQ], x[{NAME}_NX], xd[{NAME}_NX], acc = 0.0;
    double u[{NAME}_NU + 1] = {{0.0}};             /* inputs at 0 (one more entry: never a zero-length array) */
    long calls = argc > 1 ? atol(argv[1]) : 100000, i;
    int batch, k;
    {name}_default_parameters(p);
    {name}_initial_state(q, qd);
    for (k = 0; k < {NAME}_NQ; ++k) {{ x[k] = q[k] + 0.01 * k; x[{NAME}_NQ + k] = qd[k] + 0.1 * k; }}
    for (batch = 0; batch < {batches}; ++batch) {{
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (i = 0; i < calls; ++i) {{
            x[0] += 1e-12;                        /* a new input every call */
            {name}_rhs(0.0, x, u, p, xd);
            acc += xd[{NAME}_NX - 1];
        }}
        clock_gettime(CLOCK_MONOTONIC, &b);
        printf("%.3f\n", ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / (double)calls);
    }}
    fprintf(stderr, "%g\n", acc);
    return 0;
}}
"""


def time_rhs(model: GeneratedModel, calls: int = 100000, flags=("-O2",)) -> Timing:
    """Nanoseconds per NAME_rhs call: one sample per batch of ``calls`` calls, 7 batches, timed in C.  The
    model is compiled with the runtime's C library (runtime.compile.library_sources)."""
    from runtime.compile import LIBRARY_DIR, library_sources
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / f"{model.name}.h").write_text(model.header)
        (folder / f"{model.name}.c").write_text(model.source)
        harness = folder / "timing.c"
        harness.write_text(HARNESS.format(name=model.name, NAME=model.name.upper(), batches=BATCHES))
        compile_c([harness, folder / f"{model.name}.c", *library_sources()], folder / "timing", flags=flags,
                  include_dirs=[folder, LIBRARY_DIR])
        out = subprocess.run([str(folder / "timing"), str(calls)], cwd=folder, capture_output=True, text=True,
                             check=True)
    return Timing(tuple(float(line) for line in out.stdout.split()))
