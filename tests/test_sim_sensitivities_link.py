"""Forward sensitivities through the impact of two capsule links (gac_sens.c, a contact of kind GAC_CONTACT_LINK):
a free planar three-link chain folding until links 1 and 3 strike (the end of link 1 on the inside of link 3, both
segments moving), its row's derivative against central differences of gac_contact_normal and of the gap, and the
final state's sensitivities to the initial state and to link lengths and masses against central differences of
whole runs (the same impacts across the stencil).  The pair's restitution is fixed in the model (not a parameter)."""
from __future__ import annotations

import numpy as np
import pytest

from runtime import load_model, simulate
from tests.test_sim_link_loop import folding_scene
from tests.test_sim_sensitivities import central_differences
from tests.test_sim_sensitivities_obstacle import central

TIGHT = dict(rtol=1e-12, atol=1e-14)
DIRECTIONS = ["q0[theta_2]", "q0[theta_3]", "qd0[theta_2]", "qd0[X1]", "qd0[theta_1]", "l_3", "mu_2"]


@pytest.fixture(scope="module")
def model():
    return load_model(folding_scene(1.0), tangent=True)


@pytest.mark.parametrize("c", [0, 1], ids=["L1-L3", "O1-L3"])
def test_the_rows_derivative_matches_central_differences_of_the_c_functions(model, c):
    """Near the strike's configuration, along random directions of q and of link 3's length: d gap and d(J^T n)
    (gac_contact_normal_tangent, exact) against sixth-order central differences (step 1e-4) of the gap and of
    gac_contact_normal, to 1e-10 of the row's size; the pair's contact and its end O_1's against link 3."""
    r = simulate(model, 0.2, **TIGHT)
    q_hit = model.layout.reduce(r.impacts[0].q)
    rng = np.random.default_rng(5)
    index = model.parameter_names.index("l_3")
    for _ in range(4):
        q = q_hit + rng.uniform(-0.02, 0.02, model.nq)
        _, s, t, _ = model.link_gap(q, 1, 3)
        assert s == 0.0 and 0.0 < t < 1.0                      # link 1's end on the inside of link 3
        dq, dp = rng.normal(size=model.nq), np.zeros(len(model.p))
        dp[index] = rng.normal()
        dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
        code = model.lib.gac_contact_normal_tangent(model.ffi.addressof(model.c.model), model._ptr(q),
                                                    model._ptr(model.p), c, model._ptr(dq), model._ptr(dp), dgap,
                                                    model._ptr(g), model._ptr(dg))
        assert code == model.lib.GAC_OK
        assert np.allclose(g, model.contact_normal(q, c), rtol=0, atol=1e-14)

        def at(h):
            p = model.p.copy()
            p[index] += h * dp[index]
            return np.concatenate([[model.contact_gaps(q + h * dq, p)[c]], model.contact_normal(q + h * dq, c, p)])

        fd = central(at)
        assert dgap[0] == pytest.approx(fd[0], rel=1e-10)
        assert np.abs(dg - fd[1:]).max() <= 1e-10 * max(1.0, np.abs(fd[1:]).max())


def test_a_link_pair_strike_matches_central_differences(model):
    """One strike of links 1 and 3 (e = 1) within T = 0.5 s: the sensitivities are carried through it (valid, one
    impact differentiated, finite dt*) and match central differences of the final state to 1e-6."""
    q0, qd0, p = np.array(model.scene.q0, dtype=float), np.array(model.scene.qd0, dtype=float), model.p.copy()
    r = simulate(model, 0.5, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and [[c.label for c in i.contacts] for i in r.impacts] == [["O1-L3"]], r.message   # an end
    s = r.sensitivities
    assert s.valid and s.n_impacts == 1 and r.sensitivity_status == "valid", r.sensitivity_message
    assert all(np.isfinite(v) for v in r.impacts[0].dt_dp.values())
    central_differences(model, 0.5, p, q0, qd0, DIRECTIONS, s.matrix, **TIGHT)
