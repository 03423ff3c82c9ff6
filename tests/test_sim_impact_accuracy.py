"""An impact's accuracy is measured after its law (record.roundoff): the velocities are refined against the momentum
balance I_f (qd+ - qd-) = J^T Lambda, and an impact that still cannot reach 1e-10 is named with its cause."""
import math

import numpy as np

from conftest import chain, random_parameters
from runtime.simulate import accuracy_cause, simulate
from studies import fuzz


def _fuzz_case(compiled, index: int, run: int):
    """The fuzz study's scene ``index`` (seed 0) and its run ``run``: the model and the run."""
    rng = np.random.default_rng([0, index])
    scene = fuzz.random_structure(rng, index)
    model = compiled(scene)
    for _ in range(run + 1):
        case = fuzz.random_run(rng, scene, model)
    return model, case


def _impulses(model, impact) -> np.ndarray:
    """Lambda along the model's contact rows (N s): each contact's impulse along its wall's inward normal."""
    f = np.zeros(len(model.contact_rows))
    for contact in impact.contacts:
        wall = next(w for w in model.scene.walls if w.name == contact.wall)
        sign = 1.0 if wall.name.endswith("min") else -1.0
        f[model.contact_rows.index((contact.point, wall.axis))] += sign * contact.impulse
        for axis, impulse in zip([a for a in range(3) if a != wall.axis], contact.impulse_t):
            if impulse != 0.0:
                f[model.contact_rows.index((contact.point, axis))] += impulse
    return f


def test_an_ill_conditioned_chain_resolves_its_impacts_to_1e_10(compiled):
    # the fuzz study's 2-link chain 0-11 (a 5.4 t block of 5 mm and a 1.3 mm rod of axial inertia 7e-9 kg m^2 per
    # m) on rough walls: the a-priori round-off bound (4 (nq + 1) eps |I_f| times the velocity changes before they
    # cancel, friction's included, over T) stopped this run at its second impact with a bound of 0.03
    model, case = _fuzz_case(compiled, 11, 3)
    result = simulate(model, case.t_end, p=case.p, q0=case.q0, qd0=case.qd0, **case.options)
    assert result.status == 0, result.message
    assert len(result.impacts) >= 2
    assert not [w for w in result.warnings if "accurate only to" in w]
    layout = model.layout
    for impact in result.impacts:
        # 1e-10, or the frictional solve's own residual (its conditions to GAC_FRICTION_RESIDUAL_MAX = 1e-9)
        assert impact.roundoff <= (1e-10 if impact.law == "frictionless" else 1e-9)
        q = layout.reduce(impact.q)
        before, after = layout.reduce(impact.qd_before), layout.reduce(impact.qd_after)
        M = model.mass_matrix(q, case.p)
        J = model.contact_jacobian(q, case.p)
        T = 0.5 * before @ M @ before
        change = after - before
        # the momentum balance, independently: the energy its residual moves, relative to T
        residual = M @ change - J.T @ _impulses(model, impact)
        assert abs(after @ residual) <= 1e-11 * T
        assert abs(0.5 * after @ M @ after - model.energy(q, after, case.p)[0]) <= 1e-12 * T + 1e-300


def test_the_cause_of_an_inaccurate_impact_is_named(compiled):
    scene = chain(3, ("rigid", "line"), twists=True)
    model = compiled(scene)
    p = random_parameters(scene, 3)
    qd = np.random.default_rng(4).normal(size=model.nq)
    q = np.zeros(model.nq)
    q[0], q[2] = 0.3, -0.4
    q[1] = math.pi / 2 + 1e-4                          # next to the default chart's singular pose (phi = pi / 2)
    cause = accuracy_cause(model, p, q, qd, [0])
    assert "base chart is near its singular pose" in cause and "chi" in cause
    q[1] = 0.2                                         # far from it: the chain's own conditioning is named
    cause = accuracy_cause(model, p, q, qd, [0])
    assert "cond(I_f)" in cause and "base chart" not in cause
    cause = accuracy_cause(model, p, q, qd, [0], law="gdi", residual=3e-10)
    assert "frictional law's solve" in cause
