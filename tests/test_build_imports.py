"""What loads when: running a model that is already built loads neither the computer algebra (sympy) nor the
templates (jinja2), generating loads sympy on demand, and the product never loads the studies (studies/).  The
layers of the product and their one-way imports are checked in test_build_layers.py."""
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


PACKAGES = ("codegen", "runtime", "studies")


def imports_of(path: Path, package: str) -> set:
    """The packages (of PACKAGES) a source file imports, in any import statement (inside functions too)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            found.add(package if node.level else (node.module or "").split(".")[0])
    return found & set(PACKAGES)


def sources(package: str):
    return sorted((ROOT / package).rglob("*.py"))


def test_the_product_never_imports_the_studies():
    """No module of codegen/ or runtime/ imports studies, not even inside a function; and importing every
    one of them loads no study."""
    offenders = [str(path.relative_to(ROOT)) for package in ("codegen", "runtime") for path in sources(package)
                 if "studies" in imports_of(path, package)]
    assert offenders == []
    modules = [".".join(path.relative_to(ROOT).with_suffix("").parts) for package in ("codegen", "runtime")
               for path in sources(package) if path.name != "__main__.py"]
    loaded = run_python(
        f"import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name.removesuffix('.__init__'))\n"
        f"print(sorted(m for m in sys.modules if m == 'studies' or m.startswith('studies.')))")
    assert loaded == "[]"


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
