"""Forward sensitivities through resting contact (gac_sens.c): a landing (the impact that puts a contact at rest, its
saltation with the field of the constrained flight after it and the landing struck with e = 0), flight with contacts
held (the constrained dynamics' tangent and the projection after each step), a release (its event time from the
force lambda reaching 0) and contacts at rest at the start.  Against closed forms (a vertical rod that lands and
slides on, a ladder whose top leaves the wall) and central differences of the final state (the same impacts and
contact events across the stencil asserted), and the verdict where resting contact is not differentiated (a rough
wall)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall, scene_from_dict
from conftest import perturbed_start
from runtime import simulate

TIGHT = dict(rtol=1e-12, atol=1e-14)
G = 9.81


def sliding_rod(e: float, h0: float, u0: float):
    """A vertical uniform rod (1 m), its lower end O_1 at height h0 above the floor, at rest but for a horizontal
    speed u0: it bounces once (e), then lands (its next bounce below the rest height) and slides on along the
    frictionless floor, standing on its end."""
    return scene_from_dict({"name": "sens_rest_rod", "gravity": G,
                            "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}],
                            "walls": {"x2_min": 0.0}, "restitution": e,
                            "initial": {"q": [-math.pi / 2, 0.0, 0.0, 0.0, h0, 0.0],
                                        "qd": [0.0, 0.0, 0.0, u0, 0.0, 0.0]}})


def ladder(friction: float = 0.0):
    """A uniform rod (1 m) leaning at 60 degrees on the frictionless wall x1_min and floor, from rest: both ends rest
    from the start; the top leaves the wall at 2/3 of its height, and the rod then strikes the floor with its top
    while its foot rests."""
    phi0 = math.radians(60.0)
    return Scene(name=f"sens_rest_ladder{int(10 * friction)}", links=(LineLink(1.0, 1.0, (0.0, 0.0, 0.0)),),
                 walls=(Wall("x1_min", 0.0, 0.5, friction=friction), Wall("x2_min", 0.0, 0.5, friction=friction)),
                 q0=(-math.pi / 2, 0.0, math.pi / 2 - phi0, math.cos(phi0) + 2e-16, 0.0, 0.0))


def sequence(run):
    return ([tuple(c.label for c in i.contacts) for i in run.impacts],
            [(e.label, e.kind) for e in run.contact_events])


def central_differences(model, t_end, directions, matrix, step=1e-6, p=None, q0=None, qd0=None, **options):
    """Every column of d x(t_end)/d(direction) against a central difference of the final state, to 1e-6 of the
    column's size (at least 1e-5), the perturbed runs meeting the same impacts and contact events as the nominal
    (p, q0, qd0: the nominal run's, the model's by default; q0, qd0 in the full layout)."""
    p = model.p.copy() if p is None else np.array(p, dtype=float)
    q0 = model.layout.expand(model.q0) if q0 is None else np.array(q0, dtype=float)
    qd0 = model.layout.expand(model.qd0, velocity=True) if qd0 is None else np.array(qd0, dtype=float)
    nominal = sequence(simulate(model, t_end, p=p, q0=q0, qd0=qd0, **options))

    def final(h, direction):
        p1, q1, qd1 = perturbed_start(model, direction, h, p, q0, qd0)
        run = simulate(model, t_end, p=p1, q0=q1, qd0=qd1, check_start=False, **options)
        assert run.success and sequence(run) == nominal, direction
        return np.concatenate([model.layout.reduce(run.q_final), model.layout.reduce(run.qd_final)])

    for j, direction in enumerate(directions):
        fd = (final(step, direction) - final(-step, direction)) / (2 * step)
        assert np.abs(fd - matrix[:, j]).max() <= 1e-6 * max(10.0, np.abs(fd).max()), direction


E, H0, U0, T = 0.05, 0.3, 0.7, 0.6


@pytest.fixture(scope="module")
def rod(compiled):
    return compiled(sliding_rod(E, H0, U0), specialise=True, tangent=True)


def test_a_landing_then_sliding_matches_the_closed_form(rod):
    """The rod strikes at t1 = sqrt(2 h0 / g), bounces with e, lands at t2 = t1 (1 + 2 e) and stands on the floor,
    sliding at u0: X2(T) = floor, X1(T) = u0 T, every velocity but X1's 0.  So dX2/dh0 = dX2/de = dX2/dg = 0 (the
    saltation with the constrained field after the landing: with the free one, g dt2 would stay in dqd), dX2/dfloor
    = 1, dX1/du0 = T and d qd = 0 but d qd[X1]/du0 = 1 (the landing struck with e = 0: with its wall's e read, the
    derivative by e would keep -v- de); the landing's time: dt2/dh0 = (1 + 2 e) t1 / (2 h0), dt2/de = 2 t1,
    dt2/dg = -(1 + 2 e) t1 / (2 g)."""
    names = ["q0[X2]", "e_x2_min", "g", "qd0[X1]", "wall_x2_min"]
    r = simulate(rod, T, sensitivities=names, **TIGHT)
    assert r.success and len(r.impacts) == 2 and [e.kind for e in r.contact_events] == ["rest"]
    s = r.sensitivities
    assert s.valid, s.message
    t1 = math.sqrt(2 * H0 / G)
    assert r.contact_events[0].t == pytest.approx(t1 * (1 + 2 * E), rel=1e-10)
    expected = np.zeros((2 * rod.nq, len(names)))
    expected[s.rows.index("q[X2]"), names.index("wall_x2_min")] = 1.0
    expected[s.rows.index("q[X1]"), names.index("qd0[X1]")] = T
    expected[s.rows.index("qd[X1]"), names.index("qd0[X1]")] = 1.0
    assert np.abs(s.matrix - expected).max() < 1e-8
    dt = r.contact_events[0].dt_dp
    assert dt == r.impacts[1].dt_dp
    assert dt["q0[X2]"] == pytest.approx((1 + 2 * E) * t1 / (2 * H0), rel=1e-8)
    assert dt["e_x2_min"] == pytest.approx(2 * t1, rel=1e-8)
    assert dt["g"] == pytest.approx(-(1 + 2 * E) * t1 / (2 * G), rel=1e-8)


def test_a_landing_matches_central_differences(rod):
    names = ["q0[X2]", "e_x2_min", "g", "qd0[X1]", "qd0[X2]"]
    r = simulate(rod, T, sensitivities=names, **TIGHT)
    central_differences(rod, T, names, r.sensitivities.matrix, **TIGHT)


@pytest.fixture(scope="module")
def leaning(compiled):
    return compiled(ladder(), specialise=True, tangent=True)


def test_the_ladder_release_time_scales_with_g(leaning):
    """Both ends rest from the start; the top leaves the wall at t_r with t_r sqrt(g) fixed (the motion from rest
    only scales in time with g): dt_r/dg = -t_r / (2 g), to 1e-8 -- the release's event time from lambda's tangent,
    after the constrained flight's variational equations and the start's projection."""
    r = simulate(leaning, 0.4, sensitivities=["g", "qd0[X1]"], **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O2/x1_min", "rest"), ("O1/x2_min", "rest"),
                                                              ("O2/x1_min", "release")]
    release = r.contact_events[2]
    assert release.dt_dp["g"] == pytest.approx(-release.t / (2 * G), rel=1e-8)


@pytest.mark.parametrize("t_end", [0.3, 0.7])
def test_the_ladder_matches_central_differences(leaning, t_end):
    """At rest from the start (its velocities projected onto the walls: qd0[X1] is taken off), sliding with both ends
    held, then (t_end 0.7) released at the top, which later strikes the floor while the foot rests (an impact with a
    resting contact in it): the final state against central differences."""
    names = ["q0[theta_1]", "g", "qd0[theta_1]", "qd0[X1]", "l_1", "e_x2_min"]
    r = simulate(leaning, t_end, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert len(r.impacts) == (1 if t_end > 0.5 else 0)
    central_differences(leaning, t_end, names, r.sensitivities.matrix, **TIGHT)


def test_a_ladder_standing_on_rough_walls_matches_central_differences(compiled):
    """With c_f = 0.3 on both walls the ladder at 60 degrees stands: at rest from the start, its foot stuck (its
    velocities projected onto the stuck rows there) and its top at rest on the wall, sliding friction's viscous band
    holding it; the state stays put and its derivatives are those of the start."""
    model = compiled(ladder(friction=0.3), specialise=True, tangent=True)
    names = ["q0[theta_1]", "g", "qd0[theta_1]", "l_1", "friction_x1_min", "friction_x2_min"]
    r = simulate(model, 0.3, sensitivities=names, **TIGHT)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    assert [(e.label, e.kind) for e in r.contact_events] == [("O2/x1_min", "rest"), ("O1/x2_min", "rest"),
                                                              ("O1/x2_min", "stick")]
    central_differences(model, 0.3, names, r.sensitivities.matrix, **TIGHT)
