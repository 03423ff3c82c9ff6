"""The product's layers point one way.  Every module of codegen/, runtime/ and templates/ has a layer (LAYERS);
a module imports modules of its own layer or a lower one only, wherever the import stands (module level, inside
a function or method, under ``if TYPE_CHECKING``), and a package located by name (``find_spec``,
``importlib.resources.files``, ``import_module``) counts as imported.  The description layer imports no sympy,
jinja2 or cffi (numpy only); another layer is used through its public names; no product module imports the
studies; and no import circle joins two modules (of the product, or of the studies, which sit outside the product
and may import any of it).  A new module without a layer fails here: give it one."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PRODUCT = ("codegen", "runtime", "templates")

DESCRIPTION, DERIVATION, BUILD, SIMULATION, TOOLS = 1, 2, 3, 4, 5
LAYER_NAMES = {DESCRIPTION: "description", DERIVATION: "derivation and emission", BUILD: "build",
               SIMULATION: "simulation", TOOLS: "tools"}

LAYERS = {
    # 1. description: scenes and what follows from them without algebra (numpy only)
    "codegen.errors": DESCRIPTION,            # SceneError
    "codegen.version": DESCRIPTION,
    "codegen.urdf": DESCRIPTION,              # URDF text <-> link tables
    "codegen.scene": DESCRIPTION,
    "codegen.scenes": DESCRIPTION,            # the shipped scene files (package data)
    "codegen.parameters": DESCRIPTION,        # the allowed values of every runtime parameter
    "codegen.options": DESCRIPTION,           # every choice of a build, resolved once
    "codegen.specialise": DESCRIPTION,        # a model's layout
    "codegen.charts": DESCRIPTION,            # the second base chart's scene
    "codegen.interface": DESCRIPTION,         # the C interface, as plain data
    "codegen.outputs": DESCRIPTION,           # output paths checked before work
    # 2. derivation and emission (sympy, jinja2)
    "codegen": DERIVATION,                    # the package: load_scene, generate, GeneratedModel
    "codegen.tape": DERIVATION,
    "codegen.kinematics": DERIVATION,
    "codegen.gibbs_appell": DERIVATION,
    "codegen.articulated": DERIVATION,
    "codegen.linalg": DERIVATION,
    "codegen.kernels": DERIVATION,
    "codegen.lagrange": DERIVATION,
    "codegen.flatten": DERIVATION,
    "codegen.tangent": DERIVATION,
    "codegen.ops": DERIVATION,
    "codegen.rolled": DERIVATION,
    "codegen.emit": DERIVATION,
    "codegen.pipeline": DERIVATION,
    "codegen.combine": DERIVATION,            # several chains' kernels wrapped into one model
    "codegen.artifact": DERIVATION,           # the generated text as plain data
    "codegen.cache": DERIVATION,              # generate_cached and the cache directory
    "codegen.fmu": DERIVATION,                # an FMU's texts
    "templates": DERIVATION,
    # 3. build (cffi) and the C library runtime/c, its package data
    "runtime.compile": BUILD,
    "runtime.header": BUILD,                  # gac.h read: its constants and its declarations for cffi
    # 4. simulation
    "runtime": SIMULATION,                    # the package: load_model, simulate, compile_model
    "runtime.model": SIMULATION,
    "runtime.simulate": SIMULATION,
    "runtime.inputs": SIMULATION,
    "runtime.sensitivities": SIMULATION,
    "runtime.horizon": SIMULATION,
    # 5. tools: command lines and what they drive
    "codegen.cli": TOOLS,
    "codegen.__main__": TOOLS,
    "runtime.cli": TOOLS,
    "runtime.__main__": TOOLS,
    "runtime.sweep": TOOLS,
    "runtime.ensemble": TOOLS,
    "runtime.export": TOOLS,
    "runtime.fmu": TOOLS,
    "runtime.plots": TOOLS,
    "runtime.animate": TOOLS,
}

ALGEBRA = ("sympy", "jinja2", "cffi")         # what the description layer must not import
DESCRIPTION_ALLOWS = ("numpy", "tomli")       # its only packages beyond the standard library (tomli: Python 3.10)
LOCATORS = ("find_spec", "files", "import_module", "__import__")   # calls that reach a package by its name


def modules_of(packages) -> dict:
    """module name -> source path, for every .py file of the packages (a package by its __init__.py)."""
    found = {}
    for package in packages:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def _owner(name: str, modules) -> str:
    """The module a dotted name imports: the longest prefix that is one of ``modules`` ('' for none)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name


def imports(module: str, path: Path, modules) -> list:
    """Every import of ``path`` as (name, line): a module of ``modules`` when it is one, else the imported top
    package (numpy, sympy, ...).  Statements anywhere in the file, relative ones resolved; a module of a
    ``from X import a`` is X.a when that is a module, else X; a package named in a LOCATORS call counts too."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []

    def add(name, line):
        owner = _owner(name, modules)
        found.append((owner or name.split(".")[0], line))

    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            for alias in node.names:
                add(f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules else source, node.lineno)
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            function = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            target = node.args[0].value
            if function in LOCATORS and isinstance(target, str) and _owner(target, modules):
                add(target, node.lineno)
    return found


PRODUCT_MODULES = modules_of(PRODUCT)
STUDY_MODULES = modules_of(("studies",))


def where(module: str, line: int) -> str:
    return f"{PRODUCT_MODULES[module].relative_to(ROOT)}:{line}"


def test_every_product_module_has_a_layer():
    missing = sorted(set(PRODUCT_MODULES) - set(LAYERS))
    stale = sorted(set(LAYERS) - set(PRODUCT_MODULES))
    assert not missing, f"modules without a layer (add them to LAYERS in {Path(__file__).name}): {missing}"
    assert not stale, f"LAYERS names modules that do not exist: {stale}"


def test_imports_point_to_the_same_or_a_lower_layer():
    everything = {**PRODUCT_MODULES, **STUDY_MODULES}
    offenders = []
    for module, path in PRODUCT_MODULES.items():
        for target, line in imports(module, path, everything):
            if target in STUDY_MODULES or target == "tests" or target == "conftest":
                offenders.append(f"{where(module, line)}: {module} imports {target}, outside the product")
            elif target in LAYERS and target != module and LAYERS[target] > LAYERS[module]:
                offenders.append(f"{where(module, line)}: {module} ({LAYER_NAMES[LAYERS[module]]}) imports "
                                 f"{target} ({LAYER_NAMES[LAYERS[target]]}), a higher layer")
    assert offenders == [], "\n".join(offenders)


def test_another_layer_is_used_through_its_public_names():
    """A module takes from a module of another layer only names without a leading underscore."""
    offenders = []
    for module, path in PRODUCT_MODULES.items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if not isinstance(node, ast.ImportFrom):
                continue
            base = package.split(".")[:len(package.split(".")) - node.level + 1] if node.level else []
            source = _owner(".".join(base + ([node.module] if node.module else [])), PRODUCT_MODULES)
            private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
            if private and source in LAYERS and LAYERS[source] != LAYERS[module]:
                offenders.append(f"{where(module, node.lineno)}: {module} takes {', '.join(private)} from {source}")
    assert offenders == [], "\n".join(offenders)


def test_the_description_layer_is_numpy_only():
    offenders = []
    for module, path in PRODUCT_MODULES.items():
        if LAYERS.get(module) != DESCRIPTION:
            continue
        for target, line in imports(module, path, PRODUCT_MODULES):
            third_party = (target not in PRODUCT_MODULES and target not in sys.stdlib_module_names
                           and target != "__future__")
            if target in ALGEBRA or (third_party and target not in DESCRIPTION_ALLOWS):
                offenders.append(f"{where(module, line)}: {module} imports {target}")
    assert offenders == [], "\n".join(offenders)


def cycle_in(graph: dict) -> list:
    """One import circle of ``graph`` (module -> the modules it imports) as a list of modules, or []."""
    state, trail = {}, []

    def visit(module):
        state[module] = "open"
        trail.append(module)
        for other in sorted(graph.get(module, ())):
            if state.get(other) == "open":
                return trail[trail.index(other):] + [other]
            if other not in state:
                found = visit(other)
                if found:
                    return found
        trail.pop()
        state[module] = "done"
        return []

    for module in sorted(graph):
        if module not in state:
            found = visit(module)
            if found:
                return found
    return []


@pytest.mark.parametrize("packages", [PRODUCT, ("studies",)], ids=["product", "studies"])
def test_no_import_circle(packages):
    modules = {**PRODUCT_MODULES, **STUDY_MODULES}
    graph = {module: {target for target, _ in imports(module, path, modules) if target in modules} - {module}
             for module, path in modules_of(packages).items()}
    assert cycle_in(graph) == [], "import circle: " + " -> ".join(cycle_in(graph))


def test_the_checks_see_imports_inside_functions_and_type_checking(tmp_path):
    """What the checks above read: imports under ``if TYPE_CHECKING``, inside a function, a package located by
    name; and a circle through them."""
    path = tmp_path / "specialise.py"
    path.write_text("from typing import TYPE_CHECKING\n"
                    "if TYPE_CHECKING:\n    from .kernels import Kernel\n"
                    "def f():\n    from runtime.compile import compile_model\n"
                    "    return importlib.util.find_spec('runtime')\n")
    found = set(imports("codegen.specialise", path, PRODUCT_MODULES))
    assert {("typing", 1), ("codegen.kernels", 3), ("runtime.compile", 5), ("runtime", 6)} <= found
    assert cycle_in({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def test_loading_the_lower_layers_loads_nothing_above_them():
    """At run time too: importing every description module loads no sympy, jinja2 or cffi, and importing every
    module of the generator (description, derivation and emission) loads no module of runtime/."""
    lower = {layer: [m for m in sorted(LAYERS) if LAYERS[m] <= layer and not m.endswith("__main__")]
             for layer in (DESCRIPTION, DERIVATION)}
    code = ("import importlib, sys\n"
            "for name in sys.argv[1].split(','): importlib.import_module(name)\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in sys.argv[2].split(',')))")
    for layer, forbidden in ((DESCRIPTION, ALGEBRA), (DERIVATION, ("runtime",))):
        done = subprocess.run([sys.executable, "-c", code, ",".join(lower[layer]), ",".join(forbidden)],
                              capture_output=True, text=True, cwd=ROOT)
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == "[]", f"{LAYER_NAMES[layer]} layer loads {done.stdout.strip()}"
