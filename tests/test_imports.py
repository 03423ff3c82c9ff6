"""Dependencies run one way: scene -> derivation -> emission -> build -> simulation.  Running a model that is
already built loads neither the computer algebra (sympy) nor the templates (jinja2), and the generator
never imports the runtime."""
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
               "codegen.model", "codegen.articulated", "codegen.lagrange", "codegen.opscount", "codegen.specialise"]
    loaded = run_python(
        f"import importlib, sys\n"
        f"for name in {modules!r}: importlib.import_module(name)\n"
        f"print(sorted(m for m in sys.modules if m == 'runtime' or m.startswith('runtime.')))")
    assert loaded == "[]"
