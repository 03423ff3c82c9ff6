"""Boxes and a plane as fixed obstacles (gac_obstacle.c): a free rod among a flat slab, a box turned to stand on an
edge (a ridge), a cube standing on a corner, a box turned at random and a slanted roof plane.  The gaps against an
independent numpy signed distance minimised over the rod by a dense search and golden section (inside a box minus
the depth, from the faces of its Minkowski sum with the rod), on random states (inside the obstacles too); J^T n
against central differences of that gap (outside); the rod falling flat onto the slab (v+ = -e v-, no rotation: the
stretch of the rod on the face strikes at its middle, the centre of mass) and onto the ridge and the corner
off-centre (the velocities after it those of an independent numpy Newton's law with the mass matrix and the gap's
gradient)."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene
from runtime import load_model, simulate
from studies.reference import reference_of

G, H = 9.81, 0.3             # m/s^2, m: the rod's gap at the start of a drop
R_LINK = 0.02
TOL = dict(rtol=1e-11, atol=1e-13)


def rotation_taking(u, v) -> np.ndarray:
    """The rotation turning unit u onto unit v (Rodrigues)."""
    u, v = np.asarray(u, float) / np.linalg.norm(u), np.asarray(v, float) / np.linalg.norm(v)
    w, c = np.cross(u, v), float(u @ v)
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


RIDGE_R = rotation_taking((1, 1, 0), (0, 1, 0))              # the box's edge along X3 on top
CORNER_R = rotation_taking((1, 1, 1), (0, 1, 0))             # a cube's corner on top
TILT_R = rotation_taking((0.3, -0.5, 0.8), (0.9, 0.2, -0.1)) @ rotation_taking((1, 0, 0), (0.6, 0.0, 0.8))
ROOF_N = np.array([0.15, -1.0, 0.1]) / np.linalg.norm([0.15, -1.0, 0.1])
OBSTACLES = (
    Obstacle.box("slab", (0.0, 0.2, 0.0), (0.8, 0.2, 0.5)),
    Obstacle.box("ridge", (3.0, 0.3, 0.0), (0.2, 0.2, 0.5), RIDGE_R),
    Obstacle.box("corner", (6.0, 0.3, 0.0), (0.25, 0.25, 0.25), CORNER_R),
    Obstacle.box("tilted", (-3.0, 0.8, 0.2), (0.3, 0.5, 0.2), TILT_R),
    Obstacle.plane("roof", (0.0, 6.0, 0.0), ROOF_N),
)


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m, 1 kg, horizontal (theta_1 = pi/2: along -X1 from O_1), above the slab at the start."""
    scene = Scene(name="obstacle_box", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 0.5, 1.0, 0.0), obstacles=OBSTACLES)
    return load_model(scene)


def box_sd(o: Obstacle, x) -> float:
    """Independent: clamp the point to the box in the box's frame; outside the distance to the clamped point,
    inside minus the distance to the nearest face."""
    R, h = np.array(o.box_rotation), np.array(o.half_extents)
    y = R.T @ (np.asarray(x) - np.array(o.a))
    outside = np.linalg.norm(y - np.minimum(np.maximum(y, -h), h))
    return outside if outside > 0.0 else -np.min(h - np.abs(y))


def box_depth(o: Obstacle, p0, p1) -> float:
    """Independent, in the world's frame: minus the least translation of segment p0-p1 that parts it from the box,
    the greatest separation of the two projections over the normals of the faces of the box's Minkowski sum with
    the segment (the cross products of every pair of its generators, the box's three edges and the segment)."""
    R, h, c = np.array(o.box_rotation), np.array(o.half_extents), np.array(o.a)
    generators = [R[:, 0], R[:, 1], R[:, 2], np.asarray(p1) - np.asarray(p0)]
    best = -math.inf
    for i in range(4):
        for j in range(i + 1, 4):
            n = np.cross(generators[i], generators[j])
            if np.linalg.norm(n) < 1e-9 * max(np.linalg.norm(generators[3]), 1.0):   # (a point: the faces' alone)
                continue
            n /= np.linalg.norm(n)
            reach = h @ np.abs(R.T @ n)
            ends = sorted([n @ (np.asarray(p0) - c), n @ (np.asarray(p1) - c)])
            best = max(best, ends[0] - reach, -reach - ends[1])
    return best


def independent_gap(o: Obstacle, p0, p1, radius: float = R_LINK) -> float:
    """min over s of sd(p0 + s (p1 - p0)) - r: a plane at the ends (its formula); a box by a dense search over s,
    then golden section in the bracket of the best sample, and where that is not positive (the rod touching or in
    the box) minus the depth instead (box_depth)."""
    if o.kind == "plane":
        n = np.array(o.normal)
        return min(n @ (p0 - np.array(o.a)), n @ (p1 - np.array(o.a))) - radius
    f = lambda s: box_sd(o, p0 + s * (p1 - p0))
    if np.array_equal(p0, p1):                                # a joint point's contact
        distance = f(0.0)
        return (distance if distance > 0.0 else box_depth(o, p0, p1)) - radius
    grid = np.linspace(0.0, 1.0, 401)
    k = int(np.argmin([f(s) for s in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, 400)]
    golden = (math.sqrt(5) - 1) / 2
    while hi - lo > 1e-14:
        m1, m2 = hi - golden * (hi - lo), lo + golden * (hi - lo)
        lo, hi = (lo, m2) if f(m1) <= f(m2) else (m1, hi)
    distance = min(f(0.0), f(1.0), f(lo), f(hi))
    return (distance if distance > 0.0 else box_depth(o, p0, p1)) - radius


def gap_of(model, q, o: Obstacle, contact=None) -> float:
    """The independent gap of the rod (or of the joint point of a plane's `contact`) and obstacle o."""
    points = reference_of(model.scene).points(q)
    return independent_gap(o, *(contact.segment(points) if contact is not None else points[:2]))


def test_the_scene_holds_boxes_and_a_plane(model):
    boxes = ["slab", "ridge", "corner", "tilted"]        # a box's: the link's and the joint points'; a plane's: these
    assert [c.name for _, c in model.contacts] == [f"{part}/{b}" for b in boxes for part in ("L1", "O1", "O2")] + \
        ["O1/roof", "O2/roof"]
    assert [c.end for _, c in model.contacts] == [0, 1, 2] * 4 + [1, 2]
    geometry = sum(len(o.geometry_names) for o in model.scene.obstacles)    # after every obstacle's e
    assert model.parameter_names[-5 - geometry:-geometry] == ["e_slab", "e_ridge", "e_corner", "e_tilted", "e_roof"]


def test_gaps_and_directions_against_an_independent_computation(model):
    """Random states of the rod among the obstacles (inside them too): each gap is the independent one; where the
    rod is clear of an obstacle, J^T n is the gradient of the independent gap (central differences) and n is a
    unit vector."""
    rng = np.random.default_rng(3)
    centres = [np.array(o.a) for o in OBSTACLES[:4]]
    checked_rows = 0
    for trial in range(20):
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 3), centres[trial % 4] + rng.uniform(-0.9, 0.9, 3)])
        q[1] = rng.uniform(-1.2, 1.2)                         # theta_0 away from the base chart's lock
        gaps = model.contact_gaps(q)
        for c, (_, contact) in enumerate(model.contacts):
            o = contact.obstacle
            expected = gap_of(model, q, o, contact)
            assert gaps[c] == pytest.approx(expected, abs=1e-11), (trial, contact.name)
            gap, s, t, n = model.contact_geometry(q, c)
            assert gap == gaps[c] and 0.0 <= s <= 1.0 and t == 0.0
            assert contact.end == 0 or s == contact.end - 1                 # a joint point: its end of the link
            if contact.end == 0:
                assert model.obstacle_gap(q, 1, o.name)[:3] == (gap, s, t)
            own = [k for k, (_, other) in enumerate(model.contacts) if other.obstacle is o]
            assert model.obstacle_gap(q, 1, o.name)[0] == pytest.approx(min(gaps[own]), abs=1e-12)   # the least
            assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-14)
            if expected < 0.02:                               # inside or near: the gradient may have a kink
                continue
            g = model.contact_normal(q, c)
            h = 1e-6
            fd = np.array([(gap_of(model, q + h * d, o, contact) - gap_of(model, q - h * d, o, contact)) / (2 * h)
                           for d in np.eye(model.nq)])
            assert g == pytest.approx(fd, abs=2e-6 * max(1.0, np.abs(g).max())), (trial, o.name)
            checked_rows += 1
    assert checked_rows >= 30


def drop(model, x1: float, top: float, e: float, name: str):
    """The rod horizontal from O_1 = (x1, top + R_LINK + H, 0) along -X1, at rest, falling onto obstacle `name`
    (e its e): the run to just after the first strike."""
    q0 = np.array([-math.pi / 2, 0.0, math.pi / 2, x1, top + R_LINK + H, 0.0])
    p = {f"e_{o.name}": 1.0 for o in OBSTACLES} | {f"e_{name}": e}
    r = simulate(model, math.sqrt(2 * H / G) + 0.01, q0=q0, p=p, **TOL)
    assert r.status == 0, r.message
    flat = ["O1/slab", "O2/slab"] if name == "slab" else [f"L1/{name}"]   # a face: both ends; an edge, a corner
    assert sorted(c.wall for c in r.impacts[0].contacts) == flat
    assert r.impacts[0].t == pytest.approx(math.sqrt(2 * H / G), rel=1e-9)
    return r.impacts[0]


@pytest.mark.parametrize("e", [1.0, 0.5])
def test_a_rod_landing_flat_on_a_face_bounces_without_turning(model, e):
    """Both ends over the slab's top face strike at once (each its joint point's contact): the rod's velocity
    reverses to e times it, all along, each end taking half the impulse."""
    impact = drop(model, 0.5, 0.4, e, "slab")
    v = -G * impact.t
    assert np.abs(impact.qd_before - [0, 0, 0, 0, v, 0]).max() <= 1e-9
    assert impact.qd_after == pytest.approx([0, 0, 0, 0, -e * v, 0], abs=1e-9)
    impulses = [c.impulse for c in impact.contacts]
    assert impulses == pytest.approx([-(1 + e) * v * 1.0 / 2] * 2, rel=1e-9)    # m = 1 kg


@pytest.mark.parametrize("name, x1, top, e", [("ridge", 3.3, 0.3 + 0.2 * math.sqrt(2), 1.0),
                                              ("ridge", 3.75, 0.3 + 0.2 * math.sqrt(2), 0.4),
                                              ("corner", 6.2, 0.3 + 0.25 * math.sqrt(3), 1.0),
                                              ("corner", 6.85, 0.3 + 0.25 * math.sqrt(3), 0.7)])
def test_a_rod_landing_off_centre_on_an_edge_or_a_corner(model, name, x1, top, e):
    """The ridge's edge or the cube's corner strikes the rod away from its middle: Newton's law on the gap's
    gradient (central differences of the independent gap), with the mass matrix, gives the velocities after."""
    impact = drop(model, x1, top, e, name)
    o = next(o for o in OBSTACLES if o.name == name)
    q, qd_m = model.layout.reduce(impact.q), model.layout.reduce(impact.qd_before)
    assert abs(gap_of(model, q, o)) <= 1e-9
    s = model.obstacle_gap(q, 1, name)[1]
    assert s == pytest.approx((x1 - o.a[0]) / 1.0, abs=1e-9)  # the apex under the rod, s along it from O_1
    h = 1e-6
    row = np.array([(gap_of(model, q + h * d, o) - gap_of(model, q - h * d, o)) / (2 * h) for d in np.eye(model.nq)])
    y = np.linalg.solve(model.mass_matrix(q), row)
    v = row @ qd_m
    F = -(1 + e) * v / (row @ y)
    qd_p = model.layout.reduce(impact.qd_after)
    assert qd_p == pytest.approx(qd_m + F * y, rel=1e-7, abs=1e-8)
    assert row @ qd_p == pytest.approx(-e * v, rel=1e-7, abs=1e-9)
    assert abs(impact.qd_after[2]) > 0.1                      # struck off-centre, it turns
    lost = impact.energy_before - impact.energy_after
    assert lost == pytest.approx((1 - e * e) * v * v / (2 * (row @ y)), rel=1e-7, abs=1e-12)


EDGE_H = (0.0402, 0.0343, 0.0957)      # m: a small box, and a thin rod (no radius) of 0.27 m, as in a random scene


@pytest.mark.parametrize("phi, tilt, speed, e", [(0.95, 0.0, 2.0, 0.5), (math.pi / 4, 0.7, 20.0, 0.0)])
def test_a_thin_rod_struck_across_an_edge_leaves_the_box(phi, tilt, speed, e):
    """A rod without radius moving straight (no gravity, no rotation) onto a turned box's edge, its middle across
    the edge: the gap closes to 0 on the edge, where sd's nearest face is not the direction that separates rod and
    box; the one strike is along the edge's separating direction n (e x the edge, at phi from the box's X face
    towards its -Z face: the limit of the normal from outside), so n . v+ = -e n . v- and the rod never enters the
    box: its depth at the impact and at every output sample (the independent sd minimised over the rod) is within
    round-off, with the tolerance of a random scene's run (DOP853, rtol 1.3e-10)."""
    length, gap0 = 0.27, 0.01
    q0 = np.array([-math.pi / 2, 0.3, 2.0, 0.0, 0.0, 0.0])
    free = load_model(Scene(name="edge_rod", links=(LineLink(length, 1.0),), gravity=0.0, q0=tuple(q0)))
    a0, a1 = free.contact_points(q0)
    d = (a1 - a0) / length
    along = np.array([math.sin(phi), tilt, math.cos(phi)])             # the rod in the box's frame, across Y
    R = rotation_taking(along, d)
    n = R @ np.array([math.cos(phi), 0.0, -math.sin(phi)])             # (along x E_Y) turned: X towards -Z
    centre = a0 + 0.5 * length * d - gap0 * n - R @ np.array([EDGE_H[0], 0.0, -EDGE_H[2]])
    box = Obstacle.box("box", tuple(centre), EDGE_H, tuple(map(tuple, R)))
    model = load_model(Scene(name="edge_rod", links=(LineLink(length, 1.0),), gravity=0.0, q0=tuple(q0),
                             obstacles=(box,)))
    qd0 = np.concatenate([np.zeros(3), -speed * n])
    t_end = 2 * gap0 / speed
    r = simulate(model, t_end, q0=q0, qd0=qd0, p={"e_box": e}, method="dop853", rtol=1.3e-10, atol=5e-13,
                 t_eval=np.linspace(0.0, t_end, 201))
    assert r.status == 0, r.message
    assert len(r.impacts) == 1 and r.impacts[0].t == pytest.approx(gap0 / speed, rel=1e-9)
    impact = r.impacts[0]
    assert n @ impact.qd_after[3:] == pytest.approx(e * speed, abs=1e-9 * speed)
    assert np.abs(impact.qd_after[:3]).max() <= 1e-9 * speed                  # struck at its middle: no turn
    depth = -min(gap_of_rod(model, q, box) for q in [impact.q, *r.q])
    assert depth <= 1e-10


def gap_of_rod(model, q, o: Obstacle) -> float:
    points = reference_of(model.scene).points(model.layout.reduce(q))
    return independent_gap(o, points[0], points[1], radius=0.0)


def test_film_strips_draw_the_boxes_and_the_plane(model, tmp_path):
    """In the plane each box's outline is its corners' hull there (the slab a rectangle, the ridge a square on
    its edge) and the plane its trace line; in space each box's 12 edges; a film strip of a drop is written."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from runtime.animate import draw_obstacles, film_strip
    fig, ax = plt.subplots()
    draw_obstacles(ax, model.scene, planar=True)
    outlines = [patch.get_xy()[:-1] for patch in ax.patches]
    assert len(outlines) == 4 and len(ax.lines) == 1                         # four boxes, the roof's trace
    assert sorted(map(tuple, np.round(outlines[0], 12))) == [(-0.8, 0.0), (-0.8, 0.4), (0.8, 0.0), (0.8, 0.4)]
    x, y = outlines[1].T
    assert 0.5 * abs(x @ np.roll(y, 1) - y @ np.roll(x, 1)) == pytest.approx(0.16, rel=1e-12)   # (2 * 0.2)^2
    assert y.max() == pytest.approx(0.3 + 0.2 * math.sqrt(2), abs=1e-12)
    (p0, p1) = ax.lines[0]._xy1, ax.lines[0]._xy2                          # the trace: n . (x - point) = 0 there
    for p in (p0, p1):
        assert np.array(ROOF_N[:2]) @ (np.array(p) - (0.0, 6.0)) == pytest.approx(0.0, abs=1e-12)
    plt.close(fig)
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    draw_obstacles(ax, model.scene, planar=False)
    assert len(ax.lines) == 4 * 12 + 1
    plt.close(fig)
    r = simulate(model, 0.4, q0=np.array([-math.pi / 2, 0.0, math.pi / 2, 3.3, 0.9, 0.0]), **TOL)
    film_strip(r, model.scene, tmp_path / "strip.png", [0.0, 0.2, 0.4])
    assert (tmp_path / "strip.png").stat().st_size > 1000
