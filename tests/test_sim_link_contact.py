"""Two links of a chain as capsules (runtime/c/gac_link.c): the closest points of two segments against an independent
computation, the gap of two capsules, and Newton's law on their relative normal velocity: the energy kept at e = 1,
the free chain's momenta kept through the impulse, v+ = -e v- along the normal."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene
from runtime import load_model
from runtime.model import ImpactError
from studies import fuzz
from studies.reference import reference_of

RADII = (0.05, 0.03, 0.04, 0.02)


# min |a(s) - b(t)| over the unit square by its candidates (the interior stationary point, the minimum along each
# edge): the fuzz study's independent segment distance, itself checked against a dense search there
closest_distance = fuzz.segment_distance


@pytest.fixture(scope="module")
def chain():
    """A spatial four-link chain of capsules (twisted joints), no walls, no gravity."""
    twists = (((1.0, 0, 0), (0, 0.0, -1.0), (0, 1.0, 0.0)), ((1.0, 0, 0), (0, 0.6, -0.8), (0, 0.8, 0.6)),
              ((1.0, 0, 0), (0, 0.0, 1.0), (0, -1.0, 0.0)))
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), r) for l, mu, r in zip((1.0, 0.7, 0.9, 0.6), (1.0, 2.0, 0.5, 1.5),
                                                                            RADII))
    scene = Scene(name="capsule_pairs", links=links, twists=twists, gravity=0.0, q0=(0.0,) * 9)
    return load_model(scene)


def test_the_pair_list_leaves_out_adjacent_links_and_bare_segments(chain):
    assert chain.scene.link_pairs() == [(1, 3), (1, 4), (2, 4)]
    bare = Scene(name="bare", links=(LineLink(1.0, 1.0),) * 2 + (LineLink(1.0, 1.0, radius=0.1),) + (LineLink(1.0, 1.0),) * 2)
    assert bare.link_pairs() == [(1, 3), (3, 5)]          # only link 3 is a capsule; (1, 4), (2, 4), ...: segments


def test_segment_distance_against_an_independent_computation(chain):
    """Random states (crossings, parallel and near-parallel pairs included): gap + r_i + r_j is the segments'
    distance, and the returned fractions reach it."""
    reference = reference_of(chain.scene)
    rng = np.random.default_rng(11)
    states = [np.concatenate([rng.uniform(-math.pi, math.pi, 6), rng.uniform(-1, 1, 3)]) for _ in range(200)]
    straight = np.zeros(9)                    # every link along one line (the twists turn about the links' axes):
    states += [straight, straight + 1e-4 * rng.standard_normal(9)]          # collinear, and nearly parallel
    for q in states:
        points = reference.points(q)
        for i, j in [(1, 3), (1, 4), (2, 4), (3, 1)]:
            gap, s, t, n = chain.link_gap(q, i, j)
            a0, a1, b0, b1 = points[i - 1], points[i], points[j - 1], points[j]
            distance = closest_distance(a0, a1, b0, b1)
            assert gap + RADII[i - 1] + RADII[j - 1] == pytest.approx(distance, abs=1e-12)
            assert 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
            d = (a0 + s * (a1 - a0)) - (b0 + t * (b1 - b0))
            assert np.linalg.norm(d) == pytest.approx(distance, abs=1e-12)
            assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-14)
            if distance > 1e-9:
                assert n == pytest.approx(d / distance, abs=1e-9)


def test_collision_keeps_energy_and_momentum_and_obeys_newton(chain):
    """Links 1 and 3 of the free chain struck by Newton's law: at e = 1 the kinetic energy is kept, at any e the
    linear and angular momentum of the free chain are (an internal impulse pair along the line of centres), and
    the relative normal velocity after is -e times the one before."""
    reference = reference_of(chain.scene)
    rng = np.random.default_rng(5)
    struck = 0
    for trial in range(40):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 6), rng.uniform(-1, 1, 3)])
        qd = rng.standard_normal(9)
        gap, s, t, n = chain.link_gap(q, 1, 3)
        if (s, t) == (1.0, 0.0):                  # O_2 and O_3 closest: n along link 2, a push no motion takes
            with pytest.raises(ImpactError, match="singular"):
                chain.link_impact(q, qd, 1, 3, 1.0)
            continue
        for e in (1.0, 0.6, 0.0):
            qd_plus, impulse, v_before = chain.link_impact(q, qd, 1, 3, e)
            vel = chain.contact_velocities(q, qd_plus)
            v_after = n @ ((1 - s) * vel[0] + s * vel[1] - (1 - t) * vel[2] - t * vel[3])
            scale = 1.0 + np.abs(qd).max()
            if v_before >= 0.0:                    # separating: no impulse, nothing changes
                assert impulse == 0.0 and np.array_equal(qd_plus, qd)
                continue
            struck += 1
            assert impulse > 0.0
            assert v_after == pytest.approx(-e * v_before, abs=1e-12 * scale)
            T0, T1 = chain.energy(q, qd)[0], chain.energy(q, qd_plus)[0]
            if e == 1.0:
                assert T1 == pytest.approx(T0, rel=1e-12)
            else:
                assert T1 < T0
            assert reference.linear_momentum(q, qd_plus) == pytest.approx(reference.linear_momentum(q, qd),
                                                                           abs=1e-12 * scale)
            assert reference.angular_momentum(q, qd_plus) == pytest.approx(reference.angular_momentum(q, qd),
                                                                            abs=1e-12 * scale)
    assert struck > 30


def test_bad_pairs_are_refused(chain):
    with pytest.raises(ValueError, match=r"i: a link index in 1..4, got 0"):
        chain.link_gap(np.zeros(9), 0, 2)
    with pytest.raises(ValueError, match=r"j: a link other than i = 2, got 2"):
        chain.link_gap(np.zeros(9), 2, 2)
    with pytest.raises(ValueError, match=r"radius: a finite number >= 0"):
        chain.link_gap(np.zeros(9), 1, 3, radius=-1.0)
