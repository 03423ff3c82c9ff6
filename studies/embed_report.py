"""Figures of the embeddable C: object size, stack use per function, time per simulated second.

    python -m studies embed --links 4,16 [--t-end 1.5] [--runs 50]

For each n it writes the built-in N-link scene with --standalone into a temporary folder, compiles the
model and the runtime's C library with -O2 -fstack-usage (studies.toolchain), reads the sizes (`size`,
summed over the objects) and the .su files, and runs the example (DOPRI5 and DOP853 at rtol = 1e-10) to
time one simulated second, with no Python in the loop.
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from codegen.pipeline import generate, write_model, write_standalone
from codegen.scene import default_scene

from .machine import describe
from .toolchain import compile_c, compiler_version


def measure(n: int, t_end: float, runs: int, folder: Path) -> dict:
    from runtime.compile import LIBRARY_DIR, copy_library, library_sources
    scene = default_scene(n)
    model = generate(scene)
    write_model(model, folder)
    copy_library(folder)
    write_standalone(model, scene, folder, [path.name for path in library_sources()])
    name = model.name
    objects = folder / "objects"
    compile_c([folder / f"{name}.c", *library_sources()], objects, flags=("-O2", "-fstack-usage"),
              include_dirs=[folder, LIBRARY_DIR], link=False)
    lines = subprocess.run(["size", *sorted(str(o) for o in objects.glob("*.o"))], capture_output=True, text=True,
                           check=True).stdout.splitlines()[1:]
    text, data, bss = (sum(int(line.split()[k]) for line in lines) for k in range(3))
    stack = {}                                   # function without the model's prefix -> bytes
    for su in sorted(objects.glob("*.su")):
        for line in su.read_text().splitlines():
            function, size, _ = line.split("\t")
            function = function.split(":")[-1]
            stack[function[len(name) + 1:] if function.startswith(name + "_") else function] = int(size)
    subprocess.run(["make", "-s"], cwd=folder, check=True)
    timing = {}
    for method in ("dopri5", "dop853"):
        out = subprocess.run([f"./{name}_example", str(t_end), method, "1e-10", "--time", str(runs)], cwd=folder,
                             capture_output=True, text=True, check=True).stdout
        timing[method] = float(re.search(r"time per simulated second: ([0-9.eE+-]+) ms", out).group(1))
        timing[f"{method}_impacts"] = int(re.search(r"# impacts (\d+)", out).group(1))
    return {"n": n, "name": name, "text": int(text), "data": int(data), "bss": int(bss), "stack": stack,
            "timing": timing}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies embed", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--links", default="4,16")
    parser.add_argument("--t-end", type=float, default=1.5)
    parser.add_argument("--runs", type=int, default=50)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    rows = []
    for n in (int(x) for x in args.links.split(",")):
        with tempfile.TemporaryDirectory() as tmp:
            print(f"n = {n} ...", file=sys.stderr, flush=True)
            rows.append(measure(n, args.t_end, args.runs, Path(tmp)))
    print(f"Machine: {describe(compiler_version())}")
    print("| n | object code (text / data / bss bytes) | ms per simulated second, DOPRI5 / DOP853 (rtol 1e-10) "
          "| impacts in the run |")
    print("|---|---|---|---|")
    for r in rows:
        print(f"| {r['n']} | {r['text']:,} / {r['data']} / {r['bss']} | {r['timing']['dopri5']:.3f} / "
              f"{r['timing']['dop853']:.3f} | {r['timing']['dopri5_impacts']} |")
    print()
    print("| stack bytes (-fstack-usage, -O2) | " + " | ".join(f"n = {r['n']}" for r in rows) + " |")
    print("|---|" + "---|" * len(rows))
    for function in sorted({f for r in rows for f in r["stack"]}):
        print(f"| {function} | " + " | ".join(str(r["stack"].get(function, "")) for r in rows) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
