"""Impacts near the gimbal lock of the base chart against a 40-digit solve.

Near theta_0 = pi/2 the smallest eigenvalue of I_f falls like chi^2 (chi = |det E| = |cos theta_0| for the
default twists), so a double-precision impact carries a relative error of about 16 eps / chi^2.  The
reference evaluates the same derived expressions for I_f and the contact Jacobian (the kernels' straight-
line programs, before C) in 40-digit arithmetic with mpmath and solves Eq. 47 there.  The compiled impact
must either agree to the bound 16 eps / chi^2 (<= 1e-6 where it answers) or refuse with ERR_GIMBAL_LOCK.
"""
import mpmath as mp
import numpy as np
import pytest

from codegen.kernels import contact_jacobian_kernel, mass_matrix_kernel
from codegen.kinematics import ChainSymbols
from codegen.scene import load_scene
from conftest import mpmath_program
from runtime import ImpactError, simulate

EPS = 2.220446049250313e-16


def evaluate(kernel, q, digits=40):
    """The kernel's outputs at q (float64 values taken exactly), in `digits`-digit arithmetic (its parameters
    baked in)."""
    mp.mp.dps = digits
    return mpmath_program(kernel)([mp.mpf(float(x)) for x in q], [])


@pytest.fixture(scope="module")
def lock_case(compiled):
    scene = load_scene("gimbal-lock")
    chain = ChainSymbols(scene, bake_params=True)
    return scene, compiled(scene, chart_b=True), mass_matrix_kernel(chain), contact_jacobian_kernel(chain)


@pytest.mark.parametrize("cos_theta0", [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9])
def test_impact_near_the_lock_is_accurate_or_refused(lock_case, cos_theta0):
    scene, model, mass_kernel, jacobian_kernel = lock_case
    nq = model.nq
    rng = np.random.default_rng(int(-np.log10(cos_theta0)))
    q = np.array(scene.q0, dtype=float)
    q[1] = np.pi / 2 - cos_theta0
    qd = rng.normal(size=nq)
    chi = abs(np.cos(q[1]))
    c = 0
    point, wall = model.contacts[c]
    row = model.contact_rows.index((point, wall.axis))
    e = model.p[scene.parameter_names().index(f"e_{wall.name}")]
    M = mp.matrix(nq, nq)
    for i, x in enumerate(evaluate(mass_kernel, q)):
        M[i // nq, i % nq] = x
    J = evaluate(jacobian_kernel, q)
    normal = mp.matrix([wall.normal_sign * J[row * nq + i] for i in range(nq)])
    qd_mp = mp.matrix([mp.mpf(float(x)) for x in qd])
    Y = mp.lu_solve(M, normal)
    F = -(1 + e) * (normal.T * qd_mp)[0] / (normal.T * Y)[0]          # Eq. 47, one contact
    exact = np.array([float(x) for x in qd_mp + Y * F])
    bound = 16 * EPS / chi ** 2
    try:
        qd_plus, _ = model.impact(q, qd, [c])
    except ImpactError as exc:
        assert "gimbal lock" in str(exc)
        assert bound > 1e-6                  # refused only where double precision loses 1e-6
        return
    error = np.abs(qd_plus - exact).max() / np.abs(exact).max()
    assert error <= bound <= 1e-6, (cos_theta0, error, bound)


def test_run_into_the_lock_does_not_end_at_an_inaccurate_impact(lock_case):
    """The hybrid loop stops before the lock at the run's tolerance, never applying an impact there; by
    default the run continues on the second chart."""
    scene, model, _, _ = lock_case
    plain = simulate(model, 0.6, rtol=1e-10, atol=1e-12, charts=False)
    assert plain.status == -1 and "gimbal lock" in plain.message
    assert abs(np.cos(plain.q_final[1])) >= np.sqrt(16 * EPS / 1e-10)
    assert simulate(model, 0.6, rtol=1e-10, atol=1e-12).success
