"""Our forward dynamics against Pinocchio's articulated-body algorithm traced by CasADi into C, side by side.

For each n the general (n + 5 coordinate) model of the built-in n-link chain is generated, and the same chain
is written as a URDF (three prismatic joints X1, X2, X3, then the revolute joints theta_-1, theta_0, theta_1 ..
theta_n with the scene's twists as fixed rotations, massless imaginary links, gravity along the scene's direction
(-X2) by a fixed rotation of the reference frame), traced by Pinocchio + CasADi (studies/peer_trace.py, run in the interpreter
that has the `peer` extra) and generated as C.  One C program then times both on the same random states,
alternating batches, and checks that they agree (coordinates mapped exactly; relative difference below 1e-12).

    python -m studies peer [--links 4,8,16,32,64] [--flags="-O2,-O3 -march=native"] [--peer-python PATH]

Without the peer it says so and stops; it pins numpy 1.24, so it lives in an environment of its own:
python3 -m venv .peer && .peer/bin/pip install cmeel-casadi-kin-dyn (the `peer` extra), then --peer-python
.peer/bin/python.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

TRACE = Path(__file__).resolve().parent / "peer_trace.py"
STATES = 256


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies peer", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--links", default="4,8,16,32,64", help="chain lengths, comma-separated (default 4,8,16,32,64)")
    parser.add_argument("--flags", default="-O2,-O3 -march=native",
                        help='compiler flag sets separated by commas, given as --flags="..." '
                             '(default "-O2,-O3 -march=native")')
    parser.add_argument("--batches", type=int, default=9, help="alternating timed batches per side (default 9)")
    parser.add_argument("--peer-python", metavar="PATH", default=sys.executable,
                        help="the Python that has the peer extra (casadi_kin_dyn; default: this one)")
    parser.add_argument("--json", metavar="FILE", help="also write the rows as JSON")
    return parser


# ---------------------------------------------------------------------------------------------------
# the chain as a URDF
# ---------------------------------------------------------------------------------------------------
def urdf(scene) -> str:
    """The scene's chain for Pinocchio: q_pin = [X1, X2, X3, theta_-1, theta_0, theta_1 .. theta_n]."""
    from codegen.scene import LineLink
    from codegen.urdf import link_inertial, matrix_rpy
    free = '<limit lower="-1e9" upper="1e9" effort="1e9" velocity="1e9"/>'
    massless = '<inertial><mass value="0"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial>'

    def link(name, inertial=massless):
        return f'<link name="{name}">{inertial}</link>'

    def joint(name, kind, parent, child, axis, xyz=(0, 0, 0), angles=(0, 0, 0)):
        return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                f'<origin xyz="{" ".join(map(repr, map(float, xyz)))}" rpy="{" ".join(map(repr, map(float, angles)))}"/>'
                f'<axis xyz="{axis}"/>{free if kind != "fixed" else ""}</joint>')

    parts = ['<robot name="chain">', link("world", ""), link("ref"),
             joint("gravity_along_d", "fixed", "world", "ref", "1 0 0", angles=_gravity_mount(scene.gravity_direction))]
    previous = "ref"
    for a, axis in enumerate(("1 0 0", "0 1 0", "0 0 1")):
        parts += [link(f"slide{a + 1}"), joint(f"X{a + 1}", "prismatic", previous, f"slide{a + 1}", axis)]
        previous = f"slide{a + 1}"
    twists = scene.all_twists
    for k in range(-1, scene.n + 1):
        name = f"link{k}".replace("-", "m")
        offset = (scene.links[k - 2].length, 0, 0) if k >= 2 else (0, 0, 0)
        if k >= 1:
            body = scene.links[k - 1]
            if not isinstance(body, LineLink):
                raise ValueError("peer: only line links are mapped")
            m, c, I = link_inertial(body)
            inertial = (f'<inertial><mass value="{float(m)!r}"/><origin xyz="{float(c[0])!r} 0 0"/>'
                        f'<inertia ixx="{float(I[0, 0])!r}" iyy="{float(I[1, 1])!r}" '
                        f'izz="{float(I[2, 2])!r}" ixy="0" ixz="0" iyz="0"/></inertial>')
        else:
            inertial = massless
        parts += [link(name, inertial),
                  joint(f"theta_{k}".replace("-", "m"), "revolute", previous, name, "0 0 1", offset, matrix_rpy(twists[k + 1]))]
        previous = name
    parts.append("</robot>")
    return "\n".join(parts)


def _gravity_mount(d) -> tuple[float, float, float]:
    """rpy of the fixed rotation from Pinocchio's world (gravity along -z) to the box frame: it turns the scene's
    gravity direction d onto -z (rows a, b, -d, right-handed); Rx(pi/2) for the default d = -X2."""
    from codegen.urdf import matrix_rpy
    d = np.asarray(d, dtype=float)
    if np.array_equal(d, [0.0, -1.0, 0.0]):
        return (math.pi / 2, 0.0, 0.0)
    a = np.cross(-d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.cross(-d, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    return matrix_rpy(np.array([a, np.cross(-d, a), -d]))


def pin_order(n: int) -> list[int]:
    """Index into our q of each entry of Pinocchio's q: [X1, X2, X3, theta_-1 .. theta_n]."""
    return [n + 2, n + 3, n + 4] + list(range(n + 2))


# ---------------------------------------------------------------------------------------------------
# the side-by-side harness
# ---------------------------------------------------------------------------------------------------
HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include "{name}.h"
#include "{rname}.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

typedef long long int casadi_int;
int peer_aba(const double **arg, double **res, casadi_int *iw, double *w, int mem);
int peer_aba_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw, casadi_int *sz_w);

#define S {states}
#define NQ {NAME}_NQ
static const int order[NQ] = {{ {order} }};
static double q[S][NQ], qd[S][NQ], qp[S][NQ], vp[S][NQ], out[NQ], outp[NQ];

static double now(void)
{{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e9 + t.tv_nsec;
}}

int main(void)
{{
    double p[{NAME}_NPARAM], u[{NAME}_NU + 1] = {{0.0}}, tau[NQ] = {{0.0}}, sink = 0.0, worst = 0.0, scale = 0.0;
    double outr[NQ], worst_rolled = 0.0;
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    const double *arg[3];
    double *res[1], *w;
    casadi_int *iw;
    long reps = {reps};
    int s, i, b;
    FILE *f = fopen("states.txt", "r");
    if (f == 0) return 1;
    for (s = 0; s < S; ++s) {{
        for (i = 0; i < NQ; ++i) if (fscanf(f, "%lf", &q[s][i]) != 1) return 1;
        for (i = 0; i < NQ; ++i) if (fscanf(f, "%lf", &qd[s][i]) != 1) return 1;
        for (i = 0; i < NQ; ++i) {{ qp[s][i] = q[s][order[i]]; vp[s][i] = qd[s][order[i]]; }}
    }}
    fclose(f);
    {name}_default_parameters(p);
    peer_aba_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    w = malloc(sizeof(double) * (size_t)(sz_w + 1));
    iw = malloc(sizeof(casadi_int) * (size_t)(sz_iw + 1));
    res[0] = outp;
    arg[2] = tau;
    for (s = 0; s < S; ++s) {{                         /* the two agree, coordinates mapped */
        arg[0] = qp[s]; arg[1] = vp[s];
        {name}_forward_dynamics(q[s], qd[s], u, p, out);
        {rname}_forward_dynamics(q[s], qd[s], u, p, outr);
        peer_aba(arg, res, iw, w, 0);
        for (i = 0; i < NQ; ++i) {{
            if (fabs(out[order[i]] - outp[i]) > worst) worst = fabs(out[order[i]] - outp[i]);
            if (fabs(outr[i] - out[i]) > worst_rolled) worst_rolled = fabs(outr[i] - out[i]);
            if (fabs(out[order[i]]) > scale) scale = fabs(out[order[i]]);
        }}
    }}
    printf("agree %.3e %.3e\n", worst / scale, worst_rolled / scale);
    for (b = 0; b < {batches}; ++b) {{                 /* alternating batches: drift hits both alike */
        long r;
        double t0 = now(), t1, t2, t3;
        for (r = 0; r < reps; ++r)
            for (s = 0; s < S; ++s) {{
                {name}_forward_dynamics(q[s], qd[s], u, p, out);
                sink += out[NQ - 1];
            }}
        t3 = now();
        for (r = 0; r < reps; ++r)
            for (s = 0; s < S; ++s) {{
                {rname}_forward_dynamics(q[s], qd[s], u, p, outr);
                sink += outr[NQ - 1];
            }}
        t1 = now();
        for (r = 0; r < reps; ++r)
            for (s = 0; s < S; ++s) {{
                arg[0] = qp[s]; arg[1] = vp[s];
                peer_aba(arg, res, iw, w, 0);
                sink += outp[NQ - 1];
            }}
        t2 = now();
        printf("ours %.4f peer %.4f rolled %.4f\n", (t3 - t0) / (reps * S) * 1e-3, (t2 - t1) / (reps * S) * 1e-3,
               (t1 - t3) / (reps * S) * 1e-3);
    }}
    fprintf(stderr, "%g\n", sink);
    free(w);
    free(iw);
    return 0;
}}
"""


def random_states(scene, rng) -> tuple[np.ndarray, np.ndarray]:
    """STATES states of the general layout, theta_0 kept away from the base chart's lock."""
    nq = scene.nq
    q = rng.uniform(-math.pi, math.pi, size=(STATES, nq))
    q[:, 1] = rng.uniform(-1.2, 1.2, size=STATES)
    q[:, scene.n + 2:] = rng.uniform(-1, 1, size=(STATES, 3))
    return q, rng.normal(size=(STATES, nq))


def measure(n: int, flag_sets, batches: int, peer_python: str, progress=print) -> list[dict]:
    from codegen.options import build_options
    from codegen.pipeline import generate
    from codegen.scene import default_scene
    from runtime.compile import LIBRARY_DIR, library_sources
    from .toolchain import compile_c
    scene = default_scene(n)
    start = time.perf_counter()
    model = generate(scene, build_options(scene, specialise=False, dense=False, rolled=False))
    looped = generate(scene, build_options(scene, specialise=False, dense=False), name=f"{scene.name}_rolled")
    ours_ops = {f.name: f.ops for f in model.functions}["forward_dynamics"]
    has_loops = "in loops" in {f.name: f.summary for f in looped.functions}["forward_dynamics"]
    rows = []
    with tempfile.TemporaryDirectory(prefix="peer-") as tmp:
        folder = Path(tmp)
        (folder / "chain.urdf").write_text(urdf(scene))
        traced = subprocess.run([peer_python, str(TRACE), str(folder / "chain.urdf"), str(folder)],
                                capture_output=True, text=True)
        if traced.returncode != 0:
            raise RuntimeError(f"tracing the peer failed: {traced.stderr.strip().splitlines()[-1:]}")
        info = json.loads((folder / "peer_ops.json").read_text())
        progress(f"  n = {n}: both generated in {time.perf_counter() - start:.1f} s")
        (folder / f"{model.name}.h").write_text(model.header)
        (folder / f"{model.name}.c").write_text(model.source)
        (folder / f"{looped.name}.h").write_text(looped.header)
        (folder / f"{looped.name}.c").write_text(looped.source)
        q, qd = random_states(scene, np.random.default_rng(n))
        with open(folder / "states.txt", "w") as out:
            for s in range(STATES):
                out.write(" ".join(repr(float(x)) for x in q[s]) + "\n")
                out.write(" ".join(repr(float(x)) for x in qd[s]) + "\n")
        reps = max(1, int(200 / n))
        (folder / "side.c").write_text(HARNESS.format(name=model.name, NAME=model.name.upper(), rname=looped.name,
                                                      states=STATES,
                                                      order=", ".join(map(str, pin_order(n))), reps=reps,
                                                      batches=batches))
        for flags in flag_sets:
            build = folder / "side"
            seconds = compile_c([folder / "side.c", folder / f"{model.name}.c", folder / f"{looped.name}.c",
                                 folder / "peer_aba.c",
                                 *library_sources()], build, flags=tuple(flags.split()),
                                include_dirs=[folder, LIBRARY_DIR])
            run = subprocess.run([str(build)], cwd=folder, capture_output=True, text=True, check=True)
            lines = run.stdout.split("\n")
            agree, agree_rolled = map(float, lines[0].split()[1:3])
            ours = [float(line.split()[1]) for line in lines[1:] if line]
            peer = [float(line.split()[3]) for line in lines[1:] if line]
            rolled = [float(line.split()[5]) for line in lines[1:] if line]
            ratios = [a / b for a, b in zip(ours, peer)]
            rolled_ratios = [a / b for a, b in zip(rolled, peer)]
            if not has_loops:                  # too short to loop over: the default is the straight-line kernel
                rolled = rolled_ratios = [math.nan]
            rows.append({"n": n, "flags": flags, "agree": agree, "agree_rolled": agree_rolled,
                         "ours_us": statistics.median(ours), "rolled_us": statistics.median(rolled),
                         "peer_us": statistics.median(peer), "ratio": statistics.median(ratios),
                         "ratio_min": min(ratios), "ratio_max": max(ratios),
                         "rolled_ratio": statistics.median(rolled_ratios), "rolled_ratio_min": min(rolled_ratios),
                         "rolled_ratio_max": max(rolled_ratios), "ours_ops": ours_ops.total,
                         "peer_ops": info["ops"]["total"], "compile_s": seconds})
            progress(f"  n = {n} {flags}: unrolled {rows[-1]['ours_us']:.3f} us, rolled {rows[-1]['rolled_us']:.3f} "
                     f"us, peer {rows[-1]['peer_us']:.3f} us, agree {agree:.1e}")
    return rows


def _cell(value: float, text: str) -> str:
    return "—" if math.isnan(value) else text


def peer_available(peer_python: str) -> str:
    """'' when ``peer_python`` can trace the peer, else why not."""
    check = subprocess.run([peer_python, "-c", "import sys; sys.path.insert(0, sys.argv[1]); import peer_trace; "
                            "peer_trace._load_casadi()", str(TRACE.parent)], capture_output=True, text=True)
    if check.returncode == 0:
        return ""
    last = (check.stderr.strip().splitlines() or ["?"])[-1]
    return (f"the peer (Pinocchio + CasADi, from casadi_kin_dyn) is not available to {peer_python}: {last}. "
            "It pins numpy 1.24, so give it an environment of its own: python3 -m venv .peer && "
            ".peer/bin/pip install cmeel-casadi-kin-dyn (the peer extra), then --peer-python .peer/bin/python")


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    from .cli import parse_links
    from codegen.interface import ROLLED_MIN_LINKS
    try:
        links = parse_links(args.links)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.batches < 1:
        print(f"error: --batches: must be >= 1, got {args.batches}", file=sys.stderr)
        return 2
    problem = peer_available(args.peer_python)
    if problem:
        print(f"peer: {problem}", file=sys.stderr)
        return 3
    rows = []
    for n in links:
        rows += measure(n, [f.strip() for f in args.flags.split(",") if f.strip()], args.batches, args.peer_python,
                        progress=lambda m: print(m, file=sys.stderr, flush=True))
    from .machine import describe
    from .toolchain import compiler_version
    print(f"Machine: {describe(compiler_version())}")
    print(f"Forward dynamics of the general built-in n-link chain (n + 5 coordinates), {STATES} random states, "
          f"median of {args.batches} alternating batches; ratio = ours / peer (min-max over the batches); rolled: "
          f"the kernel with loops over links 2..n - 1 (the default from {ROLLED_MIN_LINKS} links; — : too short "
          "to loop over).\n")
    print("| n | flags | peer µs | ours unrolled µs | ratio (min-max) | ours rolled µs | ratio (min-max) | "
          "agree (rel.) | peer ops | ours ops |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        rolled = _cell(r["rolled_us"], f"{r['rolled_us']:.3f}")
        rolled_ratio = _cell(r["rolled_ratio"], f"{r['rolled_ratio']:.2f} ({r['rolled_ratio_min']:.2f}-"
                                                f"{r['rolled_ratio_max']:.2f})")
        print(f"| {r['n']} | `{r['flags']}` | {r['peer_us']:.3f} | {r['ours_us']:.3f} | {r['ratio']:.2f} "
              f"({r['ratio_min']:.2f}-{r['ratio_max']:.2f}) | {rolled} | {rolled_ratio} | "
              f"{max(r['agree'], r['agree_rolled']):.0e} | {r['peer_ops']:,} | {r['ours_ops']:,} |")
    per_link = {}
    for key in ("peer_ops", "ours_ops"):
        ops = {r["n"]: r[key] for r in rows}
        if len(ops) >= 2:
            a, b = min(ops), max(ops)
            per_link[key] = (ops[b] - ops[a]) / (b - a)
    if per_link:
        print(f"\nOperations per added link: peer {per_link['peer_ops']:.1f}, ours {per_link['ours_ops']:.1f}.")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
