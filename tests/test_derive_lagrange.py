"""The Lagrangian expansion (codegen.lagrange) against the Gibbs-Appell kernels and the independent numpy
model (studies/reference.py), for the general and the scene-specialised layouts, slender and rigid links.  The
derivations run as Python (tests/derived.py); one Lagrangian model is compiled (its rhs and its C)."""
import subprocess

import numpy as np
import pytest
import sympy as sp

import codegen
from studies import reference
from codegen.kinematics import ChainSymbols
from codegen.lagrange import Differentiator, energies
from codegen.scene import LineLink, RigidLink, Scene
from codegen.options import build_options
from conftest import chain, random_parameters, random_planar_scene, random_scene, reference_of, tilted
from runtime.compile import LIBRARY_DIR

STRICT = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]
_MODELS = {}


def lagrangian(scene, specialise=False):
    """The compiled model of a scene with the Lagrangian dynamics kernels (cached per session)."""
    from runtime.compile import compile_model
    from runtime.model import CompiledModel
    key = (scene, specialise)
    if key not in _MODELS:
        generated = codegen.generate(scene, build_options(scene, specialise=specialise, formulation="lagrange"))
        module = compile_model(generated.name, generated.header, generated.source, generated.cdef)
        _MODELS[key] = CompiledModel(scene, generated, module)
    return _MODELS[key]


def rel_err(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


GENERAL = [pytest.param(1, False, ("line",), False, id="n1-line", marks=pytest.mark.slow),
           pytest.param(2, True, ("rigid", "line"), False, id="n2-rigid-twists"),
           pytest.param(2, True, ("rigid", "line"), True, id="n2-rigid-twists-tilted-gravity"),
           pytest.param(3, True, ("line",), False, id="n3-line-twists", marks=pytest.mark.slow),
           pytest.param(4, True, ("rigid", "line"), False, id="n4-rigid-twists", marks=pytest.mark.slow)]


def general_scene(n, random_twists, kinds, tilt=False):
    """chain(n, kinds, random_twists), with gravity along a random direction if ``tilt``."""
    scene = chain(n, kinds, random_twists)
    return tilted(scene, seed=n) if tilt else scene


@pytest.mark.parametrize("n,random_twists,kinds,tilt", GENERAL)
def test_general_layout_matches_gibbs_appell_and_reference(derived, n, random_twists, kinds, tilt):
    scene = general_scene(n, random_twists, kinds, tilt)
    lag, ga = derived(scene, formulation="lagrange"), derived(scene)
    assert lag.nq == ga.nq == n + 5
    rng = np.random.default_rng(n)
    for trial in range(3):
        p = random_parameters(scene, seed=300 * n + trial)
        ref = reference_of(scene, p)
        q, qd = reference.random_state(n, rng)
        M, R, qdd = lag.mass_matrix(q, p), lag.bias(q, qd, p), lag.forward_dynamics(q, qd, p)
        assert rel_err(M, ga.mass_matrix(q, p)) < 1e-10
        assert rel_err(R, ga.bias(q, qd, p)) < 1e-10
        assert rel_err(qdd, ga.forward_dynamics(q, qd, p)) < 1e-9
        assert rel_err(M, ref.mass_matrix(q)) < 1e-10
        assert rel_err(R, ref.bias(q, qd)) < 1e-10
        assert rel_err(qdd, ref.forward_dynamics(q, qd)) < 1e-9


SPECIALISED = [pytest.param(1, 2, False, marks=pytest.mark.slow), pytest.param(2, 0, False),
               pytest.param(3, 2, False), pytest.param(3, 2, True, id="3-2-tilted-gravity-in-plane"),
               pytest.param(4, 0, False, marks=pytest.mark.slow)]


@pytest.mark.parametrize("n,normal,tilt", SPECIALISED)
def test_specialised_layout_matches_gibbs_appell_and_reference(derived, n, normal, tilt):
    """Planar scenes (n + 2 coordinates, zero parameters built in), rigid and slender links alternating; ``tilt``:
    gravity along a random direction in the plane (the scene stays planar)."""
    scene = random_planar_scene(n, 90 + n, normal)
    scene = tilted(scene, seed=n, normal=normal) if tilt else scene
    lag, ga = derived(scene, specialise=True, formulation="lagrange"), derived(scene, specialise=True)
    layout = lag.layout
    assert lag.nq == ga.nq == n + 2
    assert layout.zero_params or n == 1              # rigid links (even positions) have zero cz, Ixz, Iyz
    free = list(layout.free)
    ref = reference_of(scene)
    rng = np.random.default_rng(n)
    for trial in range(3):
        q_full, qd_full = reference.random_state(n, rng)
        q = layout.reduce(q_full)
        q_full, qd = layout.expand(q), rng.normal(size=layout.nq)
        qd_full = layout.expand(qd, velocity=True)
        M_ref = ref.mass_matrix(q_full)[np.ix_(free, free)]
        R_ref = ref.bias(q_full, qd_full)[free]
        M, R, qdd = lag.mass_matrix(q), lag.bias(q, qd), lag.forward_dynamics(q, qd)
        assert rel_err(M, ga.mass_matrix(q)) < 1e-10
        assert rel_err(R, ga.bias(q, qd)) < 1e-10
        assert rel_err(qdd, ga.forward_dynamics(q, qd)) < 1e-9
        assert rel_err(M, M_ref) < 1e-10
        assert rel_err(R, R_ref) < 1e-10
        assert rel_err(qdd, np.linalg.solve(M_ref, R_ref)) < 1e-9


def test_rhs_uses_the_lagrangian_forward_dynamics():
    lag = lagrangian(general_scene(2, True, ("rigid", "line")))
    q, qd = reference.random_state(2, np.random.default_rng(7))
    xdot = lag.rhs(0.0, np.concatenate([q, qd]))
    assert np.array_equal(xdot[:lag.nq], qd)
    assert np.array_equal(xdot[lag.nq:], lag.forward_dynamics(q, qd))


def test_differentiator_gives_sympy_diff():
    """The memoised chain rule gives what sympy.diff gives (exact scene: identical after expansion)."""
    scene = Scene(name="exact", links=(LineLink(1.0, 1.0), RigidLink(0.5, 2.0, (0.25, 0.1, 0.0),
                                                                          ((1.0, 0.0, 0.0), (0.0, 2.0, 0.0),
                                                                           (0.0, 0.0, 2.0)))))
    chain = ChainSymbols(scene)
    T, V = energies(chain)
    d = Differentiator()
    for x in [chain.q[i] for i in (0, 2, 3, 5)] + [chain.qd[i] for i in (1, 3, 4)]:
        assert sp.expand(d(T, x) - sp.diff(T, x)) == 0, x
        assert sp.expand(d(V, x) - sp.diff(V, x)) == 0, x


def test_energies_match_the_energy_kernel(derived):
    """T and V written out explicitly equal the model's energy kernel (a separate tape path)."""
    scene = chain(2, ("rigid", "line"), twists=True)
    symbols = ChainSymbols(scene)
    T, V = energies(symbols)
    q, qd = reference.random_state(2, np.random.default_rng(11))
    values = {symbols.q[i]: q[i] for i in range(scene.nq)} | {symbols.qd[i]: qd[i] for i in range(scene.nq)}
    values |= {s: v for s, v in zip(symbols.p, scene.parameter_vector()) if isinstance(s, sp.Symbol)}
    T_model, V_model = derived(scene).energy(q, qd)
    assert abs(float(T.xreplace(values)) - T_model) < 1e-12 * abs(T_model)
    assert abs(float(V.xreplace(values)) - V_model) < 1e-12 * (abs(V_model) + 1)


def test_lagrangian_c_is_strict_c99(tmp_path):
    model = lagrangian(general_scene(2, True, ("rigid", "line"))).generated
    (tmp_path / f"{model.name}.h").write_text(model.header)
    (tmp_path / f"{model.name}.c").write_text(model.source)
    subprocess.run(["gcc", *STRICT, "-O1", "-I", str(LIBRARY_DIR), "-c", f"{model.name}.c", "-o", "m.o"],
                   cwd=tmp_path, check=True)
    assert "Lagrangian expansion" in model.header


def test_unknown_formulation_is_a_clear_error():
    with pytest.raises(ValueError, match="formulation: must be one of gibbs_appell, lagrange, got 'newton'"):
        build_options(random_scene(1, seed=1), formulation="newton")
