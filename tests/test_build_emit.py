"""The generated C: strict C99, C++-clean header, deterministic, committed copies up to date,
operation counts that match the emitted code, baked parameters, the CLI and the cffi build cache."""
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import codegen
from codegen.emit import c_expression
from codegen.pipeline import write_model
from codegen.ops import count_ops
from codegen.scene import MAX_LINKS, Scene, LineLink, load_scene
from codegen.options import build_options
from runtime.compile import copy_library, library_files
from conftest import cache_with_library, chain

ROOT = Path(__file__).resolve().parent.parent
STRICT = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]


_GENERATED = {}


def generated(scene, bake_params: bool = False, chart_b: bool = True, tangent: bool = False):
    """codegen.generate(scene), each (scene, bake_params, chart_b, tangent) derived once in this file (the tests only
    read it)."""
    key = (scene, bake_params, chart_b, tangent)
    if key not in _GENERATED:
        _GENERATED[key] = codegen.generate(scene, build_options(scene, bake_params=bake_params, chart_b=chart_b,
                                                                tangent=tangent))
    return _GENERATED[key]


def write(model, folder: Path) -> Path:
    """NAME.h, NAME.c and the library's files in folder; the path of NAME.c."""
    write_model(model, folder)
    copy_library(folder)
    return folder / f"{model.name}.c"


def library_sources(folder: Path) -> list[str]:
    return sorted(str(path) for path in folder.glob("gac_*.c"))


SCENES = {
    "case1": lambda: load_scene("paper-case1"),
    "case2": lambda: load_scene("paper-case2"),
    "rigid3d": lambda: chain(3, ("rigid", "line"), twists=True),
    "nowalls": lambda: Scene(name="free", links=(LineLink(1.0, 1.0),)),
}


@pytest.mark.parametrize("which", sorted(SCENES))
@pytest.mark.parametrize("bake", [False, True])
def test_generated_c_is_strict_c99_and_header_is_cxx(tmp_path, which, bake):
    """The model's source with the library's headers beside it (the library's own sources are held to the same
    flags at every optimisation level in test_build_clib)."""
    model = generated(SCENES[which](), bake, chart_b=not bake)      # a free base's second chart: unbaked case only
    source = write(model, tmp_path)
    subprocess.run(["gcc", *STRICT, "-O1", "-c", str(source), "-o", str(tmp_path / "m.o")], check=True)
    cxx = tmp_path / "use.cpp"
    cxx.write_text(f'#include "{model.name}.h"\nint main() {{ double p[{model.name.upper()}_NPARAM]; '
                   f'{model.name}_default_parameters(p); return p[0] > 0 ? 0 : 1; }}\n')
    subprocess.run(["g++", "-std=c++11", "-Wall", "-Wextra", "-pedantic", "-Werror", "-fsyntax-only",
                    "-I", str(tmp_path), str(cxx)], check=True)


@pytest.mark.parametrize("which", ["case2", "rigid3d"])
def test_header_names_every_coordinate_index(tmp_path, which):
    """NAME_Q_<coordinate> is the index of each of the model's coordinates in q (theta_-1 -> THETA_M1), so a
    controller need not hard-code q[1]: read back from a compiled C program, against the model's layout."""
    from codegen.specialise import coordinate_names, layout_for
    scene = SCENES[which]()
    model = generated(scene)
    write(model, tmp_path)
    names = [coordinate_names(scene.n)[i] for i in layout_for(scene, True).free]
    NAME = model.name.upper()
    macros = [f"{NAME}_Q_{name.replace('-', 'M').upper()}" for name in names]
    program = tmp_path / "indices.c"
    program.write_text(f'#include <stdio.h>\n#include "{model.name}.h"\nint main(void) {{\n'
                       + "".join(f'    printf("%d\\n", {m});\n' for m in macros)
                       + f'    printf("%d\\n", {NAME}_NQ);\n    return 0;\n}}\n')
    subprocess.run(["gcc", *STRICT, "-I", str(tmp_path), str(program), "-o", str(tmp_path / "indices")], check=True)
    printed = subprocess.run([str(tmp_path / "indices")], capture_output=True, text=True, check=True).stdout.split()
    assert [int(v) for v in printed] == [*range(len(names)), len(names)]


@pytest.fixture(scope="module")
def library_objects(tmp_path_factory) -> list[Path]:
    """The library's sources compiled one by one (-std=c99 -O2), once for this file."""
    folder = tmp_path_factory.mktemp("library")
    copy_library(folder)
    objects = []
    for path in library_sources(folder):
        objects.append(folder / (Path(path).stem + ".o"))
        subprocess.run(["gcc", "-std=c99", "-O2", "-c", path, "-o", str(objects[-1])], check=True)
    return objects


@pytest.mark.parametrize("scene_name", ["paper-case1", "paper-case2"])     # planar; a free base with chart B
def test_no_globals_and_no_malloc_in_generated_code(tmp_path, scene_name, library_objects):
    """The model's and the library's object files define only code and read-only data (the descriptors and the
    parameter table, whose pointers are relocated, sit in .data.rel.ro), and call only libm and the library."""
    model = generated(load_scene(scene_name))
    source = write(model, tmp_path)
    objects = [tmp_path / f"{model.name}.o", *library_objects]
    subprocess.run(["gcc", "-std=c99", "-O2", "-c", str(source), "-o", str(objects[0])], check=True)
    defined = set()
    for obj in objects:
        symbols = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
        sections = subprocess.run(["objdump", "-t", str(obj)], capture_output=True, text=True, check=True).stdout
        for line in symbols.splitlines():
            kind, symbol = line.split()[-2:]
            if kind in "Dd":                        # a const object with pointers: read-only after relocation
                section = next(row.split()[-3] for row in sections.splitlines() if row.endswith(f" {symbol}"))
                assert section.startswith(".data.rel.ro"), f"writable global in generated code: {line} ({section})"
                assert symbol in (f"{model.name}_model", f"{model.name}_model_b", f"{model.name}_parameter_info"), line
                continue
            assert kind in "TtRrU", f"writable global in generated code: {line}"
            if kind == "U":
                # libm, the library, the memset/memcpy/memmove gcc itself emits for array copies, and C's clock()
                # (the wall-time budget's default clock), C99's fenv.h (the impact accuracy's evaluations under each
                # rounding mode, the caller's mode restored); the global offset table is where a position-independent
                # build reads a library function's address (a schedule's controller), not a call
                assert symbol.startswith("gac_") or symbol in {
                    "sin", "cos", "sincos", "sqrt", "pow", "fabs", "atan2", "hypot", "floor", "memset", "memcpy",
                    "memmove", "clock", "fegetround", "fesetround", "nextafter", "_GLOBAL_OFFSET_TABLE_",
                    "sinl", "cosl", "sincosl", "sqrtl", "powl", "fabsl"}, \
                    f"unexpected call: {symbol}"
            elif kind in "TR":
                defined.add(symbol)
    undefined_library = {line.split()[-1] for obj in objects for line in subprocess.run(
        ["nm", "-u", str(obj)], capture_output=True, text=True, check=True).stdout.splitlines()
        if line.split()[-1].startswith("gac_")}
    assert undefined_library <= defined                      # the library defines everything it is asked for


GENERATE_AND_HASH = (
    "import hashlib, codegen; from codegen.scene import load_scene; "
    "m = codegen.generate(load_scene('{scene}')); "
    "print(hashlib.sha256((m.header + m.source).encode()).hexdigest())"
)


@pytest.mark.parametrize("scene", ["paper-case1", "paper-case2"])
def test_same_scene_gives_byte_identical_output_across_processes(scene):
    digests = set()
    for seed in ("1", "2", "3"):
        env = dict(os.environ, PYTHONHASHSEED=seed, PYTHONPATH=str(ROOT))
        out = subprocess.run([sys.executable, "-c", GENERATE_AND_HASH.format(scene=scene)], env=env,
                             capture_output=True, text=True, check=True, cwd=ROOT)
        digests.add(out.stdout.strip())
    assert len(digests) == 1


@pytest.mark.parametrize("scene,name", [("paper-case1", "paper_case1"), ("paper-case2", "paper_case2")])
def test_committed_generated_code_is_up_to_date(scene, name):
    model = generated(load_scene(scene))
    committed = ROOT / "generated"
    assert (committed / f"{name}.h").read_text() == model.header, \
        f"generated/{name}.h is stale: run python -m codegen --scene {scene}"
    assert (committed / f"{name}.c").read_text() == model.source


def test_committed_library_copies_are_up_to_date():
    """generated/ holds the library (runtime/c) beside the models, byte for byte, and nothing else of it."""
    committed = ROOT / "generated"
    library = library_files()
    assert [p.name for p in library_files(committed)] == [p.name for p in library], \
        "generated/ has other library files than runtime/c: run python -m codegen --scene paper-case1"
    for path in library:
        assert (committed / path.name).read_text() == path.read_text(), \
            f"generated/{path.name} is stale: run python -m codegen --scene paper-case1 --no-compile"


LITERAL = re.compile(r"(?<![\w\]])\d+\.\d*(?:e[-+]?\d+)?|(?<![\w\]])\d+e[-+]?\d+")


def count_c_operators(rhs: str) -> dict:
    """Count the operators in one emitted C expression, straight from the text."""
    calls = len(re.findall(r"\b(?:sin|cos|sqrt|pow|tan|exp|log)l?\(", rhs))     # (l: the long-double kernels')
    text = LITERAL.sub("L", rhs)
    text = re.sub(r"\[\d+\]", "", text)
    binary_minus = len(re.findall(r"(?<=[\w)\]])\s*-", text))
    return {"add": text.count("+") + binary_minus, "mul": text.count("*"), "div": text.count("/"),
            "calls": calls}


@pytest.mark.parametrize("which", ["case1", "rigid3d"])
def test_reported_operation_counts_match_the_emitted_code(which):
    """Every kernel's reported count is what its lines compute; in the block tangent the loop's body (indented)
    counts once per direction and its pointer lines (a seed array's direction j) are not arithmetic of the model."""
    from codegen import interface
    model = generated(SCENES[which]())
    for function in model.functions:
        totals = {"add": 0, "mul": 0, "div": 0, "calls": 0}
        for line in function.lines:
            if line.startswith(("for (", "}")) or line.lstrip().startswith(("(void)", "const double *")):
                continue
            times = interface.TANGENT_BLOCK if line.startswith("    ") else 1
            for key, value in count_c_operators(line.split("=", 1)[1]).items():
                totals[key] += times * value
        ops = function.ops
        assert totals == {"add": ops.add, "mul": ops.mul, "div": ops.div, "calls": ops.calls}, function.name


def test_printer_evaluates_like_sympy():
    x, y, z = sp.symbols("x y z", real=True)
    values = {x: 0.7, y: -1.3, z: 2.1}
    expressions = [x ** 3 * y / z ** 2, -x / 3 + y * sp.Rational(2, 7) - 1, sp.sqrt(x) * sp.cos(y) / (z * x),
                   1 / (x * y), -(x - y) * 2.5 * z ** 2, x ** -2, sp.sin(z) * y + z ** 4]
    namespace = {"sin": math.sin, "cos": math.cos, "sqrt": math.sqrt, "pow": math.pow,
                 "x": 0.7, "y": -1.3, "z": 2.1}
    for expr in expressions:
        printed = c_expression(expr)
        assert eval(printed, namespace) == pytest.approx(float(expr.subs(values)), rel=1e-14), printed
        counted = count_ops([expr]).as_dict()
        assert {k: counted[k] for k in ("add", "mul", "div", "calls")} == count_c_operators(printed), printed
    # x*x*x*y/(z*z): 4 mul, 1 div
    assert count_ops([x ** 3 * y / z ** 2]).as_dict() == {"add": 0, "mul": 4, "div": 1, "calls": 0, "total": 5}
    assert count_ops([-x / 3 + y * sp.Rational(2, 7) - 1]).as_dict()["add"] == 2


def test_baked_parameters_give_the_same_dynamics(compiled):
    scene = chain(2, ("rigid", "line"), twists=True)
    general, baked = compiled(scene), compiled(scene, bake_params=True)
    q = np.array([0.3, -0.4, 0.5, 1.1, -0.7, 0.1, 0.2])
    qd = np.linspace(-1, 1, scene.nq)
    assert np.allclose(baked.forward_dynamics(q, qd), general.forward_dynamics(q, qd), rtol=1e-13, atol=1e-13)
    assert np.allclose(baked.mass_matrix(q), general.mass_matrix(q), rtol=1e-14, atol=1e-14)
    kernels = baked.generated.source.split("_impact(")[0].split("_mass_matrix(")[1]
    assert re.search(r"\bp\[", kernels) is None            # no parameter is read at run time


def run_cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "codegen", *args], capture_output=True, text=True,
                          cwd=ROOT, env=env)


def test_cli_writes_files_and_reports(tmp_path):
    result = run_cli("--links", "2", "--out", str(tmp_path), "--name", "two", "--no-compile")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "two.h").exists() and (tmp_path / "two.c").exists()
    assert "forward_dynamics" in result.stdout and "derive" in result.stdout and "cse" in result.stdout
    assert "derive mass_matrix" in result.stderr            # progress


def test_cli_rejects_bad_input_clearly(tmp_path):
    result = run_cli("--links", "0", "--out", str(tmp_path))
    assert result.returncode == 2 and f"--links: must be in 1..{MAX_LINKS}, got 0" in result.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text('[[links]]\nlength = -1.0\nmu = 1.0\n')
    result = run_cli("--scene", str(bad), "--out", str(tmp_path))
    assert result.returncode == 2 and "links[1].length: must be in [1e-09, 1e+09] m" in result.stderr
    assert "Traceback" not in result.stderr
    assert run_cli("--help").returncode == 0


BUILD = ("import sys; sys.path.insert(0, {root!r}); from runtime import load_model; "
         "m = load_model('paper-case2'); print(m.forward_dynamics(m.q0, m.qd0)[4])")


def test_concurrent_builds_of_the_same_model_both_succeed(tmp_path):
    """Two processes build one model into an empty model cache at once: one module, both runs right.  (The C
    library's object, which every model links, is copied in from the suite's cache: this test is about the model.)"""
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(cache_with_library(tmp_path / "cache")))
    code = BUILD.format(root=str(ROOT))
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outputs = [p.communicate(timeout=300) for p in procs]
    for proc, (out, err) in zip(procs, outputs):
        assert proc.returncode == 0, err
        assert float(out) == pytest.approx(-9.81)          # free fall from rest
    built = list((tmp_path / "cache").glob("_gac_*"))
    assert len(built) == 1 and built[0].is_file()            # one module, no leftover build dirs


def test_missing_compiler_is_reported_clearly(tmp_path):
    env = dict(os.environ, GIBBS_APPELL_CACHE=str(tmp_path / "cache"), CC="/nonexistent/cc")
    code = BUILD.format(root=str(ROOT))
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert result.returncode != 0
    assert "CompilerNotFound: no C compiler found: tried '/nonexistent/cc'" in result.stderr


def test_interface_is_plain_data_and_matches_the_kernels():
    """codegen.interface loads neither sympy, jinja2 nor the runtime, and declares the kernels the generator
    emits (names, inputs and output, in order) and every per-model function the runtime's table calls."""
    code = ("import sys, codegen.interface\n"
            "print(sorted(m for m in sys.modules if m in ('sympy', 'jinja2', 'runtime')))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert result.returncode == 0 and result.stdout.strip() == "[]", result.stdout + result.stderr
    from codegen import interface
    model = generated(SCENES["nowalls"](), tangent=True)                 # every kernel, the tangents too
    assert [(f.name, tuple(f.inputs), f.output) for f in model.functions] == \
        [(f.name, tuple(a.name for a in f.args[:-1]), f.args[-1].name) for f in interface.KERNELS]
    for function in interface.ALL_FUNCTIONS:               # declared in the header and defined in the source
        assert function.declaration(model.name, "GAC_RESTRICT") + ";" in model.header, function.name
        assert f"{model.name}_{function.name}(" in model.source, function.name
