"""Specialised models (planar reduction, zero parameters built in) against the general model."""
import math

import numpy as np
import pytest

import codegen
from codegen.scene import LineLink, RigidLink, Scene, SceneError, Wall, contact_points, load_scene
from codegen.specialise import layout_for
from codegen.options import build_options
from runtime import simulate


def rz(angle):
    c, s = math.cos(angle), math.sin(angle)
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


def random_planar_scene(n, seed, normal_axis):
    """A planar chain (joint axes along X3 or X1), in-plane centres of mass, in-plane spin and drift,
    a floor 0.2 m under its lowest point."""
    rng = np.random.default_rng(seed)
    links = []
    for i in range(n):
        if i % 2:
            l, m = rng.uniform(0.3, 1.0), rng.uniform(0.2, 2.0)
            Ixx, Iyy, Izz, Ixy = 0.01 * m, 0.02 * m, 0.025 * m, 0.003 * m
            links.append(RigidLink(l, m, (l * rng.uniform(0.2, 0.8), 0.05 * l, 0.0),
                                   ((Ixx, Ixy, 0.0), (Ixy, Iyy, 0.0), (0.0, 0.0, Izz))))
        else:
            links.append(LineLink(rng.uniform(0.3, 1.0), rng.uniform(0.5, 2.0), tuple(rng.uniform(1e-5, 1e-3, 3))))
    theta_m1 = -math.pi / 2 if normal_axis == 2 else 0.0
    q = [theta_m1, 0.0] + list(rng.uniform(-1.5, 1.5, n)) + [0.0, 0.0, 0.0]
    qd = [0.0, 0.0] + list(rng.normal(0, 2.0, n)) + [0.0, 0.0, 0.0]
    for axis in (0, 1, 2):
        if axis != normal_axis:
            qd[n + 2 + axis] = -abs(rng.normal()) if axis == 1 else rng.normal()   # heading for the floor
    twists = tuple(rz(a) for a in rng.uniform(-1, 1, n - 1))
    probe = Scene(name="probe", links=tuple(links), twists=twists, q0=tuple(q), qd0=tuple(qd))
    floor = contact_points(probe, np.array(q))[:, 1].min() - 0.2
    walls = (Wall("x2_min", floor, 0.8), Wall(f"x{3 - normal_axis}_min", -20.0), Wall(f"x{normal_axis + 1}_max", 5.0))
    return Scene(name=f"planar{n}_{seed}", links=tuple(links), twists=twists, walls=walls, q0=tuple(q),
                 qd0=tuple(qd), gravity=9.81)


def compare(compiled, scene, t_end):
    general = simulate(compiled(scene), t_end, rtol=1e-12, atol=1e-14)
    special = simulate(compiled(scene, specialise=True), t_end, rtol=1e-12, atol=1e-14)
    assert general.success and special.success
    assert len(general.impacts) == len(special.impacts) >= 1
    for a, b in zip(general.impacts, special.impacts):
        assert abs(a.t - b.t) < 1e-10
        assert [(c.point, c.wall) for c in a.contacts] == [(c.point, c.wall) for c in b.contacts]
    assert np.abs(general.q - special.q).max() < 1e-8
    assert np.abs(general.qd - special.qd).max() < 1e-7
    return general, special


def test_case1_specialised_and_general_give_the_same_trajectory(compiled):
    scene = load_scene("paper-case1")
    assert compiled(scene, specialise=True).nq == 6 and compiled(scene).nq == 9
    compare(compiled, scene, 1.5)


@pytest.mark.parametrize("n,seed,normal", [(1, 1, 2), (2, 2, 0), (3, 3, 2), (4, 4, 0)])
def test_random_planar_scenes(compiled, n, seed, normal):
    scene = random_planar_scene(n, seed, normal)
    layout = layout_for(scene)
    assert layout.planar_normal == normal and layout.nq == n + 2
    compare(compiled, scene, 0.8)


def test_specialised_model_is_smaller():
    scene = load_scene("paper-case1")
    general = {f.name: f.ops.total for f in codegen.generate(scene, build_options(scene, specialise=False)).functions}
    special = {f.name: f.ops.total for f in codegen.generate(scene).functions}
    assert special["forward_dynamics"] < general["forward_dynamics"] / 2
    assert all(special[name] <= general[name] for name in general)


def test_non_planar_reasons_and_zero_parameters():
    case2 = load_scene("paper-case2")
    assert layout_for(case2).planar_normal is None
    assert any("not planar" in note for note in layout_for(case2).notes)
    moving = Scene(name="m", links=(LineLink(1.0, 1.0),), q0=(-math.pi / 2, 0.0, 0.3, 0.0, 0.0, 0.0),
                   qd0=(0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert "initial velocity" in layout_for(moving).notes[0]
    free_fall = Scene(name="z", links=(LineLink(1.0, 1.0, (1e-4, 0.0, 1e-4)),), gravity=0.0,
                      q0=(0.3, 0.2, 0.3, 0.0, 0.0, 0.0))
    layout = layout_for(free_fall)
    assert layout.zero_params == ("g", "Jyy_1")
    model = codegen.generate(free_fall)
    kernels = model.source.split("_mass_matrix(")[1].split("_rhs(")[0]
    assert "p[0]" not in kernels                                     # g is built in as 0


def test_zero_axial_inertia_of_a_spatial_single_link_is_a_clear_error(compiled):
    spatial = Scene(name="s", links=(LineLink(1.0, 1.0, (0.0, 1e-4, 1e-4)),), q0=(0.3, 0.2, 0.3, 0.0, 0.0, 0.0))
    with pytest.raises(SceneError, match=r"links\[1\].J: Jxx = 0 leaves the spatial single link"):
        codegen.generate(spatial)
    planar = Scene(name="p", links=(LineLink(1.0, 1.0, (0.0, 0.0, 0.0)),), walls=(Wall("x2_min", -1.0),),
                   q0=(-math.pi / 2, 0.0, 0.3, 0.0, 0.0, 0.0))
    result = simulate(compiled(planar, specialise=True), 0.6)        # fine: no rotation about the rod
    assert result.success and len(result.impacts) >= 1


def test_state_outside_the_plane_is_refused(compiled):
    scene = load_scene("paper-case1")
    q0 = np.array(scene.q0)
    q0[0] += 0.1
    with pytest.raises(ValueError, match=r"q0\[0\]: this specialised \(planar\) model holds it"):
        simulate(compiled(scene, specialise=True), 0.1, q0=q0)
