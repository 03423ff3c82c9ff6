"""Time a generated model's right-hand side in C (no Python in the loop).

    ns = time_rhs(generated_model)      # median over batches, nanoseconds per NAME_rhs call
"""
from __future__ import annotations

import statistics
import subprocess
import tempfile
from pathlib import Path

from .emit import GeneratedModel

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include "{name}.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

int main(int argc, char **argv)
{{
    double p[{NAME}_NPARAM], q[{NAME}_NQ], qd[{NAME}_NQ], x[{NAME}_NX], xd[{NAME}_NX], acc = 0.0;
    long calls = argc > 1 ? atol(argv[1]) : 100000, i;
    int batch, k;
    {name}_default_parameters(p);
    {name}_initial_state(q, qd);
    for (k = 0; k < {NAME}_NQ; ++k) {{ x[k] = q[k] + 0.01 * k; x[{NAME}_NQ + k] = qd[k] + 0.1 * k; }}
    for (batch = 0; batch < 7; ++batch) {{
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (i = 0; i < calls; ++i) {{
            x[0] += 1e-12;                        /* a new input every call */
            {name}_rhs(0.0, x, p, xd);
            acc += xd[{NAME}_NX - 1];
        }}
        clock_gettime(CLOCK_MONOTONIC, &b);
        printf("%.3f\n", ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / (double)calls);
    }}
    fprintf(stderr, "%g\n", acc);
    return 0;
}}
"""


def time_rhs(model: GeneratedModel, calls: int = 100000, flags=("-O2",)) -> float:
    """Median nanoseconds per NAME_rhs call over 7 batches of ``calls`` calls."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / f"{model.name}.h").write_text(model.header)
        (folder / f"{model.name}.c").write_text(model.source)
        (folder / "timing.c").write_text(HARNESS.format(name=model.name, NAME=model.name.upper()))
        subprocess.run(["gcc", "-std=c99", *flags, "timing.c", f"{model.name}.c", "-lm", "-o", "timing"],
                       cwd=folder, check=True)
        out = subprocess.run(["./timing", str(calls)], cwd=folder, capture_output=True, text=True, check=True)
    return statistics.median(float(line) for line in out.stdout.split())
