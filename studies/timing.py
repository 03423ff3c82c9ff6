"""The studies' timer: the median and spread of repeated runs, from Python or from a C loop.

    timing = time_call(lambda: simulate(model, 1.5, t_eval=[]), repeat=21)   # timing.median, .spread (s)
    timing = time_call(run, budget=0.5, clock=time.process_time)           # as many runs as fit in 0.5 s
    ns = time_rhs(generated_model).median                                  # ns per NAME_rhs call, in C
    a, b = time_rhs_side_by_side([model_a, model_b], [20000, 2000])     # one C program, alternating batches
    ratio = ratios(b, a)                                                   # b / a batch by batch: .median, ...
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
    def low(self) -> float:
        return min(self.samples)

    @property
    def high(self) -> float:
        return max(self.samples)

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
# NAME_rhs in a C loop (no Python in the loop), one model or several side by side
# ---------------------------------------------------------------------------
BATCHES = 7

TIMED_MODEL = r"""
static double time_{name}(long calls, double *acc)      /* ns per {name}_rhs call over one batch */
{{
    double p[{NAME}_NPARAM], q[{NAME}_NQ], qd[{NAME}_NQ], x[{NAME}_NX], xd[{NAME}_NX];
    double u[{NAME}_NU + 1] = {{0.0}};         /* inputs at 0 (one more entry: never a zero-length array) */
    struct timespec a, b;
    long i;
    int k;
    {name}_default_parameters(p);
    {name}_initial_state(q, qd);
    for (k = 0; k < {NAME}_NQ; ++k) {{ x[k] = q[k] + 0.01 * k; x[{NAME}_NQ + k] = qd[k] + 0.1 * k; }}
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (i = 0; i < calls; ++i) {{
        x[0] += 1e-12;                            /* a new input every call */
        {name}_rhs(0.0, x, u, p, xd);
        *acc += xd[{NAME}_NX - 1];
    }}
    clock_gettime(CLOCK_MONOTONIC, &b);
    return ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / (double)calls;
}}
"""

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
{includes}
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
{timed}
int main(int argc, char **argv)
{{
    long calls[{count}];
    double ns[{count}], acc = 0.0;
    int batch, j;
    if (argc != {count} + 1) return 2;
    for (j = 0; j < {count}; ++j) calls[j] = atol(argv[j + 1]);
    for (batch = 0; batch < {batches}; ++batch) {{
        for (j = 0; j < {count}; ++j) {{              /* each model in turn, starting one later every batch */
            int m = (batch + j) % {count};
            switch (m) {{
{cases}
            }}
        }}
        for (j = 0; j < {count}; ++j) printf("%.3f%c", ns[j], j + 1 < {count} ? ' ' : '\n');
    }}
    fprintf(stderr, "%g\n", acc);
    return 0;
}}
"""


def time_rhs(model: GeneratedModel, calls: int = 100000, flags=("-O2",)) -> Timing:
    """Nanoseconds per NAME_rhs call: one sample per batch of ``calls`` calls, 7 batches, timed in C.  The
    model is compiled with the runtime's C library (runtime.compile.library_sources)."""
    return time_rhs_side_by_side([model], [calls], flags)[0]


def time_rhs_side_by_side(models, calls, flags=("-O2",)) -> list[Timing]:
    """Nanoseconds per NAME_rhs call of several models timed in one C program: in each of 7 batches every
    model runs its ``calls[k]`` calls in turn (the first model of a batch rotating), so load and clock drift
    on the machine hit all of them alike.  Sample b of every Timing comes from batch b, so ``ratios`` pairs
    them.  ``models``: GeneratedModel (or anything with .name, .header, .source), names all different; they
    are compiled together with one copy of the runtime's C library."""
    from runtime.compile import LIBRARY_DIR, library_sources
    models, calls = list(models), [int(c) for c in calls]
    names = [m.name for m in models]
    if not models or len(calls) != len(models):
        raise ValueError(f"time_rhs_side_by_side: one calls count per model, got {len(calls)} for {len(models)}")
    if len(set(names)) != len(names):
        raise ValueError(f"time_rhs_side_by_side: the models need different names, got {names}")
    if min(calls) < 1:
        raise ValueError(f"time_rhs_side_by_side: calls must be >= 1, got {calls}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for m in models:
            (folder / f"{m.name}.h").write_text(m.header)
            (folder / f"{m.name}.c").write_text(m.source)
        harness = folder / "timing.c"
        harness.write_text(HARNESS.format(
            includes="\n".join(f'#include "{name}.h"' for name in names),
            timed="".join(TIMED_MODEL.format(name=name, NAME=name.upper()) for name in names),
            cases="\n".join(f"            case {k}: ns[{k}] = time_{name}(calls[{k}], &acc); break;"
                            for k, name in enumerate(names)),
            count=len(models), batches=BATCHES))
        compile_c([harness, *(folder / f"{name}.c" for name in names), *library_sources()], folder / "timing",
                  flags=flags, include_dirs=[folder, LIBRARY_DIR])
        out = subprocess.run([str(folder / "timing"), *map(str, calls)], cwd=folder, capture_output=True,
                             text=True, check=True)
    rows = [[float(x) for x in line.split()] for line in out.stdout.splitlines() if line.strip()]
    return [Timing(tuple(row[k] for row in rows)) for k in range(len(models))]


def ratios(a: Timing, b: Timing) -> Timing:
    """a / b batch by batch, for two Timings of one time_rhs_side_by_side call: the ratio's median and spread
    as measured, not the ratio of two medians."""
    if a.runs != b.runs:
        raise ValueError(f"ratios: {a.runs} samples against {b.runs}; give the Timings of one side-by-side run")
    return Timing(tuple(x / y for x, y in zip(a.samples, b.samples)))


def median_range(timing: Timing, digits: int = 2) -> str:
    """'median (min-max)' of a Timing's samples, as the reports print a measured ratio or time."""
    return f"{timing.median:.{digits}f} ({timing.low:.{digits}f}-{timing.high:.{digits}f})"
