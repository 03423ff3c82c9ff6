"""Conservation laws in free flight, integrated with the compiled right-hand side."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from studies import reference
from codegen.scene import load_scene
from conftest import chain, random_parameters, reference_of


def fly(model, q, qd, t_end, p=None):
    solution = solve_ivp(lambda t, x: model.rhs(t, x, p), (0.0, t_end), np.r_[q, qd], method="DOP853",
                         rtol=1e-13, atol=1e-13, dense_output=True)
    assert solution.success
    return solution


@pytest.mark.parametrize("scene_name", ["paper-case1", "paper-case2"])
def test_energy_is_conserved_in_flight_paper_scenes(compiled, scene_name):
    """Free flight (walls ignored) from the paper's start with a random spin: 2 s, drift < 1e-10."""
    scene = load_scene(scene_name)
    model = compiled(scene)
    rng = np.random.default_rng(7)
    q, qd = np.array(scene.q0), rng.normal(size=scene.nq)
    E0 = sum(model.energy(q, qd))
    solution = fly(model, q, qd, 2.0)
    for x in solution.y.T[::10]:
        E = sum(model.energy(x[:scene.nq], x[scene.nq:]))
        assert abs(E - E0) < 1e-10 * abs(E0)


@pytest.mark.parametrize("n", [2, 4])
def test_energy_is_conserved_in_flight_random_3d_chain(compiled, n):
    scene = chain(n, ("rigid", "line"), twists=True)
    model = compiled(scene)
    q, qd = reference.random_state(n, np.random.default_rng(n))
    q[1] = 0.3                      # well away from the gimbal lock for the whole run
    E0 = sum(model.energy(q, qd))
    x = fly(model, q, qd, 2.0).y[:, -1]
    E = sum(model.energy(x[:scene.nq], x[scene.nq:]))
    kinetic = model.energy(q, qd)[0]
    assert abs(E - E0) < 1e-10 * max(abs(E0), kinetic)


@pytest.mark.parametrize("n", [1, 3])
def test_linear_momentum_is_conserved_without_gravity(compiled, n):
    scene = chain(n, ("rigid", "line"), twists=True)
    model = compiled(scene)
    p = random_parameters(scene, seed=70 + n)
    p[0] = 0.0                                  # g = 0
    ref = reference_of(scene, p)
    q, qd = reference.random_state(n, np.random.default_rng(n))
    q[1] = 0.2
    P0 = ref.linear_momentum(q, qd)
    solution = fly(model, q, qd, 1.0, p)
    scale = np.linalg.norm(P0) + ref.m.sum() * np.abs(qd).max()
    for x in solution.y.T:
        P = ref.linear_momentum(x[:scene.nq], x[scene.nq:])
        assert np.abs(P - P0).max() < 1e-10 * scale


def test_momentum_check_can_fail(compiled):
    """With gravity the same check must see momentum change (the test above is not vacuous)."""
    scene = chain(1)
    model = compiled(scene)
    ref = reference_of(scene)
    q, qd = reference.random_state(1, np.random.default_rng(0))
    x = fly(model, q, qd, 0.5).y[:, -1]
    change = ref.linear_momentum(x[:scene.nq], x[scene.nq:]) - ref.linear_momentum(q, qd)
    assert abs(change[1] + ref.m.sum() * scene.gravity * 0.5) < 1e-8
