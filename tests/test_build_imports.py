"""Dependencies run one way: scene -> derivation -> emission -> build -> simulation.  Running a model that is
already built loads neither the computer algebra (sympy) nor the templates (jinja2), the generator never
imports the runtime, and the studies (studies/) import codegen and runtime, never the other way."""
import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_python(code: str) -> str:
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip().splitlines()[-1]


def test_simulating_a_built_model_does_not_load_sympy_or_jinja2():
    from runtime import load_model
    load_model("paper-case2")                        # built (or found) in the cache the subprocess reads
    loaded = run_python(
        "import sys, runtime\n"
        "result = runtime.simulate('paper-case2', 0.5)\n"
        "assert result.success and len(result.impacts) >= 1, result.message\n"
        "print(sorted(m for m in ('sympy', 'jinja2') if m in sys.modules))")
    assert loaded == "[]"


def test_generating_loads_sympy_on_demand():
    loaded = run_python(
        "import sys, codegen\n"
        "before = 'sympy' in sys.modules\n"
        "codegen.generate\n"
        "print(before, 'sympy' in sys.modules)")
    assert loaded == "False True"


def test_the_generator_never_imports_the_runtime():
    modules = ["codegen", "codegen.scene", "codegen.pipeline", "codegen.cache", "codegen.cli", "codegen.emit",
               "codegen.kernels", "codegen.articulated", "codegen.lagrange", "codegen.specialise"]
    loaded = run_python(
        f"import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        f"print(sorted(m for m in sys.modules if m == 'runtime' or m.startswith('runtime.')))")
    assert loaded == "[]"


PACKAGES = ("codegen", "runtime", "studies")


def imports_of(path: Path, package: str, module_level_only: bool) -> set:
    """The packages (of PACKAGES) a source file imports: in every import statement, or only in those that run
    when the module loads (not inside a function)."""
    found = set()

    def visit(node):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            found.add(package if node.level else (node.module or "").split(".")[0])
        elif module_level_only and isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            return
        for child in ast.iter_child_nodes(node):
            visit(child)
    visit(ast.parse(path.read_text(), str(path)))
    return found & set(PACKAGES)


def sources(package: str):
    return sorted((ROOT / package).rglob("*.py"))


def test_the_product_never_imports_the_studies():
    """No module of codegen/ or runtime/ imports studies, not even inside a function; and importing every
    one of them loads no study."""
    offenders = [str(path.relative_to(ROOT)) for package in ("codegen", "runtime") for path in sources(package)
                 if "studies" in imports_of(path, package, module_level_only=False)]
    assert offenders == []
    modules = [".".join(path.relative_to(ROOT).with_suffix("").parts) for package in ("codegen", "runtime")
               for path in sources(package) if path.name != "__main__.py"]
    loaded = run_python(
        f"import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name.removesuffix('.__init__'))\n"
        f"print(sorted(m for m in sys.modules if m == 'studies' or m.startswith('studies.')))")
    assert loaded == "[]"


def test_no_import_cycle_among_the_packages():
    """The packages' import graph (the imports that run when a module loads) has no cycle: codegen <- runtime
    <- studies, one way."""
    graph = {package: set() for package in PACKAGES}
    for package in PACKAGES:
        for path in sources(package):
            graph[package] |= imports_of(path, package, module_level_only=True) - {package}
    order, state = [], {}

    def visit(package, trail):
        if state.get(package) == "open":
            raise AssertionError("import cycle: " + " -> ".join(trail + [package]))
        if state.get(package) != "done":
            state[package] = "open"
            for other in sorted(graph[package]):
                visit(other, trail + [package])
            state[package] = "done"
            order.append(package)
    for package in PACKAGES:
        visit(package, [])
    assert "studies" not in graph["codegen"] | graph["runtime"]
    assert graph["studies"] <= {"codegen", "runtime"}


EDGE = re.compile(r"""getattr\([\w.]*lib\b|ffi\.new\(f["']|def_extern""")


def test_calls_into_a_compiled_model_go_through_one_edge():
    """Every lookup of a model's C function or type by its name (NAME_sim_init, NAME_options, the extern "Python"
    callbacks) is in runtime.model.CInterface, bound from codegen.interface; elsewhere the product calls
    model.c.<function> and model.c.new(<type>)."""
    offenders = []
    for package in ("codegen", "runtime", "studies"):
        for path in sources(package):
            if path.name == "model.py" and package == "runtime":
                continue
            for number, line in enumerate(path.read_text().splitlines(), start=1):
                if EDGE.search(line):
                    offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert offenders == [], "\n".join(offenders)
