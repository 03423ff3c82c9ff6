"""The rolled forward dynamics (codegen.rolled: the recursion's passes as C loops over a run of identical links)
against the unrolled kernel and the independent reference model, on chains whose runs have random parameters per
link, a common random twist, springs, dampers and inputs, and links of another kind before and after the run;
which links a run covers; the fall-back when there is none; strict C99."""
from __future__ import annotations

import dataclasses
import subprocess

import numpy as np
import pytest

from codegen import generate, pipeline, rolled
from codegen.emit import render_function
from codegen.flatten import flatten
from codegen.kernels import forward_dynamics_kernel
from codegen.kinematics import ChainSymbols
from codegen.scene import Joint, LineLink, Scene, SceneError, Wall, default_scene
from codegen.specialise import layout_for
from codegen.options import build_options
from conftest import FAR, random_link
from runtime import load_model, simulate
from studies import reference
from studies.reference import reference_of

STRICT = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]


def run_chain(n: int, kinds, seed: int, planar: bool = False, joints: bool = True, inputs: bool = True) -> Scene:
    """n links of kinds[i] (random parameters each), every twist T_2..T_n the same random rotation (about z when
    planar), a spring and a damper on every joint, an input on every joint angle and on X1..X3, far walls; gravity
    along a random direction (gravity_direction) when not planar, else along -X2."""
    rng = np.random.default_rng(seed)
    links = tuple(random_link(rng, kinds[i]) for i in range(n))
    if planar:
        links = tuple(LineLink(link.length, link.mu, (link.J[0], link.J[1], link.J[2])) if link.kind == "line"
                      else link for link in links)
        a = rng.uniform(-np.pi, np.pi)
        T = ((np.cos(a), -np.sin(a), 0.0), (np.sin(a), np.cos(a), 0.0), (0.0, 0.0, 1.0))
    else:
        T = tuple(map(tuple, reference.random_rotation(rng)))
    joint_list = tuple(Joint(stiffness=rng.uniform(0.5, 5), rest_angle=rng.uniform(-1, 1), damping=rng.uniform(0.1, 2))
                       for _ in range(n - 1)) if joints else ()
    names = tuple(f"theta_{k}" for k in range(2, n + 1)) + ("X1", "X2", "X3") if inputs else ()
    walls = tuple(Wall(w, -FAR if w.endswith("min") else FAR, 0.5)
                  for w in ("x1_min", "x1_max", "x2_min", "x2_max", "x3_min", "x3_max"))
    q0 = [0.0] * (n + 5)
    if planar:
        q0[0] = -np.pi / 2
    gravity = rng.uniform(1, 12)
    d = (0.0, -1.0, 0.0) if planar else rng.normal(size=3)
    return Scene(name=f"run{n}_{seed}", links=links, twists=(T,) * (n - 1), gravity=gravity, walls=walls,
                 q0=tuple(q0), joints=joint_list, inputs=names, gravity_direction=tuple(d / np.linalg.norm(d)))


def _run(scene: Scene, specialise: bool = False, bake: bool = False):
    return rolled.find_run(ChainSymbols(scene, bake, layout_for(scene, specialise)))


def summary(model) -> str:
    """The forward dynamics' summary of a generated or compiled model."""
    functions = getattr(model, "generated", model).functions
    return {f.name: f for f in functions}["forward_dynamics"].summary


def rel(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b))))


def test_the_run_is_the_longest_range_of_identical_links():
    assert _run(default_scene(8)) == (2, 7)
    assert _run(default_scene(5)) is None                              # links 2..4: three, fewer than four
    mixed = run_chain(12, ("rigid", "rigid") + ("line",) * 8 + ("rigid", "rigid"), seed=1)
    assert _run(mixed) == (4, 10)          # k - 1 and k both line links; k + 1 may differ (the backward step's child)
    alternating = run_chain(9, ("line", "rigid") * 4 + ("line",), seed=2)
    assert _run(alternating) is None
    # a different twist T_7 splits the run: the steps at links 6 and 7 use it; links 3..5 (link 2's parent, link
    # 1, has no joint spring) are shorter than 8..11
    scene = run_chain(12, ("line",) * 12, seed=3)
    twists = list(scene.twists)
    twists[5] = tuple(map(tuple, reference.random_rotation(np.random.default_rng(0))))   # T_7
    assert _run(dataclasses.replace(scene, twists=tuple(twists))) == (8, 11)


CASES = {
    "3d line run, springs, dampers, inputs": lambda seed: run_chain(7, ("line",) * 7, seed=seed),   # links 3..6
    "3d rigid run between line links": lambda seed: run_chain(11, ("line", "line") + ("rigid",) * 7 + ("line", "line"),
                                                              seed=seed),
    "3d rigid run, no joints or inputs": lambda seed: run_chain(9, ("rigid",) * 9, seed=seed, joints=False,
                                                                inputs=False),
}


# the line run in the default suite; the rigid runs (a minute each to build on two cores) with -m slow
@pytest.mark.parametrize("case", [case if case.startswith("3d line") else pytest.param(case, marks=pytest.mark.slow)
                                  for case in CASES])
def test_rolled_equals_unrolled_and_the_reference(case, tmp_path):
    scene = CASES[case](11)
    assert _run(scene) is not None
    loops = load_model(scene, specialise=False, dense=False, rolled=True, chart_b=False, extended=False)
    straight = load_model(scene, specialise=False, dense=False, rolled=False, chart_b=False, extended=False)
    assert "in loops" in summary(loops) and "in loops" not in summary(straight)
    generated = [{f.name for f in model.generated.functions} for model in (loops, straight)]
    assert "forward_dynamics_energy" not in generated[0] and "forward_dynamics_energy" in generated[1]
    from runtime.compile import LIBRARY_DIR                      # the loops' C is strict C99 too
    (tmp_path / f"{loops.name}.h").write_text(loops.generated.header)
    (tmp_path / f"{loops.name}.c").write_text(loops.generated.source)
    subprocess.run(["gcc", *STRICT, "-O2", "-I", str(LIBRARY_DIR), "-c", str(tmp_path / f"{loops.name}.c"), "-o",
                    str(tmp_path / "m.o")], check=True)
    names = scene.parameter_names()
    rng = np.random.default_rng(len(case))
    for trial in range(4):
        p = CASES[case](100 + trial).parameter_vector()           # new values for every link, gravity, joint
        ref = reference_of(scene, p)
        q, qd = reference.random_state(scene.n, rng)
        u = rng.normal(size=scene.nu) * 3
        a, b = loops.forward_dynamics(q, qd, p, u), straight.forward_dynamics(q, qd, p, u)
        assert rel(a, b) < 1e-12
        for model in (loops, straight):       # forward_dynamics_energy: formed by the library, and generated
            qdd, T, V = model.forward_dynamics_energy(q, qd, p, u)
            E = model.energy(q, qd, p)
            assert rel(qdd, model.forward_dynamics(q, qd, p, u)) < 1e-12
            assert abs(T - E[0]) + abs(V - E[1]) < 1e-12 * (E[0] + abs(E[1]))
        springs = {k: (p[names.index(f"stiffness_{k}")], p[names.index(f"rest_angle_{k}")])
                   for k, j in enumerate(scene.joints, start=2) if j.stiffness is not None}
        dampers = {k: p[names.index(f"damping_{k}")] for k, j in enumerate(scene.joints, start=2) if j.damping}
        M = ref.mass_matrix(q)
        R = ref.bias(q, qd) + ref.applied_forces(q, qd, u, scene.inputs, springs, dampers)
        # backward error against the independent model's I_f and R
        assert np.max(np.abs(M @ a - R)) < 1e-10 * np.max(np.abs(M)) * max(1.0, np.max(np.abs(a)))


@pytest.mark.slow
def test_planar_specialised_and_baked_chains_roll_the_same():
    """Specialised planar models (n + 2 coordinates, out-of-plane blocks dropped) and parameters baked into the
    code: loops over the run give what straight-line code gives, and a parameter built in as zero stays zero."""
    scene = default_scene(10)
    for specialise, bake in ((True, False), (True, True), (False, True)):
        loops = load_model(scene, specialise=specialise, bake_params=bake, rolled=True)
        straight = load_model(scene, specialise=specialise, bake_params=bake, rolled=False)
        assert "in loops" in summary(loops)
        rng = np.random.default_rng(5)
        for _ in range(4):
            q = loops.layout.reduce(rng.uniform(-3, 3, scene.nq))
            qd = loops.layout.reduce(rng.normal(size=scene.nq), ) * 2
            assert rel(loops.forward_dynamics(q, qd), straight.forward_dynamics(q, qd)) < 1e-12
    zero_J = dataclasses.replace(scene, links=tuple(LineLink(1.0, 1.0, (0.0, 0.0, 0.0)) for _ in range(10)))
    assert _run(zero_J, specialise=True) == (2, 9)
    loops = load_model(zero_J, specialise=True, rolled=True)
    straight = load_model(zero_J, specialise=True, rolled=False)
    ops = [{f.name: f for f in m.generated.functions}["forward_dynamics"].ops.total for m in (loops, straight)]
    # the same operations per link; the few more are entries that are zero only at the tip (where the run's
    # loop starts) and are carried into the loop as values
    assert ops[1] <= ops[0] <= ops[1] * 1.02
    q, qd = zero_J.q0, np.linspace(-1, 1, scene.nq)
    assert rel(loops.forward_dynamics(loops.layout.reduce(q), loops.layout.reduce(qd)),
               straight.forward_dynamics(straight.layout.reduce(q), straight.layout.reduce(qd))) < 1e-12


def test_baked_parameters_that_differ_per_link_do_not_roll():
    scene = run_chain(7, ("line",) * 7, seed=21)                # the shortest chain with a run (links 3..6)
    assert _run(scene, bake=True) is None and _run(scene) is not None
    with pytest.raises(SceneError, match="rolled: .* no run"):
        generate(scene, build_options(scene, bake_params=True, rolled=True, chart_b=False))
    # loops wanted but not required (a long chain's default): no loop kernel, the straight-line one stands
    options = dataclasses.replace(build_options(scene, bake_params=True, rolled=True, chart_b=False),
                                  rolled_required=False)
    assert pipeline._rolled_function(scene, options, layout_for(scene, options.specialise)) is None


@pytest.mark.slow     # the default tier compiles the line run's loops strictly (test_rolled_equals_unrolled_...)
def test_rolled_kernel_is_strict_c99_and_costs_what_the_unrolled_does(tmp_path):
    scene = run_chain(9, ("rigid",) * 9, seed=31)                # links 3..8 in loops
    loops = generate(scene, build_options(scene, specialise=False, rolled=True, chart_b=False))
    chain = ChainSymbols(scene, False, loops.layout)             # the same kernel as straight-line code
    b = render_function(flatten(forward_dynamics_kernel(chain)), None)
    a = {f.name: f for f in loops.functions}["forward_dynamics"]
    assert "for (int k = " in "\n".join(a.lines)
    assert b.ops.total <= a.ops.total <= 1.01 * b.ops.total       # the same steps (CSE's choices differ a little)
    assert len(a.lines) < 0.6 * len(b.lines)                    # six links' straight-line code in one loop body
    (tmp_path / f"{loops.name}.h").write_text(loops.header)
    (tmp_path / f"{loops.name}.c").write_text(loops.source)
    from runtime.compile import LIBRARY_DIR
    subprocess.run(["gcc", *STRICT, "-O2", "-I", str(LIBRARY_DIR), "-c", str(tmp_path / f"{loops.name}.c"),
                    "-o", str(tmp_path / "m.o")], check=True)


def test_a_rolled_model_simulates_like_the_unrolled_one():
    scene = default_scene(9)
    loops, straight = load_model(scene, rolled=True), load_model(scene, rolled=False, tangent=False)
    a, b = simulate(loops, t_end=0.6), simulate(straight, t_end=0.6)
    assert len(a.impacts) == len(b.impacts) > 0
    assert max(abs(x.t - y.t) for x, y in zip(a.impacts, b.impacts)) < 1e-9


def test_command_line_names_the_choice(capsys):
    from codegen.cli import main
    assert main(["--links", "10", "--explain"]) == 0
    assert "forward dynamics: loops over links 2..9" in capsys.readouterr().out
    assert main(["--links", "10", "--explain", "--unrolled"]) == 0
    assert "straight-line code per link (--unrolled)" in capsys.readouterr().out
    assert main(["--links", "4", "--rolled", "--no-compile"]) == 2
    assert "--rolled: straight-line code per link: no run of 4 identical links" in capsys.readouterr().err
