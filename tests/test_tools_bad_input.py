"""Bad input, table by table: every malformed scene file, command-line argument and simulate() argument is
answered with a specific message (the field, the allowed range) and a non-zero exit, never a traceback,
a silent NaN or a silently ignored value; good input next to each bad one still works.

(The C API's arguments are in test_build_c_api.py, the build cache's corruptions in test_build_cache.py, the codegen
command's output folder in test_tools_codegen_cli.py.)
"""
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import MAX_LINKS, LineLink, RigidLink, Scene, SceneError, Wall, load_scene
from runtime import cli as runtime_cli
from runtime.simulate import simulate

ROOT = Path(__file__).resolve().parent.parent

ROD = '[[links]]\nlength = 1.0\nmu = 1.0\n'
WALLS = '[walls]\nx2_min = -2.0\n'


# ---------------------------------------------------------------------------
# scene files
# ---------------------------------------------------------------------------
SCENE_FILES = [
    # (file name, content, the message must contain)
    ("garbage.toml", b"\xff\xfe\x00garbage", "is not UTF-8 text"),
    ("garbage.json", b"\x89PNG\r\n\x1a\n", "is not UTF-8 text"),
    ("dup.json", b'{"name": "a", "links": [{"length": 1, "mu": 1}], "name": "b"}', "key 'name' is given twice"),
    ("dupnested.json", b'{"links": [{"length": 1, "length": 2, "mu": 1}]}', "key 'length' is given twice"),
    ("dup.toml", (ROD + "length = 2.0\n").encode(), "line 4: links.length is given twice"),
    ("dupwall.toml", (ROD + WALLS + "x2_min = 1.0\n").encode(), "walls.x2_min is given twice"),
    ("duptop.toml", ("gravity = 1.0\ngravity = 2.0\n" + ROD).encode(), "line 2: gravity is given twice"),
    ("bad.toml", b"links = [[[", "cannot parse"),
    ("bad.json", b'{"links": ', "cannot parse"),
    ("many.toml", (ROD + "count = 10000\n").encode(), f"at most {MAX_LINKS} links"),
    ("many.json", json.dumps({"links": [{"length": 1, "mu": 1}] * (MAX_LINKS + 1)}).encode(),
     f"got n = {MAX_LINKS + 1}"),
    ("subnormal.toml", b"[[links]]\nlength = 1e-320\nmu = 1.0\n", "links[1].length: must be in [1e-09, 1e+09] m"),
    ("long.toml", b"[[links]]\nlength = 1e10\nmu = 1.0\n", "links[1].length: must be in [1e-09, 1e+09] m"),
    ("mu0.toml", b"[[links]]\nlength = 1.0\nmu = 0.0\n", "links[1].mu: must be in [1e-12, 1e+12] kg/m"),
    ("mass.toml", b"[[links]]\nlength = 1.0\nmass = -1.0\ncom = [0.5, 0, 0]\ninertia = [[1,0,0],[0,1,0],[0,0,1]]\n",
     "links[1].mass: must be in [1e-12, 1e+12] kg"),
    ("negJ.toml", b"[[links]]\nlength = 1.0\nmu = 1.0\nJ = [-1e-3, 1e-3, 1e-3]\n", "links[1].J (Jxx): must be >= 0"),
    ("tinyJ.toml", b"[[links]]\nlength = 1.0\nmu = 1.0\nJ = [1e-320, 1e-3, 1e-3]\n",
     "below the smallest normal double"),
    ("inertia.toml", b"[[links]]\nlength = 1.0\nmass = 1.0\ncom = [0.5, 0, 0]\ninertia = [[1,0,0],[0,1,0],[0,0,5]]\n",
     "violate the triangle inequality"),
    ("gravity.toml", ("gravity = 1e7\n" + ROD).encode(), "gravity: must be within [-1e6, 1e6] m/s^2"),
    ("nanwall.toml", (ROD + "[walls]\nx2_min = nan\n").encode(), "walls.x2_min: must be a finite number"),
    ("farwall.toml", (ROD + "[walls]\nx2_min = -1e12\n").encode(), "walls.x2_min: must be within [-1e+09, 1e+09]"),
    ("restitution.toml", ("restitution = 1.5\n" + ROD + WALLS).encode(), "restitution: must be in [0, 1]"),
    ("unknown.toml", (ROD + "stiffnes = 3\n").encode(), "unknown key 'stiffnes'"),
    ("spring-on-base.toml", (ROD + "stiffness = 3\n").encode(), "links[1].stiffness: theta_1 orients the base"),
    ("outside.toml", (ROD + "[walls]\nx2_min = 0.5\n").encode(), "outside the wall x2_min"),
    ("state.toml", (ROD + "[initial]\nq = [0, 0, 0, 0, 0]\n").encode(), "initial.q: expected a list of 6 numbers"),
]


@pytest.mark.parametrize("filename,content,message", SCENE_FILES, ids=[f[0] for f in SCENE_FILES])
def test_bad_scene_file_is_named_by_the_loader_and_the_command(tmp_path, capsys, filename, content, message):
    path = tmp_path / filename
    path.write_bytes(content)
    with pytest.raises(SceneError) as error:
        load_scene(path)
    assert message in str(error.value)
    code = runtime_cli.main(["simulate", "--scene", str(path), "--json", str(tmp_path / "out.json")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not (tmp_path / "out.json").exists()


@pytest.mark.parametrize("source,message", [
    (42, "expected a shipped scene name or a path"),
    (None, "expected a shipped scene name or a path"),
    ("no-such-scene", "no shipped scene of that name"),
    ("../paper-case1", "no shipped scene of that name"),
    (ROOT / "tests", "is a directory"),
])
def test_bad_scene_source(source, message):
    with pytest.raises(SceneError, match=re.escape(message)):
        load_scene(source)


def test_the_link_cap_is_the_same_for_scenes_and_the_built_in_chains():
    assert load_scene("paper-case1").n == 4                      # good input still loads
    Scene(name="longest", links=tuple(LineLink(1.0, 1.0) for _ in range(MAX_LINKS)))
    with pytest.raises(SceneError, match=f"at most {MAX_LINKS} links: generating and compiling"):
        Scene(name="too_long", links=tuple(LineLink(1.0, 1.0) for _ in range(MAX_LINKS + 1)))


# ---------------------------------------------------------------------------
# python -m runtime simulate: checked before the model is built, nothing written
# ---------------------------------------------------------------------------
CLI_CASES = [
    (["--t-end", "inf"], "--t-end: must be a finite time >= 0 s, got inf"),
    (["--t-end", "nan"], "--t-end: must be a finite time >= 0 s, got nan"),
    (["--t-end", "-1"], "--t-end: must be a finite time >= 0 s"),
    (["--samples-dt", "1e-18"], "asks for 1.5e+18 samples; at most 10,000,000"),
    (["--samples-dt", "0"], "--samples-dt: must be a finite spacing > 0 s"),
    (["--samples-dt", "inf"], "--samples-dt: must be a finite spacing > 0 s"),
    (["--rtol", "0"], "--rtol: must be a tolerance in [1e-14, 1)"),
    (["--rtol", "1e-300"], "--rtol: must be a tolerance in [1e-14, 1)"),
    (["--max-impacts", "0"], "--max-impacts: must be an integer >= 1"),
    (["--max-steps", "-1"], "--max-steps: must be an integer >= 0"),
    (["--atol=-1e-12"], "--atol: must be a finite tolerance > 0"),
    (["--method", "rk4"], "--dt: rk4 needs a step"),
    (["--method", "rk4", "--dt", "0"], "--dt: must be a finite step > 0 s"),
    (["--max-wall-time", "0"], "--max-wall-time: must be a finite time > 0 s"),
    (["--charts", "--no-charts"], "give at most one"),
    (["--json", "{tmp}/missing/out.json"], "does not exist (create it first)"),
    (["--json", "{tmp}"], "is a directory; give a file name"),
    (["--json", "{tmp}/file.txt/out.json"], "is a file, not a directory"),
    (["--plot", "{tmp}/file.txt/plots"], "is a file, not a directory"),
    (["--plot", "{tmp}/file.txt"], "exists and is not a directory"),
    (["--scene", "no-such-scene"], "no shipped scene of that name"),
]


@pytest.mark.parametrize("args,message", CLI_CASES, ids=[" ".join(a) for a, _ in CLI_CASES])
def test_bad_simulate_argument_is_refused_before_any_work(tmp_path, capsys, monkeypatch, args, message):
    import runtime.cli
    monkeypatch.setattr(runtime.cli, "load_model", lambda *a, **k: pytest.fail("the model was built"))
    (tmp_path / "file.txt").write_text("a file")
    before = sorted(tmp_path.rglob("*"))
    code = runtime_cli.main(["simulate", *[a.format(tmp=tmp_path) for a in args]])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert sorted(tmp_path.rglob("*")) == before


def test_good_simulate_arguments_still_run(tmp_path, capsys):
    out = tmp_path / "new.json"
    code = runtime_cli.main(["simulate", "--scene", "paper-case2", "--t-end", "0.3", "--json", str(out)])
    assert code == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["t_final"] == 0.3


# ---------------------------------------------------------------------------
# simulate() from Python
# ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def case1(compiled):
    return compiled(load_scene("paper-case1"), specialise=True)


def _p(model, **values):
    p = model.p.copy()
    names = model.scene.parameter_names()
    for name, value in values.items():
        p[names.index(name)] = value
    return p


API_CASES = [
    # (keyword arguments (callables get the model), message)
    ({"t_end": math.inf}, "t_end: must be a finite time >= 0 s"),
    ({"t_end": "1"}, "t_end: expected a number, got '1' (str)"),
    ({"rtol": -1.0}, "rtol: must be within [1e-14, 1)"),
    ({"rtol": 1e-300}, "rtol: must be within [1e-14, 1)"),
    ({"rtol": 1.0}, "rtol: must be within [1e-14, 1)"),
    ({"atol": 0.0}, "atol: must be within (0, 1e300)"),
    ({"method": "euler"}, "method: must be one of"),
    ({"max_steps": -1}, "max_steps: must be >= 0 (0: unbounded), got -1"),
    ({"max_steps": 2.5}, "max_steps: must be an integer"),
    ({"max_steps": "many"}, "max_steps: must be an integer"),
    ({"max_impacts": -3}, "max_impacts: must be >= 0 (0: unbounded), got -3"),
    ({"max_impacts": 1.5}, "max_impacts: must be an integer"),
    ({"event_samples": 0}, "event_samples: must be >= 1"),
    ({"zeno_impacts": -1}, "zeno_impacts: must be >= 0"),
    ({"contact_tol": math.nan}, "contact_tol: must be within [0, 1e300) m"),
    ({"max_wall_time": -1.0}, "max_wall_time: must be within [0, 1e300) s (0: unbounded)"),
    ({"rtl": 1e-6}, "rtl: no such option of simulate(); the loop's options are rtol, atol"),
    ({"p": lambda m: m.p[:-1]}, "p: expected"),
    ({"p": lambda m: ["a"] * len(m.p)}, "p: expected"),
    ({"p": lambda m: _p(m, Jxx_1=-1e-3)}, "p[Jxx_1]: must be >= 0"),
    ({"p": lambda m: _p(m, Jzz_2=-5.0)}, "p[Jzz_2]: must be >= 0"),
    ({"p": lambda m: _p(m, mu_3=0.0)}, "p[mu_3]: must be in [1e-12, 1e+12] kg/m"),
    ({"p": lambda m: _p(m, l_1=1e-320)}, "p[l_1]: must be in [1e-09, 1e+09] m"),
    ({"p": lambda m: _p(m, e_x2_min=1.5)}, "p[e_x2_min]: restitution must be in [0, 1]"),
    ({"p": lambda m: _p(m, g=1e7)}, "p[g]: must be within [-1e6, 1e6] m/s^2"),
    ({"p": lambda m: _p(m, wall_x1_max=-1.0)}, "p[wall_x1_max]: must be > p[wall_x1_min]"),
    ({"p": lambda m: _p(m, wall_x2_min=0.5)}, "outside the wall x2_min"),
]


@pytest.mark.parametrize("kwargs,message", API_CASES, ids=[str(i) for i in range(len(API_CASES))])
def test_bad_simulate_call_names_the_argument(case1, kwargs, message):
    kwargs = {key: value(case1) if callable(value) else value for key, value in kwargs.items()}
    kwargs.setdefault("t_end", 0.1)
    with pytest.raises(ValueError) as error:
        simulate(case1, **kwargs)
    assert message in str(error.value)


def test_good_parameter_override_is_honoured(case1):
    base = simulate(case1, 0.3, t_eval=[])
    heavier = simulate(case1, 0.3, t_eval=[], p=_p(case1, g=5.0))
    assert base.success and heavier.success
    assert abs(heavier.q_final[-2] - base.q_final[-2]) > 1e-3      # the override changed the fall


def test_rigid_link_inertia_override_must_be_physical(compiled):
    body = RigidLink(1.0, 1.0, (0.5, 0.0, 0.0), ((0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1)))
    rigid = Scene(name="rigid_body", links=(body,), walls=(Wall("x2_min", -2.0),))
    model = compiled(rigid)
    with pytest.raises(ValueError, match=re.escape("p[Ixx_1 .. Iyz_1]: the inertia of link 1")):
        simulate(model, 0.1, p=_p(model, Izz_1=0.5))                 # 0.1 + 0.1 < 0.5
    assert simulate(model, 0.1, p=_p(model, Izz_1=0.15), t_eval=[]).success


def test_a_parameter_built_in_as_zero_cannot_be_overridden_silently(compiled):
    weightless = Scene(name="weightless_rod", links=(LineLink(1.0, 1.0),), walls=(Wall("x2_min", -5.0),),
                       gravity=0.0, q0=(0.0, 0.0, 0.3, 0.0, 0.0, 0.0), qd0=(0.0, 0.0, 1.0, 0.0, 0.0, 0.0))
    specialised = compiled(weightless, specialise=True)
    assert "g" in specialised.layout.zero_params
    with pytest.raises(ValueError) as error:
        simulate(specialised, 0.5, p=_p(specialised, g=9.81))
    assert "p[g]: this model has g = 0 built in" in str(error.value)
    assert "specialise=False" in str(error.value)
    general = compiled(weightless, specialise=False)          # the remedy the message names: g is honoured
    falling = simulate(general, 0.5, p=_p(general, g=9.81), t_eval=[])
    assert falling.q_final[-2] < -1.0                          # X2 fell by about g t^2 / 2 = 1.23 m


def test_baked_parameters_cannot_be_overridden_silently(compiled):
    baked = compiled(load_scene("paper-case1"), bake_params=True, specialise=True)
    with pytest.raises(ValueError, match=re.escape("p[g]: this model has every parameter built in as a constant")):
        simulate(baked, 0.1, p=_p(baked, g=5.0))
    assert simulate(baked, 0.1, p=baked.p.copy(), t_eval=[]).success       # its own values are fine


def test_max_impacts_stop_names_the_limit_the_caller_set(case1):
    result = simulate(case1, 1.5, max_impacts=2, t_eval=[])
    assert result.status == -1 and len(result.impacts) == 2
    assert "max_impacts limit of 2" in result.message and "Zeno" not in result.message


# ---------------------------------------------------------------------------
# energy accounting: E0, E(t_end), losses at impacts, residual over a scale that does not vanish
# ---------------------------------------------------------------------------
def _independent_balance(model, result):
    """The residual from the model's energy kernel at the start and end states and the impact records."""
    layout = model.layout
    E0 = sum(model.energy(layout.reduce(result.q[0]), layout.reduce(result.qd[0])))
    E1 = sum(model.energy(layout.reduce(result.q_final), layout.reduce(result.qd_final, )))
    lost = sum(sum(model.energy(layout.reduce(i.q), layout.reduce(i.qd_before)))
               - sum(model.energy(layout.reduce(i.q), layout.reduce(i.qd_after))) for i in result.impacts)
    return E0, E1, lost


def test_energy_lost_at_impacts_is_not_drift(compiled, tmp_path, capsys):
    scene = load_scene("paper-case1")
    lossy = Scene(name="case1_e08", links=scene.links, walls=tuple(Wall(w.name, w.position, 0.8) for w in scene.walls),
                  gravity=scene.gravity, q0=scene.q0, qd0=scene.qd0)
    model = compiled(lossy, specialise=True)
    result = simulate(model, 1.5, rtol=1e-10, atol=1e-12)
    E0, E1, lost = _independent_balance(model, result)
    assert result.success and len(result.impacts) >= 3
    assert lost > 0.05 * abs(E0)                                    # the impacts took a lot ...
    assert result.loss_impacts == pytest.approx(lost, rel=1e-9)
    assert result.energy_residual == pytest.approx(E1 - E0 + lost, abs=1e-9 * result.energy_scale)
    assert abs(result.energy_drift) < 1e-7                          # ... and none of it is drift
    assert abs((E1 - E0) / abs(E0)) > 0.05                          # (the old E_final / E0 - 1 was not)


def test_energy_drift_of_a_chain_at_rest_is_measured_on_its_weight(compiled):
    model = compiled(load_scene("stress-rest"), specialise=True)
    result = simulate(model, 0.5)
    assert result.success
    weight = 3.0 * 9.81 * 3.0                                        # M g L of three 1 kg, 1 m links
    assert result.energy_scale == pytest.approx(weight, rel=1e-12)
    assert abs(result.energy_drift) < 1e-9


def test_energy_figures_agree_in_result_json_and_cli(tmp_path, capsys):
    out = tmp_path / "case2.json"
    assert runtime_cli.main(["simulate", "--scene", "paper-case2", "--t-end", "0.5", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    data = json.loads(out.read_text())
    result = simulate("paper-case2", 0.5, t_eval=np.arange(0.0, 0.5, 1e-3).tolist() + [0.5])
    for key in ("energy_initial", "energy_final", "loss_impacts", "energy_residual", "energy_scale",
                "energy_drift"):
        assert data[key] == pytest.approx(getattr(result, key), rel=1e-12, abs=1e-300)
    assert f"balance residual {data['energy_residual']:.3e} J = {data['energy_drift']:.3e}" in printed
    assert f"lost at impacts {data['loss_impacts']:.6g} J" in printed


# ---------------------------------------------------------------------------
# study commands name their extra; the project speaks for itself
# ---------------------------------------------------------------------------
def test_precision_without_scipy_names_the_extra_before_any_work(monkeypatch, capsys, tmp_path):
    import importlib.util
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "scipy" else real(name, *a))
    from studies import cli as studies_cli
    code = studies_cli.main(["precision", "--scene", "paper-case1", "--quick", "--out", str(tmp_path / "p")])
    err = capsys.readouterr().err
    assert code == 2 and "needs scipy" in err and '.[study]' in err
    assert not (tmp_path / "p").exists()


def test_no_text_speaks_of_how_the_project_was_made():
    pattern = re.compile(r"\bissue \d|issue author|the issue asks|as we recall|could not be consulted", re.I)
    offenders = []
    environments = {p.parent.name for p in ROOT.glob("*/pyvenv.cfg")}   # a virtual environment, whatever its name
    for path in ROOT.rglob("*"):
        parts = path.relative_to(ROOT).parts
        if any(part in (".git", ".venv", "build", "__pycache__", "site-packages") or part.endswith(".egg-info")
               for part in parts) or (parts and parts[0] in environments):
            continue
        if path.suffix in (".py", ".md", ".j2", ".toml", ".c", ".h", ".txt") and path.is_file():
            offenders += [f"{path.relative_to(ROOT)}: {line.strip()}" for line in
                          path.read_text(errors="replace").splitlines() if pattern.search(line)]
    offenders = [o for o in offenders if not o.startswith("tests/test_tools_bad_input.py")]
    assert offenders == []
