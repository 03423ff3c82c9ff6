"""Mounted bases (scene.base: pinned spherical, pinned revolute, fixed) derived against the independent numpy model
(studies/reference.py) and the Euler-Lagrange expansion (codegen/lagrange.py), run as Python (no C).

A base holds some coordinates of Eq. 13 at constant values with zero rates, so the model's equations are the
reference's full equations restricted to the coordinates left: M[free, free] qdd_free = R[free] at a state whose
held entries are the base's values and whose held rates are 0."""
import dataclasses
import numpy as np
import pytest
import sympy as sp

from codegen.scene import Base, SceneError
from studies import reference
from conftest import chain, random_parameters, reference_of


def rel_err(a, b, floor=1e-300):
    """Largest difference relative to the largest entry of b (or ``floor``, for a b that vanishes by symmetry: a
    rod spinning about a vertical axis has no bias, the model's exactly, the reference's to round-off)."""
    return np.abs(a - b).max() / max(np.abs(b).max(), floor)


def mounted(scene, base):
    """The scene on ``base``, starting from the default start (the base's values in place), its walls' points the
    default (those the base does not hold)."""
    walls = tuple(dataclasses.replace(w, points=()) for w in scene.walls)
    return dataclasses.replace(scene, base=base, walls=walls, q0=(), qd0=())


def unit(v):
    v = np.asarray(v, dtype=float)
    return tuple(float(x) for x in v / np.linalg.norm(v))


BASES = {
    "spherical": Base("pinned", "spherical", (0.3, -0.2, 0.1)),
    "revolute": Base("pinned", "revolute", (0.3, -0.2, 0.1), unit([0.4, -0.7, 0.6])),
    "revolute_x2": Base("pinned", "revolute", (0.0, 1.0, 0.0), (0.0, 1.0, 0.0)),   # theta_0 = pi/2 held
    "fixed": Base("fixed", None, (0.3, -0.2, 0.1), None, (0.7, -0.4, 1.1)),
}
CASES = [(name, n, twists, kinds) for name in BASES for n, twists, kinds in
         ((1, False, ("line",)), (2, True, ("rigid", "line")), (3, True, ("line", "rigid")))
         if not (name == "fixed" and n == 1)]


def full_state(layout, q, qd):
    """A random full-layout state with the base's held values and zero held rates."""
    return layout.expand(layout.reduce(q)), layout.expand(layout.reduce(qd), velocity=True)


@pytest.mark.parametrize("base,n,random_twists,kinds", CASES)
def test_mounted_dynamics_match_reference(derived, base, n, random_twists, kinds):
    scene = mounted(chain(n, kinds, random_twists), BASES[base])
    model = derived(scene)
    layout = model.layout
    free = list(layout.free)
    assert model.nq == scene.nq - len(scene.base.held(n))
    rng = np.random.default_rng(7 * n + len(base))
    for trial in range(3):
        p = random_parameters(scene, seed=300 * n + trial)
        ref = reference_of(scene, p)
        q, qd = full_state(layout, *reference.random_state(n, rng))
        qr, qdr = layout.reduce(q), layout.reduce(qd)
        M = ref.mass_matrix(q)[np.ix_(free, free)]
        R = ref.bias(q, qd)[free]
        assert rel_err(model.mass_matrix(qr, p), M) < 1e-10
        assert rel_err(model.bias(qr, qdr, p), R, floor=1.0) < 1e-10
        assert rel_err(model.forward_dynamics(qr, qdr, p), np.linalg.solve(M, R), floor=1.0) < 1e-9
        # the dense route (I_f by Eq. I/II, then LDL^T) and the articulated one agree
        assert rel_err(model.forward_dynamics(qr, qdr, p, solver="dense"),
                       model.forward_dynamics(qr, qdr, p)) < 1e-10
        # energy: the reference's at the full state, the base's held points still
        T, V = model.energy(qr, qdr, p)
        T_ref, V_ref = ref.energy(q, qd)
        assert abs(T - T_ref) < 1e-12 * abs(T_ref) and abs(V - V_ref) < 1e-12 * (abs(V_ref) + 1)
        points = model.contact_points(qr, p)
        assert rel_err(points, ref.points(q)) < 1e-12
        assert np.allclose(points[0], scene.base.point, rtol=0, atol=1e-15)
        velocities = model.contact_velocities(qr, qdr, p)
        for held in scene.base.held_points():
            assert np.abs(velocities[held - 1]).max() < 1e-14 * max(1.0, np.abs(velocities).max())


@pytest.mark.parametrize("base", ["spherical", "revolute", "fixed"])
def test_mounted_dynamics_match_lagrange(derived, base):
    scene = mounted(chain(2, ("rigid", "line"), True), BASES[base])
    gibbs_appell, lagrange = derived(scene), derived(scene, formulation="lagrange")
    rng = np.random.default_rng(11)
    for trial in range(3):
        p = random_parameters(scene, seed=40 + trial)
        q, qd = full_state(gibbs_appell.layout, *reference.random_state(2, rng))
        qr, qdr = gibbs_appell.layout.reduce(q), gibbs_appell.layout.reduce(qd)
        assert rel_err(gibbs_appell.mass_matrix(qr, p), lagrange.mass_matrix(qr, p)) < 1e-10
        assert rel_err(gibbs_appell.bias(qr, qdr, p), lagrange.bias(qr, qdr, p)) < 1e-10
        assert rel_err(gibbs_appell.forward_dynamics(qr, qdr, p), lagrange.forward_dynamics(qr, qdr, p)) < 1e-9


def test_revolute_base_turns_about_its_axis(derived):
    """Link 1's joint axis z_1 lies along base.axis through base.point (the reference's frames), and theta_1 turns
    link 1 about it."""
    base = BASES["revolute"]
    scene = mounted(chain(2, ("line",), False), base)
    model = derived(scene)
    for theta in (-2.0, 0.3, 1.9):
        q = np.array(scene.q0)
        q[2] = theta
        R1 = reference_of(scene).frames(q)[2]                               # [R_-1, R_0, R_1, ...]
        assert np.allclose(R1[:, 2], base.axis, rtol=0, atol=1e-14)
        points = model.contact_points(model.layout.reduce(q))
        assert abs((points[1] - points[0]) @ np.array(base.axis)) < 1e-14     # link 1 normal to the axis


def test_fixed_base_from_rotation_matches_angles():
    """A fixed base given by ^{ref}R_1 is held at the angles whose frame is that rotation."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        R = reference.random_rotation(rng)
        scene = mounted(chain(2), Base("fixed", None, (0.0, 0.0, 0.0), rotation=tuple(map(tuple, R))))
        q = np.array(scene.q0)
        assert np.allclose(reference_of(scene).frames(q)[2], R, rtol=0, atol=1e-12)


def test_held_coordinates_are_constants_of_the_model():
    """The model's layout leaves the held coordinates out, general or specialised, and an axis along a box axis
    holds exact angles (their sines and cosines vanish symbolically)."""
    from codegen.kinematics import ChainSymbols
    from codegen.specialise import layout_for
    scene = mounted(chain(3), BASES["revolute_x2"])
    for specialise in (False, True):
        layout = layout_for(scene, specialise)
        assert set(layout.held) == {0, 1, 5, 6, 7} and not set(layout.held) & set(layout.free)
        assert any(note.startswith("base pinned (revolute)") for note in layout.notes)
    symbols = ChainSymbols(scene, layout=layout_for(scene, False))
    assert symbols.q[0] == 0 and symbols.q[1] == sp.pi / 2


def test_fixed_base_needs_a_second_link():
    with pytest.raises(SceneError, match="base.kind: a fixed base welds link 1"):
        mounted(chain(1), BASES["fixed"])
