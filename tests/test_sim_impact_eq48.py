"""The generated impact solve against Eq. 48 assembled and solved directly in numpy."""
import numpy as np
import pytest

from studies import reference
from codegen.scene import load_scene
from conftest import chain, random_parameters
from runtime import ImpactError


def solve_eq48(model, q, qd, contact_set, p):
    """[[I_f, -J^T], [J, 0]] [qd+; F] = [I_f qd-; -e J qd-]  (Eq. 48), J rows along inward normals."""
    M = model.mass_matrix(q, p)
    Jall = model.contact_jacobian(q, p)
    rows, e = [], []
    for c in contact_set:
        point, wall = model.contacts[c]
        rows.append(wall.normal_sign * Jall[model.contact_rows.index((point, wall.axis))])
        e.append(p[model.scene.parameter_names().index(f"e_{wall.name}")])
    J = np.array(rows)
    k, nq = len(contact_set), model.nq
    A = np.block([[M, -J.T], [J, np.zeros((k, k))]])
    b = np.r_[M @ qd, -np.array(e) * (J @ qd)]
    x = np.linalg.solve(A, b)
    return x[:nq], x[nq:], J, np.array(e)


@pytest.mark.parametrize("n,k", [(1, 1), (2, 2), (3, 3), (4, 2)])
def test_impact_matches_block_system(compiled, n, k):
    scene = chain(n, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(n)
    p = random_parameters(scene, seed=80 + n)
    q, qd = reference.random_state(n, rng)
    # k contacts on distinct points and walls of distinct axes where possible
    contact_set = []
    for point in range(1, k + 1):
        wall_index = [i for i, (pt, w) in enumerate(model.contacts) if pt == point][point % 6]
        contact_set.append(wall_index)
    qd_plus, impulse = model.impact(q, qd, contact_set, p)
    qd_ref, F_ref, J, e = solve_eq48(model, q, qd, contact_set, p)
    assert np.allclose(qd_plus, qd_ref, rtol=1e-10, atol=1e-10 * np.abs(qd).max())
    assert np.allclose(impulse, F_ref, rtol=1e-9, atol=1e-10 * np.abs(F_ref).max())
    # Newton's law (Eq. 47) holds and the configuration is untouched
    assert np.allclose(J @ qd_plus, -e * (J @ qd), atol=1e-10 * np.abs(J @ qd).max())


def test_elastic_impact_conserves_energy_and_plastic_loses_it(compiled):
    scene = load_scene("paper-case2")
    model = compiled(scene)
    q = np.array(scene.q0)
    qd = np.array([0.3, -0.2, 1.0, 0.5, -2.0, 0.1])
    floor_o1 = next(c for c, (pt, w) in enumerate(model.contacts) if pt == 1 and w.name == "x2_min")
    qd_plus, impulse = model.impact(q, qd, [floor_o1])
    assert impulse[0] > 0                                   # it pushes
    T0, T1 = model.energy(q, qd)[0], model.energy(q, qd_plus)[0]
    assert abs(T1 - T0) < 1e-13 * T0
    p = scene.parameter_vector().copy()
    p[scene.parameter_names().index("e_x2_min")] = 0.0
    qd_plastic, _ = model.impact(q, qd, [floor_o1], p)
    assert model.contact_velocities(q, qd_plastic)[0, 1] == pytest.approx(0.0, abs=1e-13)
    assert model.energy(q, qd_plastic)[0] < T0


def test_impact_errors_are_reported(compiled):
    scene = load_scene("paper-case2")
    model = compiled(scene)
    q, qd = np.array(scene.q0), np.ones(scene.nq)
    with pytest.raises(ImpactError, match="bad contact set"):
        model.impact(q, qd, [len(model.contacts)])
    with pytest.raises(ImpactError, match="bad contact set"):
        model.impact(q, qd, [0, 0])
    # O_1 on x1_min and on x1_max: the same Jacobian row twice -> dependent constraints
    lo = next(c for c, (pt, w) in enumerate(model.contacts) if pt == 1 and w.name == "x1_min")
    hi = next(c for c, (pt, w) in enumerate(model.contacts) if pt == 1 and w.name == "x1_max")
    with pytest.raises(ImpactError, match="singular"):
        model.impact(q, qd, [lo, hi])
    q_lock = q.copy()
    q_lock[1] = np.pi / 2                                   # gimbal lock
    with pytest.raises(ImpactError, match="gimbal lock"):
        model.impact(q_lock, qd, [lo])
