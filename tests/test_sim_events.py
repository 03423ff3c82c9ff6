"""Event search: a dip through a wall shorter than the sample spacing (gap > 0 at every interpolant
sample, < 0 in between) is an impact, found where the gap's minimum (the root of the gap rate) is below 0;
a near miss (minimum gap > 0) is none.

The exact answer: a straight rod thrown vertically upwards without spin rises on a parabola (no torque
about its centre of mass), and every method here integrates a quadratic exactly.  Its top O_2 would rise
to apex = O_2(0) + v0^2 / (2 g); with the ceiling at apex - depth it reaches the ceiling at
t* - sqrt(2 depth / g), t* = v0 / g, at sqrt(2 g depth).  The dip lasts 2 sqrt(2 depth / g) (0.9 ms at
1e-6 m, 29 us at 1e-9 m), far shorter than the sample spacing the large steps give (12.5 ms and more).
"""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate

G, L, V0 = 9.81, 0.5, 2.0
T_APEX = V0 / G
APEX = L + V0 ** 2 / (2 * G)            # of O_2; O_1 starts at X2 = 0
# large steps: RK4 at dt = 0.05 s (4 samples of 12.5 ms per step), the adaptive methods at h_max = 0.1 s
# (their error estimate vanishes on a parabola, so they take the largest step allowed)
METHODS = {"rk4": {"method": "rk4", "dt": 0.05},
           "dopri5": {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12, "h_max": 0.1},
           "dop853": {"method": "dop853", "rtol": 1e-10, "atol": 1e-12, "h_max": 0.1}}


def thrown_rod(ceiling: float) -> Scene:
    """A vertical rod (theta_1 = 0 points link 1 up, +X2) with O_1 at the origin thrown up at V0 under a
    ceiling at X2 = ceiling (both points may touch it; O_1 stays L below O_2)."""
    return Scene(name="thrown_rod", links=(LineLink(L, 1.0),), walls=(Wall("x2_max", ceiling, 1.0),), gravity=G,
                 q0=(-math.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.0), qd0=(0.0, 0.0, 0.0, 0.0, V0, 0.0))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("depth", [1e-6, 1e-9])
def test_shallow_dip_inside_a_sample_interval_is_an_impact(compiled, method, depth):
    model = compiled(thrown_rod(APEX - depth))
    t_eval = np.linspace(0.0, 0.4, 4001)
    result = simulate(model, 0.4, t_eval=t_eval, **METHODS[method])
    assert result.success, result.message
    assert len(result.impacts) == 1, [i.t for i in result.impacts]
    impact = result.impacts[0]
    assert {(c.point, c.wall) for c in impact.contacts} == {(2, "x2_max")}
    t_hit, v_hit = T_APEX - math.sqrt(2 * depth / G), math.sqrt(2 * G * depth)
    # located to event_tol (1e-13 s) on an interpolant exact up to round-off: a few eps of the height
    # (8 eps APEX = 1.3e-15 m), which at the approach speed v_hit moves the crossing by 8 eps APEX / v_hit
    assert abs(impact.t - t_hit) <= 1e-13 + 8 * np.finfo(float).eps * APEX / v_hit, (impact.t - t_hit)
    assert impact.qd_before[4] == pytest.approx(v_hit, rel=1e-6)      # approach speed of O_2 (no spin)
    assert impact.qd_after[4] == pytest.approx(-v_hit, rel=1e-6)      # e = 1
    assert impact.contacts[0].impulse == pytest.approx(2 * L * 1.0 * v_hit, rel=1e-6)
    gaps = np.array([model.contact_gaps(model.layout.reduce(q)) for q in result.q])
    assert gaps.min() > -1e-12                                         # never inside the ceiling
    assert abs(result.energy_drift) < 1e-12


@pytest.mark.parametrize("method", METHODS)
def test_near_miss_by_1e9_is_no_impact(compiled, method):
    model = compiled(thrown_rod(APEX + 1e-9))
    result = simulate(model, 0.4, **METHODS[method])
    assert result.success and result.impacts == [], [i.t for i in result.impacts]
    assert result.q_final[4] == pytest.approx(V0 * 0.4 - 0.5 * G * 0.4 ** 2, abs=1e-12)


def test_dip_at_one_sample_per_step(compiled):
    """event_samples = 1: only the step ends are samples; the dip of 1e-6 m inside a 0.05 s RK4 step
    is still found (by the gap rate changing sign between the ends), at the exact time."""
    result = simulate(compiled(thrown_rod(APEX - 1e-6)), 0.4, method="rk4", dt=0.05, event_samples=1)
    assert len(result.impacts) == 1
    assert abs(result.impacts[0].t - (T_APEX - math.sqrt(2e-6 / G))) < 1e-12
