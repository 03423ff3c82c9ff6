"""A link without radius across a box's edge (gac_obstacle.c): touching or reaching into the box, its gap is minus
the depth along the separating axis its normal takes, the edge's common normal with the link, so the gap's gradient
is J^T n and a contact held across the edge holds its gap.  On random rods across the edges of a turned box, at
distances of either sign: the gap is the offset along that common normal (a closed form), and J^T n the central
differences of the gap; a rod dropped tilted onto a ridge's edge off its middle lands there, tips and slides while
held across the edge, its depth (an independent numpy distance, or depth inside) within 1e-10 m all along; a rod
landing with its middle on the edge stays held there, at rest."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from studies.reference import reference_of
from tests.test_sim_obstacle_box import RIDGE_R, TILT_R, independent_gap

G = 9.81
TURNED = Obstacle.box("turned", (0.1, 0.4, -0.2), (0.3, 0.5, 0.2), tuple(map(tuple, TILT_R)))
RIDGE = Obstacle.box("ridge", (0.0, 0.3, 0.0), (0.2, 0.2, 0.5), RIDGE_R)
TOP = 0.3 + 0.2 * math.sqrt(2)                                # the ridge's edge: x = 0, y = TOP, along X3
RUN = dict(method="dop853", rtol=1e-10, atol=1e-12)


def rod_model(box: Obstacle, q0):
    """A free rod of 1 m, 1 kg without radius, in space, and one box."""
    return load_model(Scene(name="edge_rod", links=(LineLink(1.0, 1.0),), gravity=G, q0=tuple(q0), obstacles=(box,)))


def place(model, angles, point, s0: float) -> np.ndarray:
    """q with the rod's turn angles and its point at fraction s0 at `point`."""
    q = np.concatenate([angles, np.zeros(3)])
    a0, a1 = model.contact_points(q)
    q[3:] = np.asarray(point) - a0 - s0 * (a1 - a0)
    return q


def test_across_an_edge_the_gap_is_the_offset_along_the_common_normal_and_its_gradient_the_row():
    """Random rods across the turned box's edges, at offsets delta of either sign (1e-6 to 1e-3 m) along the
    common normal u of rod and edge (outward, inside the edge's cone of normals): the gap is delta (the distance
    outside; inside the depth, least along u for so shallow a cut), n = u, and J^T n is the gap's central
    differences (h = 1e-7 m) inside as outside."""
    rng = np.random.default_rng(11)
    model = rod_model(TURNED, (-1.2, 0.4, 1.9, 0.0, 2.0, 0.0))
    R, h, c = np.array(TURNED.box_rotation), np.array(TURNED.half_extents), np.array(TURNED.a)
    checked = {1: 0, -1: 0}
    while min(checked.values()) < 12:
        k = int(rng.integers(3))                               # the edge along box axis k
        sides = rng.choice([-1.0, 1.0], size=3)
        corner = sides * h
        corner[k] = rng.uniform(-0.7, 0.7) * h[k]
        angles = np.array([rng.uniform(-math.pi, math.pi), rng.uniform(-1.2, 1.2), rng.uniform(-math.pi, math.pi)])
        a0, a1 = model.contact_points(np.concatenate([angles, np.zeros(3)]))
        d = R.T @ (a1 - a0)                                    # the rod in the box's frame
        u = np.cross(d, np.eye(3)[k])
        if np.linalg.norm(u) < 0.3:
            continue
        u /= np.linalg.norm(u)
        u *= 1.0 if u @ sides > 0 else -1.0
        off = [j for j in range(3) if j != k]
        if min(u[j] * sides[j] for j in off) < 0.15:          # not strictly inside the edge's cone of normals
            continue
        sign = 1 if checked[1] <= checked[-1] else -1
        delta = sign * 10.0 ** rng.uniform(-6, -3)
        s0 = rng.uniform(0.25, 0.75)
        q = place(model, angles, c + R @ (corner + delta * u), s0)
        gap, s, _, n = model.obstacle_gap(q, 1, "turned")
        assert gap == pytest.approx(delta, abs=1e-12 * (1 + abs(delta)) + 1e-15), (k, delta)
        assert s == pytest.approx(s0, abs=1e-9)
        assert n == pytest.approx(R @ u, abs=1e-12)
        assert gap == pytest.approx(independent_gap(TURNED, *model.contact_points(q), radius=0.0), abs=1e-12)
        g = model.contact_normal(q, 0)
        step = 1e-7
        fd = np.array([(model.contact_gaps(q + step * e)[0] - model.contact_gaps(q - step * e)[0]) / (2 * step)
                       for e in np.eye(model.nq)])
        assert np.abs(g - fd).max() <= 1e-7 * max(1.0, np.abs(g).max()), (k, delta, g, fd)
        checked[sign] += 1


def drop_on_ridge(psi: float, tau: float, off: float, t_end: float):
    """The rod at rest, turned by psi about X2 (across the ridge's edge at pi/2 - psi) and tilted by tau, its point
    at fraction 1/2 + off 0.05 m above the edge, falling onto it (e = 0): the run, the model and the samples'
    independent gaps (outside the distance, inside minus the depth)."""
    angles = np.array([-math.pi / 2 + psi, 0.0, math.pi / 2 + tau])
    model = rod_model(RIDGE, np.concatenate([angles, [0.0, 1.0, 0.0]]))
    q0 = place(model, angles, (0.0, TOP + 0.05, 0.0), 0.5 + off)
    r = simulate(model, t_end, q0=q0, qd0=np.zeros(6), p={"e_ridge": 0.0}, t_eval=np.linspace(0.0, t_end, 401),
                 **RUN)
    points = reference_of(model.scene).points
    gaps = np.array([independent_gap(RIDGE, *points(model.layout.reduce(q))[:2], radius=0.0) for q in r.q])
    return r, model, gaps


def held_phases(r):
    """(landing, release or t_final) of each stretch the rod rests on the ridge."""
    phases, start = [], None
    for event in r.contact_events:
        if event.kind == "rest":
            start = event.t
        elif event.kind == "release" and start is not None:
            phases.append((start, event.t))
            start = None
    return phases + ([(start, r.t_final)] if start is not None else [])


def test_a_rod_landing_across_an_edge_off_its_middle_is_held_there_as_it_tips():
    """Off its middle the rod tips about the edge as it lands and slides across it, held (the edge's common
    normal turning with the rod) for 0.24 s, released, lands again and is held until its end passes the edge; the
    depth at every sample within 1e-10 m (before the gap was the depth: the held contact sank 1.2e-4 m into the
    ridge in 36 ms, and the projection back onto it stopped the run)."""
    r, model, gaps = drop_on_ridge(0.5, 0.05, 0.15, 1.0)
    assert r.status == 0, r.message
    phases = held_phases(r)
    assert len(phases) >= 1 and phases[0][1] - phases[0][0] > 0.2
    assert r.impacts[0].t == pytest.approx(r.contact_events[0].t)
    turned = []
    for start, end in phases:
        inside = (r.t > start) & (r.t < end)
        assert -gaps[inside].min() <= 1e-10, (start, end)
        turned += [model.obstacle_gap(model.layout.reduce(q), 1, "ridge")[3] for q in r.q[inside]]
    turned = np.array(turned)
    assert np.ptp(np.degrees(np.arctan2(turned[:, 0], turned[:, 1]))) > 30.0     # the normal turned with the rod
    assert -gaps.min() <= 1e-10


def test_a_rod_landing_with_its_middle_on_an_edge_stays_held_at_rest():
    """Its middle on the edge, across it at 50 degrees, the rod lands (e = 0) and rests there to the end, balanced:
    the gap within 1e-13 m and the rod still."""
    r, model, gaps = drop_on_ridge(0.7, 0.0, 0.0, 0.6)
    assert r.status == 0, r.message
    assert [(e.kind, e.wall) for e in r.contact_events] == [("rest", "L1/ridge")]
    after = r.t > r.contact_events[0].t + 1e-3
    assert np.abs(gaps[after]).max() <= 1e-13
    assert np.abs(r.qd[after]).max() <= 1e-9
    assert r.resting_final == [(1, "L1/ridge")]
