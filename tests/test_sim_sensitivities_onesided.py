"""One-sided sensitivities at a mode boundary inside an impact (simulate(..., one_sided=True), gac_sens.one_sided):
a rod whose centre of mass is at its end O_1 falls flat onto the floor without turning, so both ends strike in one
impact, O_1 takes all of it (the impulse passes through the centre of mass: the rod keeps translating) and O_2 takes
an impulse 0 and leaves exactly at the law's bound (its velocity after is -e times its velocity before).  A spin
that lifts O_2 keeps it out of the pushing set; the opposite spin adds it: the run is piecewise smooth there, and
the right and left derivatives along the spin differ.  Each is checked against one-sided differences of whole runs
(the event sequence of each side asserted the same across its stencil)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import scene_from_dict
from runtime import simulate

TIGHT = dict(rtol=1e-12, atol=1e-14)
E, U, H0, T = 0.6, 1.0, 1e-3, 0.05
LIFT = 5e-7          # O_2 this much above O_1 (inside the simultaneity window, contact_tol 1e-6): O_1 locates the
                     # impact on either side
SPIN = "qd0[theta_1]"                                     # turns the rod in the plane X2-X3 about O_1
DIRECTIONS = [SPIN, "qd0[X2]", "e_x2_min", "g"]           # the last three keep the rod translating: two-sided


def rod_scene(lift: float = LIFT):
    """A rigid link (1 m, 1 kg) with its centre of mass at O_1, lying along X3 with O_2 higher by ``lift``, its
    O_1 at H0 above the floor x2_min = 0, falling at U."""
    return scene_from_dict({"name": "sens_onesided_rod", "gravity": 9.81,
                            "links": [{"length": 1.0, "mass": 1.0, "com": [0.0, 0.0, 0.0],
                                       "inertia": [[1e-3, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]}],
                            "walls": {"x2_min": 0.0}, "restitution": E,
                            "initial": {"q": [0.0, 0.0, math.pi / 2 - math.asin(lift), 0.0, H0, 0.0],
                                        "qd": [0.0, 0.0, 0.0, 0.0, -U, 0.0]}})


@pytest.fixture(scope="module")
def rod(compiled):
    return compiled(rod_scene(), specialise=True, tangent=True)


def final_state(model, direction: str, h: float, q0=None):
    """x(T) (the model's own coordinates) of the run with the direction moved by h, and its events: per impact the
    points that took part, and each one's impulse."""
    full, free = model.scene.full_coordinate_names(), list(model.layout.free)
    q = np.array(model.q0 if q0 is None else q0, dtype=float)
    q = model.layout.expand(q) if len(q) == model.nq else q
    qd = model.layout.expand(np.array(model.qd0, dtype=float), velocity=True)
    p = np.array(model.p, dtype=float)
    if direction.startswith("qd0["):
        qd[full.index(direction[4:-1])] += h
    else:
        p[model.parameter_names.index(direction)] += h
    r = simulate(model, T, t_eval=[T], q0=q, qd0=qd, p=p, **TIGHT)
    assert r.success, r.message
    x = np.concatenate([r.q_final[free], r.qd_final[free]])
    return x, [tuple(c.point for c in i.contacts) for i in r.impacts], [[c.impulse for c in i.contacts]
                                                                        for i in r.impacts]


def test_without_one_sided_the_boundary_ends_the_sensitivities(rod):
    """The construction is a mode boundary: O_2 in the impact with impulse 0 at the law's bound (the verdict)."""
    r = simulate(rod, T, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and len(r.impacts) == 1
    assert [c.point for c in r.impacts[0].contacts] == [1, 2]
    assert r.impacts[0].contacts[1].impulse == pytest.approx(0.0, abs=1e-12)
    s = r.sensitivities
    assert s.code == 10 and not s.valid and not s.one_sided and "mode boundary" in s.message and "O2" in s.message
    assert np.isnan(s.matrix).all() and s.right is None


def test_right_and_left_derivatives_match_one_sided_differences(rod):
    """Along the spin: forward differences (x(p + h) - x(p)) / h converge to the right derivative, backward ones to
    the left one (to 1e-6 relative of the column), and the two differ (the spin's sign decides whether O_2 pushes):
    no single derivative matches both.  The translating directions have equal right and left derivatives, which
    .matrix keeps (NaN in the spin's column)."""
    r = simulate(rod, T, sensitivities=DIRECTIONS, one_sided=True, sensitivities_at_samples=True, **TIGHT)
    s = r.sensitivities
    assert r.success and s.one_sided and s.status == "one-sided" and s.code == 0
    assert s.t_event == pytest.approx(r.impacts[0].t) and "O2/x2_min" in s.message and s.n_impacts == 1
    assert s.right.shape == s.left.shape == (2 * rod.nq, len(DIRECTIONS))
    assert np.allclose(s.at_samples[-1], s.right, rtol=0, atol=1e-12)          # the sample at T: the right ones
    assert np.allclose(s.at_samples_left[-1], s.left, rtol=0, atol=1e-12)
    spin = DIRECTIONS.index(SPIN)
    scale = np.abs(s.right[:, spin]).max()
    assert np.abs(s.right[:, spin] - s.left[:, spin]).max() > 0.1 * scale     # a kink, not round-off
    assert np.isnan(s.matrix[:, spin]).all()
    for j in range(len(DIRECTIONS)):
        if j != spin:
            assert np.allclose(s.right[:, j], s.left[:, j], rtol=1e-9, atol=1e-12), DIRECTIONS[j]
            assert np.allclose(s.matrix[:, j], s.right[:, j], rtol=1e-9, atol=1e-12), DIRECTIONS[j]
    x0, events0, _ = final_state(rod, SPIN, 0.0)
    o2 = {}                    # O_2's impulses on each side
    for side, derivative in ((1.0, s.right[:, spin]), (-1.0, s.left[:, spin])):
        errors, o2[side] = [], []
        for h in (1e-4, 1e-5, 1e-6):
            x, events, impulses = final_state(rod, SPIN, side * h)
            assert events == events0 == [(1, 2)], (side, h, events)               # one impact of O_1 and O_2
            errors.append(np.abs((x - x0) / (side * h) - derivative).max() / scale)
            o2[side].append(impulses[0][1])
        assert max(errors) < 1e-6, (side, errors)
    pushing, out = sorted(o2.values(), key=max, reverse=True)    # O_2 pushes on one side only (impulse ~ h)
    assert min(pushing) > 1e-8 and max(out) < 1e-12, o2
    for j, direction in enumerate(DIRECTIONS):                             # two-sided: central differences
        if j == spin:
            continue
        step = 1e-6
        xp, ep, _ = final_state(rod, direction, step)
        xm, em, _ = final_state(rod, direction, -step)
        assert ep == em == events0
        column = s.matrix[:, j]
        assert np.abs((xp - xm) / (2 * step) - column).max() <= 1e-6 * max(np.abs(column).max(), 1.0), direction


def test_without_a_boundary_one_sided_changes_nothing(rod):
    """O_2 well above the floor: O_1 strikes alone, the sensitivities are valid and one_sided gives the same single
    matrix (no right and left)."""
    q0 = rod.layout.expand(np.array(rod.q0, dtype=float))
    q0[2] = math.pi / 2 - math.asin(0.01)
    plain = simulate(rod, T, q0=q0, sensitivities=DIRECTIONS, **TIGHT).sensitivities
    both = simulate(rod, T, q0=q0, sensitivities=DIRECTIONS, one_sided=True, **TIGHT).sensitivities
    assert plain.valid and both.valid and not both.one_sided and both.right is None and both.left is None
    assert np.array_equal(plain.matrix, both.matrix)


def test_one_sided_needs_directions(rod):
    with pytest.raises(ValueError, match="one_sided: needs sensitivities"):
        simulate(rod, T, one_sided=True)
