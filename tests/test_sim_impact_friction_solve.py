"""The frictional impact law's solve where Gauss-Seidel and the enumeration of modes fail (gac_impact_friction):
rounds whose contacts' rows are dependent (two walls at one point; a link's end points at three walls) and a later
round that holds only what the earlier rounds left (a link spinning about its own axis, its end points at rest).
Each case is a state the 1,000-run fuzz study stopped at (GAC_ERR_IMPACT_FRICTION), fed to the law directly; its
result is checked from outside the solver: the velocity change is I_f^-1 J^T Lambda (J from the model's contact
velocities), every impulse lies in its Coulomb cone, no contact approaches after, contacts with e = 0 that push end
at rest along their normal, and the kinetic energy never grows."""
from __future__ import annotations

import numpy as np
import pytest

from test_sim_impact_friction import _gamma

# (fuzz case, the impact's contacts, q, qd): the states at which the study's runs stopped
CASES = [
    ("0-19/5", [29, 9, 20],          # point 5 at the corner of x3_max and x1_max: W 6 x 6 of rank 3
     [2.5848925083162406, 0.9306758107892582, -2.42887831201286, 0.2057946734489534, 2.6948759768045294,
      2.8092062766629255, 0.06063697377760716, -0.03789398428651529, -0.001579068335078864],
     [-0.14861109699847297, -0.16638788686817416, 0.007741947102724809, 0.008454394059979322,
      -0.04970860739987965, 0.14697675553570702, 0.13604563873626965, -0.08366558230968912,
      1.3834595014149173e-05]),
    ("0-19/5", [9, 29],              # the same corner 9 ms later: it sticks at both walls, impulses in both cones
     [4.589781985603231, 0.6165221157931636, -4.111837579085692, -0.24237778403087576, 3.598264847932847,
      1.317098924824036, 0.06142577068191012, -0.038437084298188456, -0.0014071606490854694],
     [97.64463635492942, -126.12406709705685, -56.269576260569075, 36.185726402326395, 120.25352853635671,
      -216.50758320315623, 0.10175988643450355, -0.042490726066021424, 0.05930875997891301]),
    ("0-35/2", [14, 16, 15],          # points 3, 4, 5 on x2_min: W 9 x 9 of rank 7
     [0.11454806813325406, -3.8801251097216056, 1.3098450744103858, -11.599690826617227, -1.8837807395387558,
      1.1534205296131286, 3.1377522542707457, -0.00252455249795683, -0.029873919176309827, 0.01064204751799374],
     [35.682334164320245, -51.58562978556385, -25.320778180832136, -52.53467992035651, -5.420782444031246,
      -0.7017337056029803, 2.198222744667807, -0.037370697100687134, 0.04710562200314879,
      0.008001675256844818]),
    ("0-48/1", [3, 9, 10],            # one link spinning about its axis, both ends on walls: W 9 x 9 of rank 5
     [-0.46156538954167503, -0.745033882129608, -1.821079271100829, 0.20150604203567193, -0.06985246704236991,
      0.08560617453477108],
     [-1.1981916942234272, -3.4452245522518092, -0.8123700343133766, 1.281898967854992e-30,
      -8.874684924730026e-31, -8.874685230391986e-31]),
]


def fuzz_model_and_p(compiled, case: str):
    """The fuzz study's model and parameters of a run "seed-structure/run": its general layout and long-double kernels
    as load_model builds it, without the free base's second chart (the law is applied here at states of the first
    chart, whose kernels are the same; half the derivation)."""
    from studies.fuzz import draw_run, draw_structure
    seed, index, k = (int(x) for x in case.replace("/", "-").split("-"))
    scene, rng = draw_structure(seed, index, 8, True)
    model = compiled(scene, specialise=False, chart_b=False, extended=True)
    for _ in range(k + 1):
        run = draw_run(rng, scene, model)
    return model, np.asarray(run.p, dtype=float)


def point_jacobian(model, q, p):
    """d(velocities of O_1..O_npoint)/d qd (3 npoint x nq), column by column from the model's contact velocities."""
    return np.column_stack([model.contact_velocities(q, np.eye(model.nq)[j], p).ravel() for j in range(model.nq)])


@pytest.mark.parametrize("case, contacts, q, qd", CASES, ids=[f"{c[0]}:{c[1]}" for c in CASES])
def test_rounds_with_dependent_contact_rows_are_solved(compiled, case, contacts, q, qd):
    """Before, the round's residual stayed at 0.06 - 0.4 (the law refused the impact); now the law meets its
    conditions: velocity change = I_f^-1 J^T Lambda, cones, no approach after, e = 0 contacts that push at rest,
    T+ <= T-."""
    model, p = fuzz_model_and_p(compiled, case)
    names = model.scene.parameter_names()
    q, qd = np.asarray(q), np.asarray(qd)
    result = model.impact_friction(q, qd, contacts, p)
    assert result.law in ("gdi", "gdi-common-e") and result.residual <= 1e-9
    # I_f (qd+ - qd) = sum_c J_c^T (L_N n_c + L_T t_c), every vector here from the model's kernels
    J, M = point_jacobian(model, q, p), model.mass_matrix(q, p)
    force = np.zeros(3 * model.scene.npoint)
    for k, c in enumerate(contacts):
        point, wall = model.contacts[c]
        axis = "x1 x2 x3".split().index(wall.name[:2])
        force[3 * (point - 1) + axis] += (1.0 if wall.name.endswith("min") else -1.0) * result.impulse[k]
        for j, a in enumerate(a for a in range(3) if a != axis):
            force[3 * (point - 1) + a] += result.impulse_t[k][j]
    change = np.linalg.solve(M, J.T @ force)
    assert np.allclose(result.qd_plus - qd, change, rtol=0, atol=1e-8 * np.abs(change).max() + 1e-13 * np.abs(qd).max())
    # the contact velocities the motion can have: |d_r . qd| <= sqrt(2 T d_r I_f^-1 d_r)
    T_before, T_after = model.energy(q, qd, p)[0], model.energy(q, result.qd_plus, p)[0]
    v_motion = np.sqrt(2 * T_before * np.einsum("ij,ji->i", J, np.linalg.solve(M, J.T)).max())
    assert T_after <= T_before * (1 + 1e-12)
    after = _gamma(model, q, result.qd_plus, p, contacts)
    e_used = [p[names.index(f"e_{model.contacts[c][1].name}")] for c in contacts]
    if result.law == "gdi-common-e":
        e_used = [min(e_used)] * len(contacts)
    for k, c in enumerate(contacts):
        wall = model.contacts[c][1]
        c_f = p[names.index(f"friction_{wall.name}")]
        L_N, L_T = result.impulse[k], np.asarray(result.impulse_t[k])
        assert L_N >= 0 and np.linalg.norm(L_T) <= c_f * L_N * (1 + 1e-9) + 1e-300
        assert after[k][0] >= -1e-9 * v_motion                       # no contact approaches after
        if L_N > 0 and e_used[k] == 0.0:
            assert abs(after[k][0]) <= 1e-9 * v_motion               # plastic and pushing: at rest along n
