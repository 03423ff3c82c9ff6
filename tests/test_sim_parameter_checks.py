"""One table of bad parameters, each driven through the three ways a run starts: Python (simulate's p override), C
(the compiled model's NAME_check_parameters and NAME_sim_init, the name and rule read from its C table
NAME_model.parameter_info) and the FMU (FMPy's simulate_fmu with start values).  Each must refuse it and name the
same parameter.  Also: the FMU's min and max, a parameter set out of order in the FMU, the C inertia test against
the scene loader's, and the return codes' table against gac.h."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from codegen.parameters import check_inertia
from codegen.scene import SceneError, scene_from_dict
from runtime import load_model, simulate
from runtime.header import PYTHON_FUNCTIONS, library_constants, library_functions, return_codes

ROOT = Path(__file__).resolve().parents[1]

# A chain with everything that has a rule: line and rigid links, four walls, friction on the floor, a joint with
# both stops.  Planar, so its specialised model has cz_2, Ixz_2 and Iyz_2 built in as 0.
SCENE = {
    "name": "checked_chain",
    "links": [
        {"length": 1.0, "mu": 1.0},
        {"length": 1.0, "mass": 1.2, "com": [0.5, 0.02, 0.0],
         "inertia": [[0.002, 0.001, 0.0], [0.001, 0.09, 0.0], [0.0, 0.0, 0.09]],
         "lower": -2.5, "upper": 2.5, "limit_restitution": 0.5},
        {"length": 0.8, "mu": 1.5},
    ],
    "walls": {"x1_min": -3.0, "x1_max": 3.0, "x2_min": -1.0, "x2_max": 3.0},
    "restitution": 0.8, "friction": {"x2_min": 0.4, "default": 0.0},
}

# (the parameters changed, the parameter every message must name)
CASES = [
    ({"e_x2_min": -0.5}, "e_x2_min"),               # negative restitution
    ({"e_x2_min": 1.5}, "e_x2_min"),                # e > 1
    ({"e_limit_2": 2.0}, "e_limit_2"),              # a stop's restitution > 1
    ({"m_2": -1.0}, "m_2"),                         # negative mass
    ({"mu_1": 0.0}, "mu_1"),                        # zero mass per unit length
    ({"l_3": 0.0}, "l_3"),                          # zero length
    ({"Jyy_1": -1e-3}, "Jyy_1"),                    # negative moment of inertia
    ({"Izz_2": 0.5}, "Ixx_2"),                      # 0.002 + 0.09 < 0.5: no real mass distribution
    ({"lower_2": 3.0}, "upper_2"),                  # stop lower > upper
    ({"wall_x1_min": 5.0}, "wall_x1_max"),          # wall min > max
    ({"friction_x2_min": -0.1}, "friction_x2_min"),  # negative friction
    ({"g": 1e7}, "g"),                              # beyond 1e6 m/s^2
    ({"e_x2_max": 1e-310}, "e_x2_max"),             # nonzero below the smallest normal double
    ({"cz_2": 0.1}, "cz_2"),                        # built into the specialised model as 0
]
IDS = [next(iter(changed)) + "=" + repr(next(iter(changed.values()))) for changed, _ in CASES]


@pytest.fixture(scope="module")
def scene():
    return scene_from_dict(SCENE)


@pytest.fixture(scope="module")
def model(scene):
    return load_model(scene)


@pytest.fixture(scope="module")
def fmu(scene, tmp_path_factory):
    """The scene's FMU, built once, and its folder unzipped once."""
    pytest.importorskip("fmpy", reason="FMPy is not installed: pip install -e '.[fmi]' to run the FMU tests")
    from fmpy import extract
    from runtime.fmu import build_fmu
    path = build_fmu(scene, tmp_path_factory.mktemp("fmu"), stop_time=0.05, step_size=0.01)
    return path, extract(str(path))


def fmu_messages(fmu, start_values: dict, capsys) -> tuple[bool, str]:
    """Run the FMU through FMPy with these start values: whether it ran, and what it logged (FMPy's default logger
    prints the FMU's messages; a logger of one's own would stay behind in FMPy's native logging proxy after the
    run and be called, freed, by the next FMU)."""
    from fmpy import simulate_fmu
    capsys.readouterr()
    try:
        simulate_fmu(fmu[1], start_values=start_values, stop_time=0.05, output_interval=0.01, validate=False)
        ran = True
    except Exception:                                 # FMPy raises on the fmi2Error the FMU returned
        ran = False
    return ran, capsys.readouterr().out


@pytest.mark.parametrize("changed,field", CASES, ids=IDS)
def test_python_c_and_fmu_name_the_same_parameter(model, fmu, changed, field, capsys):
    p = model.parameters(changed)
    with pytest.raises(ValueError) as python:
        simulate(model, 0.05, p=changed)
    assert re.match(rf"p\[{field}[\] ]", str(python.value)), str(python.value)     # "p[Ixx_2 .. Iyz_2]" for a group

    in_c = model.parameter_problem(p)                 # NAME_check_parameters, and the name from the C table
    assert in_c.startswith(f"p[{field}]: "), in_c
    sim = model.c.new("sim")
    code = model.c.sim_init(sim, 0.0, model._ptr(model.q0), model._ptr(model.qd0), model._ptr(p), model.ffi.NULL)
    assert code == model.lib.GAC_ERR_BAD_PARAMETER

    ran, log = fmu_messages(fmu, {f"p.{name}": value for name, value in changed.items()}, capsys)
    assert not ran
    assert f"p.{field} = " in log, log


def test_good_parameters_pass_everywhere(model, fmu, capsys):
    """The same three routes accept changes within the rules (both walls moved, limits narrowed)."""
    changed = {"e_x2_min": 0.0, "m_2": 2.0, "friction_x2_min": 0.0, "lower_2": -2.2, "upper_2": 2.2,
               "wall_x1_min": -3.5, "wall_x1_max": 2.5}
    assert simulate(model, 0.05, p=changed, t_eval=[]).success
    assert model.parameter_problem(model.parameters(changed)) == ""
    ran, log = fmu_messages(fmu, {f"p.{name}": value for name, value in changed.items()}, capsys)
    assert ran, log


def test_c_messages_say_the_rule(model):
    """The C table's words for a range and for each kind of relation."""
    assert model.parameter_problem(model.parameters({"e_x2_min": -0.5})) == \
        "p[e_x2_min]: restitution must be in [0, 1], got -0.5"
    assert model.parameter_problem(model.parameters({"lower_2": 3.0})) == \
        "p[upper_2]: must be within [-1e+09, 1e+09] rad, and > lower_2, got 2.5"
    assert "Ixx_2 .. Iyz_2 together a physical inertia" in model.parameter_problem(model.parameters({"Izz_2": 0.5}))
    assert "built into this model as 0" in model.parameter_problem(model.parameters({"cz_2": 0.1}))
    assert model.parameter_problem(model.parameters({"e_x2_max": 1e-310})) == \
        "p[e_x2_max]: restitution must be in [0, 1], got 1e-310 (nonzero below the smallest normal double: give 0 " \
        "or a larger magnitude)"


def test_fmu_declares_each_parameter_range(fmu):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(fmu[0])) == []
    variables = {v.name: v for v in read_model_description(str(fmu[0])).modelVariables}
    expected = {"p.e_x2_min": ("0.0", "1.0"), "p.e_limit_2": ("0.0", "1.0"), "p.l_1": ("1e-09", "1000000000.0"),
                "p.m_2": ("1e-12", "1000000000000.0"), "p.friction_x2_min": ("0.0", "1000.0"),
                "p.g": ("-1000000.0", "1000000.0"), "p.cz_2": ("0.0", "0.0"), "p.Ixy_2": ("-1e+100", "1e+100"),
                "p.upper_2": ("-1000000000.0", "1000000000.0"), "solver.dt": ("0", None)}
    for name, (low, high) in expected.items():
        assert (variables[name].min, variables[name].max) == (low, high), name
    for v in variables.values():
        if v.name.startswith("p."):
            assert float(v.min) <= float(v.start) <= float(v.max), v.name


def test_fmu_parameters_set_in_any_order(fmu, capsys):
    """fmi2SetReal checks each value's own range, so a pair may pass through min > max on the way (the walls moved
    past each other); fmi2ExitInitializationMode checks the relations.  A value out of its range is refused at
    once, with its variable and rule."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(fmu[0]))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=fmu[1], modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="order")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([refs["p.wall_x1_min"]], [3.5])     # above x1_max = 3 for now
    slave.setReal([refs["p.wall_x1_max"], refs["q0.X1"]], [10.0, 5.0])
    slave.exitInitializationMode()
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    slave.terminate()
    slave.freeInstance()

    ran, log = fmu_messages(fmu, {"p.e_x2_min": -0.5}, capsys)
    assert not ran and "fmi2SetReal: value reference " in log
    assert "p.e_x2_min = -0.5: restitution must be in [0, 1]" in log, log
    ran, log = fmu_messages(fmu, {"p.wall_x1_min": 5.0}, capsys)
    assert not ran and "fmi2ExitInitializationMode: the simulation cannot start: p.wall_x1_max = 3: " in log
    assert "and > wall_x1_min" in log, log
    ran, log = fmu_messages(fmu, {"p.e_x2_max": 1e-310}, capsys)
    assert not ran
    assert "p.e_x2_max = 1e-310: restitution must be in [0, 1] (nonzero below the smallest normal double" in log, log


def rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_c_inertia_test_agrees_with_the_scene_loader(model):
    """gac_inertia_admissible (Jacobi rotations) and the loader's test (LAPACK's eigenvalues) on turned inertias whose
    principal moments break or keep the triangle inequality or positivity by 1e-9 or 1e-14 of the largest: the same
    answer every time, and the one the construction says."""
    rng = np.random.default_rng(3)
    admissible = model.lib.gac_inertia_admissible
    for trial in range(600):
        scale = 10.0 ** rng.uniform(0, 6)             # >= 1: the tolerance is 1e-12 of the largest moment
        a, b = rng.uniform(0.05, 1.0, size=2)
        margin = [-1e-9, -1e-14, 1e-14, 1e-9][trial % 4]
        moments = scale * (np.array([a, b, a + b - margin]) if trial % 8 < 4 else np.array([margin, a, a]))
        expected = margin != -1e-9                      # 1e-14 of the largest is within the tolerance
        Q = rotation(rng)
        inertia = Q @ np.diag(moments) @ Q.T
        inertia = (inertia + inertia.T) / 2
        six = np.array([inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]])
        try:
            check_inertia(six, 1)
            python = True
        except SceneError:
            python = False
        c = bool(admissible(model.ffi.cast("double *", model.ffi.from_buffer(six))))
        assert c == python == expected, (trial, moments, c, python)


def _struct_fields(body: str) -> list[str]:
    """The field names of a C struct body: the declarators of each declaration, comments dropped."""
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    names = []
    for declaration in filter(str.strip, body.split(";")):
        if "(" in declaration:                                      # a function pointer: (*name)(...)
            names.append(re.search(r"\(\s*\*\s*(\w+)\s*\)", declaration).group(1))
            continue
        first, *rest = declaration.split(",")
        for declarator in [first.split()[-1], *rest]:
            names.append(re.sub(r"[\s*]|\[.*?\]", "", declarator))
    return names


def test_cffi_declarations_are_gac_h(model):
    """gac.h is the library's one description: its parse (runtime.header) finds every return code gac.h defines,
    the compiled module holds each constant with gac.h's value, and cffi's types and functions are gac.h's (every
    struct complete, with gac.h's fields in order: cffi checks their layout against the compiler's).  Of its functions
    cffi wraps the checks and sizes Python calls."""
    header = (ROOT / "runtime" / "c" / "gac.h").read_text()
    constants = library_constants()
    errors = set(re.findall(r"^#define (GAC_ERR_\w+)\s", header, flags=re.M))
    assert len(errors) > 20 and set(return_codes()) == errors | {"GAC_OK"}
    assert "GAC_ERR_BAD_PARAMETER" in return_codes() and constants["GAC_RTOL_MIN"] == 1e-14
    for name, value in constants.items():
        assert getattr(model.lib, name) == value, name
    assert len(set(return_codes().values())) == len(return_codes())
    structs = {name: body for body, name in re.findall(r"typedef struct \{(.*?)\} (gac_\w+);", header, flags=re.S)}
    structs["gac_model"] = re.search(r"struct gac_model \{(.*?)\};", header, flags=re.S).group(1)
    assert {"gac_options", "gac_impact_record", "gac_contact", "gac_run_summary", "gac_parameter_info",
            "gac_sim", "gac_model"} <= set(structs)
    for name, body in structs.items():
        fields = [field for field, _ in model.ffi.typeof(f"{name} *").item.fields]
        assert fields == _struct_fields(body), name
        assert model.ffi.sizeof(name) > 0
    functions = set(re.findall(r"^[a-z][\w ]*?\**\s*\b(gac_\w+)\(", header, flags=re.M))
    assert "gac_sim_ndouble" in functions and "gac_sim_run" in functions
    assert set(library_functions()) == functions
    # the module wraps the functions Python calls (lib.gac_* in the runtime and the tests), and no others
    called = {name for folder in ("runtime", "tests") for path in (ROOT / folder).glob("*.py")
              for name in re.findall(r"\blib\.(gac_\w+)", path.read_text())}
    assert "gac_check_options" in called and called <= set(PYTHON_FUNCTIONS) <= functions
    assert all(hasattr(model.lib, f) for f in PYTHON_FUNCTIONS)
    assert not any(hasattr(model.lib, f) for f in functions - set(PYTHON_FUNCTIONS))


def test_scene_loader_refuses_a_negative_moment():
    """The loader holds a rigid link's moments to the range p[Ixx_i] has (>= 0), so a scene it takes passes the C
    check as it stands."""
    data = {**SCENE, "links": [dict(SCENE["links"][0]), {**SCENE["links"][1], "inertia": [
        [-1e-14, 0.0, 0.0], [0.0, 0.09, 0.0], [0.0, 0.0, 0.09]]}, dict(SCENE["links"][2])]}
    with pytest.raises(SceneError, match=re.escape("links[2].inertia[0][0]: must be >= 0")):
        scene_from_dict(data)
