"""Shared helpers: the suite's fixed scenes, random parameters and states, the reference model, and the models
of a scene -- derived (run as Python, no C; tests/derived.py) or compiled -- made once per session.

Tiers (file name prefixes): test_scene_* (scene description), test_derive_* (the derivation, evaluated as Python
against the independent reference model, no C), test_build_* (generated C text, compile, C API), test_sim_*
(the hybrid simulation), test_tools_* (command lines, FMU, exports, reports), test_docs.py.

Compiled models are the expensive part (a derivation and a C compile each), so tests take one of the fixed
scenes of ``chain`` and vary the links through random parameter vectors (``random_parameters``: lengths,
masses, centres of mass, inertias and gravity are the runtime array p) and random states, not a new scene per
case.  The same ``chain`` arguments give the same scene in every test file and worker, so each model is built
once and shared through the on-disk cache."""
from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))      # for `from conftest import ...`

from codegen.scene import Joint, LineLink, RigidLink, Scene, Wall, WALL_NAMES, contact_points  # noqa: E402
from studies import reference  # noqa: E402
from studies.reference import reference_of, with_parameters  # noqa: E402,F401

FAR = 50.0   # walls far away: every (point, wall) pair exists but no state is outside


def random_link(rng, kind: str):
    if kind == "line":
        return LineLink(rng.uniform(0.2, 2.0), rng.uniform(0.1, 3.0), tuple(rng.uniform(0.0, 1e-2, size=3)))
    l, m, h, K = reference.random_link(rng)
    com = h / m
    inertia = K - m * (com @ com * np.eye(3) - np.outer(com, com))   # back to the centre of mass
    inertia = (inertia + inertia.T) / 2
    return RigidLink(l, m, tuple(com), tuple(map(tuple, inertia)))


def random_scene(n: int, seed: int, random_twists: bool = False, kinds=("line",), name=None,
                 walls=True) -> Scene:
    """A scene with random links (kinds cycled along the chain), random twists T_2..T_n if asked,
    random gravity, and all six walls far away."""
    rng = np.random.default_rng(seed)
    links = tuple(random_link(rng, kinds[i % len(kinds)]) for i in range(n))
    twists = tuple(map(lambda T: tuple(map(tuple, T)), (reference.random_rotation(rng) for _ in range(n - 1)))) \
        if random_twists else ()
    wall_list = tuple(Wall(w, -FAR if w.endswith("min") else FAR, rng.uniform(0, 1)) for w in WALL_NAMES) \
        if walls else ()
    q0 = (0.0,) * (n + 5)
    return Scene(name=name or f"rand{n}_{seed}", links=links, twists=twists, gravity=rng.uniform(0, 12),
                 walls=wall_list, q0=q0)


def random_parameters(scene: Scene, seed: int) -> np.ndarray:
    """A new random parameter vector with the layout of ``scene`` (same link kinds)."""
    rng = np.random.default_rng(seed)
    other = random_scene(scene.n, seed, kinds=tuple(link.kind for link in scene.links), walls=False)
    p = scene.parameter_vector().copy()
    q = other.parameter_vector()
    p[:len(q)] = q
    p[0] = rng.uniform(0, 12)
    return p


def rz(angle):
    c, s = math.cos(angle), math.sin(angle)
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


def random_planar_scene(n, seed, normal_axis):
    """A planar chain (joint axes along X3 or X1), in-plane centres of mass, in-plane spin and drift,
    a floor 0.2 m under its lowest point."""
    rng = np.random.default_rng(seed)
    links = []
    for i in range(n):
        if i % 2:
            l, m = rng.uniform(0.3, 1.0), rng.uniform(0.2, 2.0)
            Ixx, Iyy, Izz, Ixy = 0.01 * m, 0.02 * m, 0.025 * m, 0.003 * m
            links.append(RigidLink(l, m, (l * rng.uniform(0.2, 0.8), 0.05 * l, 0.0),
                                   ((Ixx, Ixy, 0.0), (Ixy, Iyy, 0.0), (0.0, 0.0, Izz))))
        else:
            links.append(LineLink(rng.uniform(0.3, 1.0), rng.uniform(0.5, 2.0), tuple(rng.uniform(1e-5, 1e-3, 3))))
    theta_m1 = -math.pi / 2 if normal_axis == 2 else 0.0
    q = [theta_m1, 0.0] + list(rng.uniform(-1.5, 1.5, n)) + [0.0, 0.0, 0.0]
    qd = [0.0, 0.0] + list(rng.normal(0, 2.0, n)) + [0.0, 0.0, 0.0]
    for axis in (0, 1, 2):
        if axis != normal_axis:
            qd[n + 2 + axis] = -abs(rng.normal()) if axis == 1 else rng.normal()   # heading for the floor
    twists = tuple(rz(a) for a in rng.uniform(-1, 1, n - 1))
    probe = Scene(name="probe", links=tuple(links), twists=twists, q0=tuple(q), qd0=tuple(qd))
    floor = contact_points(probe, np.array(q))[:, 1].min() - 0.2
    walls = (Wall("x2_min", floor, 0.8), Wall(f"x{3 - normal_axis}_min", -20.0), Wall(f"x{normal_axis + 1}_max", 5.0))
    return Scene(name=f"planar{n}_{seed}", links=tuple(links), twists=twists, walls=walls, q0=tuple(q),
                 qd0=tuple(qd), gravity=9.81)


KIND_CODES = {("line",): 0, ("rigid",): 1, ("line", "rigid"): 2, ("rigid", "line"): 3}


def chain(n: int, kinds=("line",), twists: bool = False, walls: bool = True) -> Scene:
    """One of the suite's fixed scenes: ``n`` links of ``kinds`` (cycled along the chain), random (but fixed)
    twists T_2..T_n if ``twists``, fixed gravity and, if ``walls``, all six walls far away.  Vary the links of
    a test case with ``random_parameters(scene, seed)``; twists are built into the model, not parameters."""
    kinds = tuple(kinds)
    twists = bool(twists) and n >= 2
    seed = 5000 + 100 * n + 10 * KIND_CODES[kinds] + 2 * twists + (not walls)
    name = f"chain{n}_{'_'.join(kinds)}" + ("_tw" if twists else "") + ("" if walls else "_open")
    return random_scene(n, seed, random_twists=twists, kinds=kinds, name=name, walls=walls)


def tilted(scene: Scene, seed: int, normal: int | None = None) -> Scene:
    """The scene with gravity along a random unit vector (gravity_direction, a scene constant built into the model);
    with ``normal`` (0 or 2) one in the plane normal to that box axis, so that a planar scene stays planar."""
    d = np.random.default_rng(seed).normal(size=3)
    if normal is not None:
        d[normal] = 0.0
    return dataclasses.replace(scene, name=f"{scene.name}_tilt", gravity_direction=tuple(d / np.linalg.norm(d)))


INPUTS_3D = ("theta_-1", "theta_0", "theta_1", "theta_2", "theta_3", "X1", "X2", "X3")


def driven(scene: Scene, seed: int, inputs=INPUTS_3D) -> Scene:
    """The scene with a random spring and damper on every joint and the given inputs (those it has)."""
    rng = np.random.default_rng(seed)
    joints = tuple(Joint(rng.uniform(0.5, 20.0), rng.uniform(-1, 1), rng.uniform(0.1, 3.0))
                   for _ in range(scene.n - 1))
    exists = [i for i in inputs if not i.startswith("theta_") or int(i[6:]) <= scene.n]
    return dataclasses.replace(scene, joints=joints, inputs=tuple(exists))


def driven_free_chain() -> Scene:
    """The suite's fixed driven scene: 3 twisted links (rigid, slender, rigid), springs and dampers on both
    joints, inputs on theta_2 and theta_3, no walls, g = 0 and a random start velocity."""
    scene = driven(chain(3, ("rigid", "line"), twists=True, walls=False), seed=91, inputs=("theta_2", "theta_3"))
    return dataclasses.replace(scene, gravity=0.0, qd0=tuple(np.random.default_rng(91).normal(size=8)))


def random_states(n: int, seed: int, count: int):
    """``count`` random (q, qd) of an n-link chain (studies.reference.random_state), from one seed."""
    rng = np.random.default_rng(seed)
    return [reference.random_state(n, rng) for _ in range(count)]


_MODELS = {}
_DERIVED = {}


@pytest.fixture(scope="session")
def derived():
    """derived(scene, specialise=False, bake_params=False, formulation="gibbs_appell") -> tests/derived.DerivedModel:
    the scene's kernels as derived and flattened, run as Python (no C), each kernel made once per session."""
    from derived import DerivedModel

    def get(scene: Scene, specialise: bool = False, bake_params: bool = False, formulation: str = "gibbs_appell"):
        key = (scene, specialise, bake_params, formulation)
        if key not in _DERIVED:
            _DERIVED[key] = DerivedModel(scene, specialise=specialise, bake_params=bake_params,
                                         formulation=formulation)
        return _DERIVED[key]
    return get


@pytest.fixture(scope="session")
def compiled():
    """compiled(scene, bake_params=False, specialise=False, dense=None, chart_b=False, tangent=False,
    extended=False) -> runtime.CompiledModel, built once per session.  Tests get the general model unless they ask
    for the specialised one, without a free base's second chart (half the code to build) unless they ask for it (the
    tests that pass through the gimbal lock: test_sim_charts, test_sim_gimbal_impact, test_tools_parity), without
    the forward dynamics' tangent kernels unless they ask for them (the derivative tests: test_build_tangents,
    test_sim_sensitivities), as load_model does, and without the long-double kernels of the impact's accuracy
    unless they ask for them (load_model's default: the tests of that accuracy, test_sim_impact_accuracy)."""
    from runtime import load_model

    def get(scene: Scene, bake_params: bool = False, specialise: bool = False, dense=None, chart_b: bool = False,
            tangent: bool = False, extended: bool = False):
        key = (scene, bake_params, specialise, dense, chart_b, tangent, extended)
        if key not in _MODELS:
            _MODELS[key] = load_model(scene, bake_params=bake_params, specialise=specialise, dense=dense,
                                      chart_b=chart_b, tangent=tangent, extended=extended)
        return _MODELS[key]
    return get


SANITIZE = ("-std=c99", "-g", "-O1", "-Wall", "-Wextra", "-pedantic", "-Werror", "-fsanitize=address,undefined",
            "-fno-sanitize-recover=all", "-fno-omit-frame-pointer")


def perturbed_start(model, direction: str, h: float, p, q0, qd0):
    """Copies of (p, q0, qd0) moved by h along a sensitivity direction's name: 'q0[NAME]' or 'qd0[NAME]' (NAME a
    coordinate of the full layout) or a parameter's name, for central differences of whole runs."""
    p1, q1, qd1 = np.array(p, dtype=float), np.array(q0, dtype=float), np.array(qd0, dtype=float)
    full = model.scene.full_coordinate_names()
    if direction.startswith("q0["):
        q1[full.index(direction[3:-1])] += h
    elif direction.startswith("qd0["):
        qd1[full.index(direction[4:-1])] += h
    elif direction.startswith("turn_") and direction not in model.parameter_names:   # a plane's normal turned by h
        axis, plane = direction[5], direction[7:]                                   # about X1, X2 or X3
        rows = [model.parameter_names.index(f"normal_{c}_{plane}") for c in "xyz"]
        k = "xyz".index(axis)
        c, s = np.cos(h), np.sin(h)
        turn = np.eye(3)
        i, j = (k + 1) % 3, (k + 2) % 3
        turn[i, i], turn[i, j], turn[j, i], turn[j, j] = c, -s, s, c
        p1[rows] = turn @ p1[rows]
    else:
        p1[model.parameter_names.index(direction)] += h
    return p1, q1, qd1


def cache_with_library(folder: Path) -> Path:
    """A new model cache at ``folder`` holding only the C library's object (and its sidecar), copied from the suite's
    cache: a test about generating or compiling a model into an empty cache need not recompile the library, which
    every model links (test_build_cache.py's own tests of the library's entry start from nothing)."""
    import shutil
    from codegen.options import DEFAULT_FLAGS
    from runtime.compile import library_object
    library = library_object(DEFAULT_FLAGS)
    folder.mkdir(parents=True)
    for path in (library, library.with_name(f"sha256_{library.stem}.txt")):
        shutil.copy(path, folder / path.name)
    return folder


def sanitized_build(folder: Path, sources, output: str) -> Path:
    """An executable of the C sources in ``folder`` (a model, a program) linked with the C library built strictly
    with ASan + UBSan, the library compiled once for the whole suite (the build's cache of library objects)."""
    import subprocess
    from runtime.compile import library_object
    library = library_object(SANITIZE)
    exe = folder / output
    subprocess.run(["gcc", *SANITIZE, "-I", str(folder), *map(str, sources), str(library), "-lm", "-o", str(exe)],
                   check=True)
    return exe


def quick_model(scene, specialise: bool = True, **options):
    """load_model(scene, ...) without a free base's second chart, without the tangent kernels and without the
    long-double kernels of the impact's accuracy (the code the tests of other things do not need: half the
    derivation); the tests of the defaults call load_model."""
    from runtime import load_model
    options.setdefault("chart_b", False)
    options.setdefault("tangent", False)
    options.setdefault("extended", False)
    return load_model(scene, specialise=specialise, **options)


def wall_friction(scene, p) -> dict:
    """Each rough wall's Coulomb coefficient in the parameter vector p, by wall name ('x2_min': c_f)."""
    names = scene.parameter_names()
    return {name[len("friction_"):]: float(p[i]) for i, name in enumerate(names) if name.startswith("friction_")}


def mpmath_program(kernel):
    """The kernel's straight-line program (the expressions its C is printed from) as a Python function of (q, p)
    and any further input by keyword (qd=..., f=...), lists of mpmath numbers, evaluated in mpmath's working
    precision: the kernel's outputs, independently of C."""
    import mpmath
    from sympy.printing.pycode import MpmathPrinter
    printer = MpmathPrinter({"fully_qualified_modules": True})
    lines = ["def kernel(q, p, qd=None, f=None):"]
    lines += [f"    {printer.doprint(symbol)} = {printer.doprint(expr)}" for symbol, expr in kernel.tape.assignments]
    lines.append("    return [" + ", ".join(printer.doprint(value) for value in kernel.values) + "]")
    namespace = {"mpmath": mpmath}
    exec("\n".join(lines), namespace)
    return namespace["kernel"]
