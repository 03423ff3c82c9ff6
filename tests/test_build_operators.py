"""The O(n) operators of a model -- inertia_solve (I_f^-1 Q), generalized_momentum (I_f qd) and
contact_generalized_force (J^T f) -- against the independent reference model (its mass matrix from geometric
Jacobians and its point Jacobian), against finite differences of the kinetic energy, and against each
other; and the dense matrices a model without dense kernels forms from them (gac_mass_matrix, gac_bias,
gac_contact_jacobian) against the generated dense kernels."""
from __future__ import annotations

import dataclasses
import subprocess

import numpy as np
import pytest

from studies import reference
from conftest import chain, random_parameters, reference_of
from codegen.scene import default_scene
from codegen.options import build_options
from runtime import load_model, simulate

# (scene, dense): the generated dense kernels, or the matrices the library forms from the operators
CASES = [(chain(1), True), (chain(3, ("rigid", "line"), twists=True), True), (chain(4, twists=True), True),
         (chain(3, ("rigid", "line"), twists=True), False),
         pytest.param(chain(4, twists=True), False, marks=pytest.mark.slow)]     # a model of its own for little more


def _rows(model, ref, q_full):
    """The reference model's contact Jacobian rows (point, axis) in the model's row order (general layout)."""
    Jp = ref.point_jacobian(q_full)
    rows = []
    for point, axis in model.contact_rows:
        if axis == "theta":
            row = np.zeros(Jp.shape[2])
            row[point + 1] = 1.0
            rows.append(row)
        else:
            rows.append(Jp[point - 1, axis])
    return np.array(rows)


@pytest.mark.parametrize("scene, dense", CASES, ids=lambda x: getattr(x, "name", f"dense={x}"))
def test_operators_against_the_reference_model(compiled, scene, dense):
    n = scene.n
    model = compiled(scene, dense=dense)
    rng = np.random.default_rng(n)
    for trial in range(3):
        p = random_parameters(scene, seed=3000 * n + trial)
        ref = reference_of(scene, p)
        q, qd = reference.random_state(n, rng)
        M = ref.mass_matrix(q)
        h = model.generalized_momentum(q, qd, p)
        assert np.max(np.abs(h - M @ qd)) < 1e-10 * np.max(np.abs(M)) * np.max(np.abs(qd))
        Q = rng.normal(size=model.nq)
        x = model.inertia_solve(q, Q, p)
        # backward error of the solve (independent of I_f's conditioning), and the round trip through I_f
        assert np.max(np.abs(M @ x - Q)) < 1e-10 * np.max(np.abs(M)) * np.max(np.abs(x))
        assert np.max(np.abs(model.generalized_momentum(q, x, p) - Q)) < 1e-10 * np.max(np.abs(M)) * np.max(np.abs(x))
        N = _rows(model, ref, q)
        f = rng.normal(size=len(N))
        lever = max(1.0, np.max(np.abs(ref.points(q))))
        assert np.max(np.abs(model.contact_generalized_force(q, f, p) - N.T @ f)) < 1e-12 * lever * np.max(np.abs(f))
        # the dense matrices, generated or formed from the operators
        assert np.max(np.abs(model.mass_matrix(q, p) - M)) < 1e-10 * np.max(np.abs(M))
        assert np.max(np.abs(model.contact_jacobian(q, p) - N)) < 1e-12 * lever
        R = model.bias(q, qd, p)
        assert np.max(np.abs(R - M @ ref.forward_dynamics(q, qd))) < 1e-9 * max(1.0, np.max(np.abs(R)))


@pytest.mark.parametrize("n", [2, 5])
def test_momentum_is_the_gradient_of_the_kinetic_energy(derived, n):
    """T is quadratic in qd, so a central difference (T(qd + s e_j) - T(qd - s e_j)) / 2s is exact up to
    round-off for any step s: the momentum against the energy kernel, a separate derivation (no C)."""
    scene = chain(n, ("rigid", "line"), twists=True)
    model = derived(scene)
    rng = np.random.default_rng(40 + n)
    q, qd = reference.random_state(n, rng)
    p = random_parameters(scene, seed=400 + n)
    h = model.generalized_momentum(q, qd, p)
    step = 0.5
    for j in range(model.nq):
        e = np.zeros(model.nq)
        e[j] = step
        difference = (model.energy(q, qd + e, p)[0] - model.energy(q, qd - e, p)[0]) / (2 * step)
        assert abs(difference - h[j]) < 1e-12 * max(1.0, model.energy(q, qd, p)[0])


@pytest.mark.parametrize("n", [3, pytest.param(7, marks=pytest.mark.slow)])
def test_specialised_planar_layouts(compiled, n):
    """Locked coordinates (planar reduction): the operators work on the model's own coordinates."""
    scene = default_scene(n)
    model = compiled(scene, dense=False, specialise=True)
    dense = compiled(scene, dense=True, specialise=True)
    rng = np.random.default_rng(n)
    q = model.q0 + rng.normal(scale=0.3, size=model.nq)
    qd = rng.normal(size=model.nq)
    M = dense.mass_matrix(q)
    assert np.max(np.abs(model.mass_matrix(q) - M)) < 1e-12 * np.max(np.abs(M))
    x = model.inertia_solve(q, qd)
    assert np.max(np.abs(M @ x - qd)) < 1e-11 * np.max(np.abs(M)) * np.max(np.abs(x))
    J = dense.contact_jacobian(q)
    assert np.max(np.abs(model.contact_jacobian(q) - J)) < 1e-13 * n
    f = rng.normal(size=len(J))
    assert np.max(np.abs(model.contact_generalized_force(q, f) - J.T @ f)) < 1e-12 * n * np.max(np.abs(f))
    R = dense.bias(q, qd)
    assert np.max(np.abs(model.bias(q, qd) - R)) < 1e-10 * max(1.0, np.max(np.abs(R)))


def test_the_hybrid_loop_never_uses_the_dense_kernels(compiled):
    """A model with and one without its dense kernels simulate the same run bit for bit: the loop applies the
    operators only."""
    scene = default_scene(3)
    runs = [simulate(compiled(scene, dense=dense, specialise=True), 1.5) for dense in (True, False)]
    assert len(runs[0].impacts) > 0
    assert [i.t for i in runs[0].impacts] == [i.t for i in runs[1].impacts]
    assert np.array_equal(runs[0].q, runs[1].q) and np.array_equal(runs[0].qd, runs[1].qd)


def test_dense_option_is_checked():
    with pytest.raises(TypeError, match="dense"):
        load_model(default_scene(2), dense="yes")


def test_kernels_cut_into_parts_compute_the_same(compiled, tmp_path):
    """Every kernel cut into parts of 25 lines (values crossing parts through s[]) gives what the whole
    kernels give, on random states of a 3D chain."""
    from codegen.pipeline import generate, write_model
    from runtime.compile import compile_model, copy_library
    from runtime.model import CompiledModel
    scene = chain(3, ("rigid", "line"), twists=True)
    whole = compiled(scene, dense=True)                                   # the suite's model of the scene
    generated = generate(scene, dataclasses.replace(whole.options, split_lines=25, split_lines_hot=25))
    parts = CompiledModel(scene, generated, compile_model(generated.name, generated.header, generated.source,
                                                          generated.cdef))
    assert parts.options.split_lines == 25 and whole.options.split_lines != 25
    assert "_forward_dynamics_2(" in parts.generated.source and "_forward_dynamics_2(" not in whole.generated.source
    write_model(parts.generated, tmp_path)             # and the parts are strict C99
    copy_library(tmp_path)
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2", "-c",
                    str(tmp_path / f"{parts.name}.c"), "-o", str(tmp_path / "parts.o")], check=True)
    rng = np.random.default_rng(5)
    for _ in range(3):
        q, qd = reference.random_state(3, rng)
        f = rng.normal(size=len(whole.contact_rows))
        for name, args in (("forward_dynamics", (q, qd)), ("inertia_solve", (q, qd)), ("mass_matrix", (q,)),
                           ("generalized_momentum", (q, qd)), ("contact_generalized_force", (q, f)),
                           ("contact_jacobian", (q,)), ("bias", (q, qd)), ("energy", (q, qd)),
                           ("contact_bias", (q, qd)), ("contact_velocities", (q, qd))):
            a, b = np.asarray(getattr(whole, name)(*args)), np.asarray(getattr(parts, name)(*args))
            assert np.allclose(a, b, rtol=1e-14, atol=1e-14 * np.max(np.abs(a))), name
