"""A capsule link lying nearly parallel along a long fixed bar (the same segment geometry as a link pair,
gac_segment_closest): the gap of nearly parallel segments against an exact minimum distance (mpmath, the candidates
of the unit square), and a rod dropped flat or nearly flat onto the bar with e = 0: exactly level it lands on both
ends at once and rests on them (the bar's joint points' contacts, which take the link's place where it is nearest at
an end); tilted, it lands on its lower end, pivots down about it and lands on the other, then rests on both (a line
contact), no sample inside the bar."""
import math

import mpmath
import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate

ROD, BAR = 14.0, 36.0                   # m: the rod lies along the bar, over its middle stretch
R_ROD, R_BAR = 0.02, 0.03
HEIGHT = 1.0                            # m: the rod's first end O_1 above the bar's axis at the start
TOL = dict(rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def model():
    """A free planar rod of 14 m (theta = -pi/2: along -X1 from O_1 = (7, 1)), a bar of 36 m along X1 below it."""
    bar = Obstacle.bar("bar", (-BAR / 2, 0.0, 0.0), (BAR / 2, 0.0, 0.0), R_BAR)
    scene = Scene(name="link_parallel", links=(LineLink(ROD, 1.0, radius=R_ROD),),
                  q0=(-math.pi / 2, 0.0, math.pi / 2, ROD / 2, HEIGHT, 0.0), gravity=9.81, obstacles=(bar,))
    return load_model(scene)


def exact_distance(a0, a1, b0, b1) -> mpmath.mpf:
    """min |a(s) - b(t)| over the unit square in 50 digits: the lines' stationary point where it is inside, and each
    end's foot on the other segment (the minimum is one of them)."""
    with mpmath.workdps(50):
        a0, a1, b0, b1 = (mpmath.matrix([mpmath.mpf(float(v)) for v in x]) for x in (a0, a1, b0, b1))
        d1, d2, r = a1 - a0, b1 - b0, a0 - b0
        dot = lambda x, y: sum(x[k] * y[k] for k in range(3))      # noqa: E731
        a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)
        clamp = lambda x: min(max(x, mpmath.mpf(0)), mpmath.mpf(1))  # noqa: E731
        pairs = [(mpmath.mpf(s), clamp((f + s * b) / e)) for s in (0, 1)]
        pairs += [(clamp((t * b - c) / a), mpmath.mpf(t)) for t in (0, 1)]
        det = a * e - b * b
        if det > 0:
            s, t = (b * f - c * e) / det, (a * f - b * c) / det
            if 0 <= s <= 1 and 0 <= t <= 1:
                pairs.append((s, t))
        return min(mpmath.sqrt(dot(r + s * d1 - t * d2, r + s * d1 - t * d2)) for s, t in pairs)


def bar_distance(model, q) -> float:
    """The exact distance of the rod's segment from the bar's at q (its joint points from the model)."""
    points = np.asarray(model.contact_points(q)).reshape(-1, 3)
    bar = model.scene.obstacles[0]
    return float(exact_distance(points[0], points[1], np.array(bar.a), np.array(bar.b)))


@pytest.mark.parametrize("angle", [1e-9, 1e-8, 1e-7, 1e-6, 1e-5])
def test_the_gap_of_nearly_parallel_segments_is_the_least_distance(model, angle):
    """The rod tilted by +-angle (about O_1 or so that its far end is lower), at heights from touching to 0.1 m and
    slid along: gap + r_rod + r_bar is the exact least distance to 1e-12 of the lengths (the middle of the overlap,
    its distance off the least by up to the angle times half the overlap, is not taken), and the closest point
    reaches it: the lower end of the rod while the overlap is not flat."""
    for sign in (1.0, -1.0):
        for height in (R_ROD + R_BAR, 0.05, 0.1):
            for shift in (0.0, 3.3, 10.0):
                q = np.array([math.pi / 2 + sign * angle, ROD / 2 + shift, height])   # (theta, x1, x2)
                gap, s, t, n = model.obstacle_gap(q, 1, "bar")
                exact = bar_distance(model, q)
                assert abs(gap + R_ROD + R_BAR - exact) <= 1e-12 * (ROD + BAR), (angle, sign, height, shift)
                if ROD * angle > 1e-9:                  # the overlap not flat: the lower end is closest
                    assert s == (1.0 if sign > 0 else 0.0)


def test_a_level_rod_dropped_on_the_bar_rests_on_both_ends(model):
    """Dropped exactly level (e = 0), the rod lands on the bar with both ends at once (the joint points' contacts;
    the link's own, nearest along the whole overlap, is theirs: redundant) and rests on them, each holding half its
    weight, its gaps held at 0 with no sample inside the bar."""
    r = simulate(model, 1.0, p={"e_bar": 0.0}, t_eval=np.linspace(0.0, 1.0, 201), **TOL)
    assert r.status == 0, r.message
    assert len(r.impacts) == 1 and sorted(c.wall for c in r.impacts[0].contacts) == ["O1/bar", "O2/bar"]
    assert [x.kind for x in r.contact_events] == ["rest", "rest"]
    for q in r.q:
        assert bar_distance(model, model.layout.reduce(q)) - R_ROD - R_BAR >= -1e-9
    assert sorted(r.resting_final) == [(1, "O1/bar"), (1, "O2/bar")]
    q, qd = model.layout.reduce(r.q_final), model.layout.reduce(r.qd_final)
    ends = [[c.name for _, c in model.contacts].index(name) for name in ("O1/bar", "O2/bar")]
    _, lam = model.constrained_dynamics(q, qd, ends)
    assert lam == pytest.approx([ROD * 9.81 / 2] * 2, rel=1e-9)                  # mu = 1 kg/m


@pytest.mark.parametrize("angle", [1e-7, 1e-4])
def test_a_tilted_rod_dropped_on_the_bar_comes_down_on_both_ends(model, angle):
    """Dropped with its far end lower by ROD x angle (e = 0), the rod lands on that end, pivots down about it until
    the other end reaches the bar, and lands there too: it rests on both ends (a line contact), and no sample lies
    inside the bar beyond 1e-9 m (checked exactly)."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + angle, ROD / 2, HEIGHT, 0.0])
    r = simulate(model, 1.0, p={"e_bar": 0.0}, q0=q0, t_eval=np.linspace(0.0, 1.0, 401), **TOL)
    assert r.status == 0, r.message
    assert [c.wall for c in r.impacts[0].contacts] == ["O2/bar"]                  # the lower end first
    assert sorted(r.resting_final) == [(1, "O1/bar"), (1, "O2/bar")]
    for q in list(r.q) + [r.q_final]:
        assert bar_distance(model, model.layout.reduce(q)) - R_ROD - R_BAR >= -1e-9
    assert abs(model.layout.reduce(r.q_final)[0] - math.pi / 2) <= 1e-9            # level on the bar
