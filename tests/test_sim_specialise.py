"""Specialised models (planar reduction, zero parameters built in) against the general model."""
import math

import numpy as np
import pytest

import codegen
from codegen.scene import LineLink, RigidLink, Scene, SceneError, Wall, contact_points, load_scene
from codegen.specialise import layout_for
from codegen.options import build_options
from runtime import simulate
from conftest import random_planar_scene


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


@pytest.mark.parametrize("n,seed,normal", [pytest.param(1, 1, 2, marks=pytest.mark.slow), (2, 2, 0), (3, 3, 2),
                                            pytest.param(4, 4, 0, marks=pytest.mark.slow)])
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
