"""Warnings that point at their cause: values that suggest a slip of units, the ratio that makes I_f
ill-conditioned, and steps held back by the friction regularisation.  Each is a sentence in result.warnings and
a 'warning:' line of the command, never an error."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

from codegen.scene import LineLink, Scene, default_scene, load_scene, scene_from_dict
from runtime import simulate
from studies.reference import reference_of
from conftest import quick_model

ROOT = Path(__file__).resolve().parent.parent


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "runtime", *args], capture_output=True, text=True, cwd=ROOT)


# ---------------------------------------------------------------------------------------------------------------
# units
# ---------------------------------------------------------------------------------------------------------------
def test_lengths_masses_and_angles_that_suggest_other_units_are_named():
    """A 500 m link, a 50 t link and angles of 45, 90 and 180 'rad' load (they are not errors) and give one warning
    per kind, naming the first field, how many more there are, and the expected range."""
    scene = scene_from_dict({
        "name": "units", "links": [{"length": 500.0, "mu": 1.0},
                                   {"length": 0.5, "mu": 1e5, "stiffness": 10.0, "rest_angle": 90.0,
                                    "lower": -180.0, "upper": 180.0}],
        "initial": {"q": [-math.pi / 2, 0.0, 45.0, 0.5, 0.0, 0.0, 0.0]}})
    assert scene.warnings == [
        "links[1].length = 500 m: outside 0.0001 ... 100 m, unusual for a link; lengths are in m, not mm or km",
        "links[2].mu = 100000 kg/m (a mass of 50000 kg): outside 1e-06 ... 10000 kg, unusual for a link; masses are "
        "in kg and mu in kg/m, not g or t",
        "links[2].rest_angle = 90 rad (and 3 more): beyond 2 pi in magnitude; angles are in radians (90 degrees is "
        "1.5708 rad)"]
    edge = scene_from_dict({"name": "edge", "links": [{"length": 100.0, "mu": 100.0}, {"length": 1e-4, "mu": 0.01}],
                            "initial": {"q": [-math.pi / 2, 0.0, 2 * math.pi, -2 * math.pi, 0.0, 0.0, 0.0]}})
    assert edge.warnings == []                              # the ranges' ends are accepted quietly
    for name in ("paper-case1", "paper-case2", "driven-fold", "rough-floor", "urdf-arm", "gimbal-lock", "incline"):
        assert load_scene(name).warnings == [], name


def test_a_scene_in_other_units_runs_with_its_warning_in_the_result_and_on_the_command_line(tmp_path):
    """paper-case1 with mu = 2e4 kg/m (grams taken for kilograms): the run goes ahead; result.warnings starts with
    the scene's warning and the command prints it once, on loading."""
    text = (ROOT / "codegen" / "scenes" / "paper-case1.toml").read_text()
    assert text.count("mu = 1.0") == 1
    path = tmp_path / "heavy.toml"
    path.write_text(text.replace("mu = 1.0", "mu = 2e4"))
    scene = load_scene(path)
    expected = ("links[1].mu = 20000 kg/m (a mass of 20000 kg) (and 3 more): outside 1e-06 ... 10000 kg, unusual "
                "for a link; masses are in kg and mu in kg/m, not g or t")
    assert scene.warnings == [expected]
    result = simulate(quick_model(scene), 0.3)
    assert result.success and result.warnings == [expected]
    done = run_cli("simulate", "--scene", str(path), "--t-end", "0.3")
    assert done.returncode == 0, done.stderr
    assert done.stderr.count(f"warning: {expected}\n") == 1


# ---------------------------------------------------------------------------------------------------------------
# ill-conditioned impacts
# ---------------------------------------------------------------------------------------------------------------
def test_an_impact_of_limited_accuracy_names_the_mass_ratio():
    """A 1e4 kg link at rest, without gravity, and a 2e-5 kg link spinning at 20 rad/s that strikes the floor: I_f's
    condition is about the mass ratio 5e8.  The impacts' law is refined to round-off (measured accuracy 1e-10, no
    warning); were an impact's measured accuracy poor, its warning would name the mass ratio: the same impacts,
    their records given a poor accuracy, are named by it (impact_warnings, as simulate builds result.warnings)."""
    import dataclasses

    from runtime.simulate import ROUNDOFF_WARN, impact_warnings
    scene = scene_from_dict({
        "name": "mass_ratio", "gravity": 0.0, "restitution": 1.0,
        "links": [{"length": 1.0, "mu": 1e4, "J": [0.589, 0.294, 0.294]},
                  {"length": 2.0, "mu": 1e-5, "J": [5.89e-10, 2.94e-10, 2.94e-10]}],
        "walls": {"x1_min": 0.0, "x1_max": 6.0, "x2_min": 0.0, "x2_max": 6.0},
        "initial": {"q": [-math.pi / 2, 0.0, 0.0, 0.5, 3.0, 0.7, 0.0], "qd": [0.0, 0.0, 0.0, 20.0, 0.0, 0.0, 0.0]}})
    assert scene.warnings == []
    model = quick_model(scene)
    result = simulate(model, 0.5)
    assert result.success and len(result.impacts) >= 2
    assert len(result.warnings) == sum(i.roundoff > ROUNDOFF_WARN for i in result.impacts)
    poor = [dataclasses.replace(i, roundoff=1e-4) for i in result.impacts]
    warnings = impact_warnings(poor, model, model.parameters())
    assert len(warnings) == len(poor)
    for impact, warning in zip(poor, warnings):
        assert warning.startswith(f"impact at t = {impact.t:.9g} s: its energy is accurate only to 0.0001 "
                                  "(relative): "), warning
        assert warning.endswith("its most extreme ratio is that of the links' masses: 1e+04 kg (link 1) is 5e+08 "
                                "times 2e-05 kg (link 2)"), warning


def test_the_named_ratio_is_the_largest_of_masses_lengths_moments_and_the_chain_length():
    """Identical slender links: at n = 256 the chain's length (M L^2 / 3 against a link's 1/12 + Jyy kg m^2: about
    6.7e7) outweighs the links' axial to transverse moments (about 1.4e3); a single slender link in 3D has only
    the latter (paper case 2: 353); a chain of 1e-6 m and 1 m links names its lengths."""
    from runtime.simulate import ill_conditioning
    long = default_scene(256)
    ratio = 256 * 256 ** 2 / 3 / (1 / 12 + 2.94e-5)
    for planar in (True, False):
        phrase = ill_conditioning(long, long.parameter_vector(), planar)
        assert phrase.startswith("its most extreme ratio is the chain's length: its 256 links") and \
            f"{ratio:.2g} times" in phrase, phrase
    single = load_scene("paper-case2")
    phrase = ill_conditioning(single, single.parameter_vector(), planar=False)
    transverse, axial = 1.0 * 0.5 ** 3 / 12 + 0.5 * 2.94e-5, 0.5 * 5.89e-5
    assert phrase == (f"its most extreme ratio is that of the links' moments of inertia: {transverse:.3g} kg m^2 "
                      f"(link 1, transverse) is {transverse / axial:.2g} times {axial:.3g} kg m^2 (link 1, axial)")
    whip = load_scene("stress-length-ratio-long")
    assert "that of the links' lengths: 1 m (link 2) is 1e+06 times 1e-06 m (link 1)" in \
        ill_conditioning(whip, whip.parameter_vector(), planar=True)


def test_a_long_chain_of_slender_links_is_ill_conditioned_by_its_length_not_its_axial_moments():
    """The premise of the chain-length ratio, on the independent reference model: for 16 and 32 slender links,
    curled or nearly straight, I_f's condition number does not move when the axial moments change a hundredfold,
    and doubling n multiplies it by more than 2^3."""
    rng = np.random.default_rng(4)
    conditions = {}
    for n in (16, 32):
        scene = default_scene(n)
        straight = np.r_[-math.pi / 2, 0.3, rng.normal(scale=0.05, size=n), 0.0, 0.0, 0.0]
        for name, q in (("curled", np.array(scene.q0)), ("straight", straight)):
            for axial in (5.89e-7, 5.89e-5, 5.89e-3):
                links = tuple(LineLink(1.0, 1.0, (axial, 2.94e-5, 2.94e-5)) for _ in range(n))
                chain = reference_of(Scene(name="chain", links=links, q0=tuple(q)))
                eigenvalues = np.linalg.eigvalsh(chain.mass_matrix(q))
                conditions[n, name, axial] = eigenvalues[-1] / eigenvalues[0]
    for n in (16, 32):
        for name in ("curled", "straight"):
            values = [conditions[n, name, axial] for axial in (5.89e-7, 5.89e-5, 5.89e-3)]
            assert max(values) < 1.01 * min(values), (n, name, values)
            assert conditions[32, name, 5.89e-5] > 8 * conditions[16, name, 5.89e-5]


# ---------------------------------------------------------------------------------------------------------------
# friction regularisation
# ---------------------------------------------------------------------------------------------------------------
def rough_rod(friction_velocity: float):
    """A 0.5 m rod lying on a floor of Coulomb c_f = 0.5, sliding at 0.05 m/s: it stops after about 0.01 s and then
    rests, in the regularisation's viscous regime (time constant friction_velocity / (c_f g))."""
    return scene_from_dict({
        "name": "rough_rod", "links": [{"length": 0.5, "mu": 1.0}], "friction": {"x2_min": 0.5},
        "friction_velocity": friction_velocity, "restitution": 0.0, "walls": {"x1_min": 0.0, "x1_max": 2.0, "x2_min": 0.0},
        "initial": {"q": [-math.pi / 2, 0.0, -math.pi / 2, 1.0, 0.0, 0.0], "qd": [0.0, 0.0, 0.0, 0.05, 0.0, 0.0]}})


def test_steps_held_back_by_the_friction_regularisation_are_said_to_be_and_friction_velocity_is_named(tmp_path):
    """With the regularisation alone (stick=False) and friction_velocity = 1e-6 m/s: the resting rod takes steps of a
    few 1e-7 s (its time constant 2e-7 s) over nearly all of the run, which the warning says, naming
    friction_velocity; at 1e-2 m/s the run takes a few dozen steps and no warning; sticking (the default) takes a few
    dozen steps at 1e-6 m/s too.  The command (--no-stick) prints the warning."""
    stuck = simulate(quick_model(rough_rod(1e-6)), 0.025, t_eval=[])
    assert stuck.success and stuck.n_steps < 1000 and stuck.n_sticks >= 1 and stuck.warnings == []
    slow = simulate(quick_model(rough_rod(1e-6)), 0.025, t_eval=[], stick=False)
    tau = 1e-6 / (0.5 * 9.81)
    friction = [w for w in slow.warnings if "friction_velocity" in w]
    assert slow.success and slow.n_steps > 10_000 and len(friction) == 1, slow.warnings
    warning, = friction
    assert "began with a point resting on a rough wall and sliding slower than 4 friction_velocity" in warning
    assert f"friction_velocity / (c_f g) = {tau:.2g} s" in warning
    assert "The scene's friction_velocity = 1e-06 m/s: a larger one takes proportionally fewer steps" in warning
    share = float(warning.split("steps (")[1].split("%")[0])
    assert share >= 90
    mean_step = float(warning.split("at a mean step of ")[1].split(" s")[0])
    assert tau < mean_step < 10 * tau                   # an explicit method's steps on a stiff term of time tau
    fast = simulate(quick_model(rough_rod(1e-2)), 0.025, t_eval=[], stick=False)
    assert fast.success and fast.n_steps < 1000 and fast.warnings == []
    rk4 = simulate(quick_model(rough_rod(1e-6)), 0.025, t_eval=[], method="rk4", dt=5e-7, stick=False)
    assert not any("friction_velocity" in w for w in rk4.warnings)    # RK4's step is the caller's
    path = tmp_path / "rod.toml"
    path.write_text('name = "rough_rod"\nfriction = { x2_min = 0.5 }\nfriction_velocity = 1e-6\nrestitution = 0.0\n'
                    '[[links]]\nlength = 0.5\nmu = 1.0\n[walls]\nx1_min = 0.0\nx1_max = 2.0\nx2_min = 0.0\n'
                    f'[initial]\nq = [{-math.pi / 2!r}, 0.0, {-math.pi / 2!r}, 1.0, 0.0, 0.0]\n'
                    'qd = [0.0, 0.0, 0.0, 0.05, 0.0, 0.0]\n')
    done = run_cli("simulate", "--scene", str(path), "--t-end", "0.025", "--no-stick")
    assert done.returncode == 0, done.stderr
    assert "warning: " in done.stderr and "The scene's friction_velocity = 1e-06 m/s" in done.stderr


def test_the_shipped_rough_floor_run_stays_quiet():
    """The documented rough-floor run (4 s, about 5,600 steps) is not held back enough to be warned about."""
    result = simulate(quick_model("rough-floor"), 4.0, t_eval=[])
    assert result.success and result.warnings == []
