"""A link lying along a plane: the line contact (gac_contact.end, codegen.scene.Scene.obstacle_contacts).

A plane's signed distance is linear along a link, so a capsule is nearest to it at an end sphere, or all along its
length when it lies flat; the plane's contacts are the joint points of the links it touches, and a link that comes
down to lie on it rests on two of them.  Checked against closed forms (a rod landing end first on a slope, pivoting
down and then sliding with g (sin a - c_f cos a) or staying stuck, friction taking c_f m g cos a per metre slid) and
against an independent formulation: a chain on a plane tilted by a under vertical gravity moves as the same chain on
the box's floor under gravity tilted by a (the floor's contacts are the kernel's Jacobian rows and its frictional
law on the box axes, the plane's the contact frame of the link and obstacle code)."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene, Wall
from runtime import load_model, simulate

G = 9.81
ALPHA = 0.3                     # rad, the slope's tilt
R_LINK = 0.02
TIGHT = dict(rtol=1e-10, atol=1e-12)
N_SLOPE = np.array([-math.sin(ALPHA), math.cos(ALPHA), 0.0])        # its upward normal
DOWN = np.array([-math.cos(ALPHA), -math.sin(ALPHA), 0.0])         # down the slope


@pytest.fixture(scope="module")
def slope():
    """A free rod of 1 m and 1 kg (capsule radius 0.02 m) above the slope through the origin, e = 0, its friction
    coefficient a parameter (built rough)."""
    plane = Obstacle.plane("slope", (0.0, 0.0, 0.0), tuple(N_SLOPE), restitution=0.0, friction=0.2)
    scene = Scene(name="line_slope", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.4, 0.3, 0.8, 0.0), obstacles=(plane,))
    return load_model(scene)


def test_a_planes_contacts_are_the_rods_two_ends(slope):
    assert [(c.name, c.i, c.end, c.radius) for _, c in slope.contacts] == [("O1/slope", 1, 1, R_LINK),
                                                                          ("O2/slope", 1, 2, R_LINK)]


@pytest.mark.parametrize("c_f", [0.0, 0.2, 0.5])
def test_a_rod_landing_end_first_comes_down_flat_and_slides_or_sticks(slope, c_f):
    """Dropped end first (e = 0), the rod lands on O_2, pivots down about it and lands on O_1: from then on both
    ends rest on the slope (every sample's independent gap n . (O_k - point) - r within 1e-9, no rotation, no
    normal velocity), and its centre moves down the slope with the closed-form acceleration g (sin a - c_f cos a)
    (tan a = 0.309: c_f 0 and 0.2 slide, 0.5 sticks and stays), the energy falling by c_f m g cos a per metre slid
    (rigid sliding: the normal forces add up to m g cos a)."""
    t = np.linspace(0.0, 2.0, 401)
    r = simulate(slope, 2.0, p=slope.parameters({"friction_slope": c_f}), t_eval=t, **TIGHT)
    assert r.status == 0, r.message
    rests = [(e.label, e.kind) for e in r.contact_events if e.kind == "rest"]
    assert rests == [("O2/slope", "rest"), ("O1/slope", "rest")]
    assert [[c.label for c in i.contacts] for i in r.impacts] == [["O2/slope"], ["O1/slope", "O2/slope"]]  # e = 0
    flat = max(e.t for e in r.contact_events) + 0.05
    late = t >= flat
    points = np.array([slope.contact_points(slope.layout.reduce(q)) for q in r.q])
    velocities = np.array([slope.contact_velocities(slope.layout.reduce(q), slope.layout.reduce(qd))
                           for q, qd in zip(r.q, r.qd)])
    assert (points @ N_SLOPE - R_LINK).min() >= -1e-9                         # never below it, landing included
    assert np.abs(points[late] @ N_SLOPE - R_LINK).max() <= 1e-9               # both ends on it
    assert np.abs(velocities[late] @ N_SLOPE).max() <= 1e-9
    assert np.abs(r.qd[late, 2]).max() <= 1e-9                                # theta_1: no turning
    centre_v = 0.5 * (velocities[:, 0] + velocities[:, 1]) @ DOWN
    centre_x = 0.5 * (points[:, 0] + points[:, 1]) @ DOWN
    a, b = np.flatnonzero(late)[0], len(t) - 1
    expected = G * (math.sin(ALPHA) - c_f * math.cos(ALPHA))
    if expected <= 0.0:                                                        # stuck
        assert np.abs(centre_v[late]).max() <= 1e-9
        return
    assert (centre_v[b] - centre_v[a]) / (t[b] - t[a]) == pytest.approx(expected, rel=1e-9)
    energy = [sum(slope.energy(slope.layout.reduce(r.q[k]), slope.layout.reduce(r.qd[k]))) for k in (a, b)]
    loss = c_f * 1.0 * G * math.cos(ALPHA) * (centre_x[b] - centre_x[a])
    assert energy[0] - energy[1] == pytest.approx(loss, rel=1e-9, abs=1e-9)


# ---- the same chain on a tilted plane and on the box's floor under tilted gravity ------------------------------

A = math.radians(25.0)
TURN = np.array([[math.cos(A), math.sin(A), 0.0], [-math.sin(A), math.cos(A), 0.0], [0.0, 0.0, 1.0]])  # Rz(-A)
CHAIN = tuple(LineLink(0.5, 2.0) for _ in range(3))
Q0 = np.array([-math.pi / 2, 0.0, -0.4, 0.8, -0.7, 1.0, 1.2, 0.0])          # the incline scene's start
QD0 = np.array([0.0, 0.0, -3.0, 0.0, 0.0, 1.5, 0.5, 0.0])
Q0_SPACE = np.array([-math.pi / 2, 0.3, -0.4, 0.8, -0.7, 1.0, 1.2, 0.0])    # out of the plane, moving out of it
QD0_SPACE = np.array([0.0, 0.4, -3.0, 0.5, 0.0, 1.5, 0.5, 0.7])


@pytest.fixture(scope="module")
def floor_and_plane():
    """The floor x2_min = 0 under gravity along (sin A, -cos A, 0) (the shipped incline's), and the plane through
    the origin of normal Rz(-A) e_2 under gravity -X2: the first scene turned by -A about X3.  Both rough (their
    e and c_f parameters), neither specialised to the plane of the start."""
    floor = Scene(name="line_tilted_gravity", links=CHAIN, gravity=G, gravity_direction=(math.sin(A), -math.cos(A), 0.0),
                  walls=(Wall("x2_min", 0.0, 0.3, (1, 2, 3, 4), 0.6),), q0=tuple(Q0))
    plane = Scene(name="line_tilted_plane", links=CHAIN, gravity=G, q0=tuple(Q0),
                  obstacles=(Obstacle.plane("floor", (0.0, 0.0, 0.0), tuple(TURN @ [0.0, 1.0, 0.0]), restitution=0.3,
                                            friction=0.6),))
    return load_model(floor, specialise=False), load_model(plane, specialise=False)


def turned_start(floor, plane, q0, qd0):
    """The plane scene's start: the floor scene's joint points and their velocities turned by TURN (fitted by least
    squares on the points, then on their velocities: the coordinates' charts differ)."""
    from scipy.optimize import least_squares
    target = floor.contact_points(q0) @ TURN.T
    fit = least_squares(lambda x: (plane.contact_points(x) - target).ravel(), q0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.abs(plane.contact_points(fit.x) - target).max() <= 1e-13
    J = np.column_stack([plane.contact_velocities(fit.x, e).ravel() for e in np.eye(plane.nq)])
    v = (floor.contact_velocities(q0, qd0) @ TURN.T).ravel()
    qd = np.linalg.lstsq(J, v, rcond=None)[0]
    assert np.abs(J @ qd - v).max() <= 1e-13
    return fit.x, qd


@pytest.mark.parametrize("start, c_f, t_end, tol", [
    ("plane", 0.6, 1.5, 1e-9),          # in the plane: bounces, rests, releases, then lying on it, stuck
    ("space", 0.0, 1.0, 1e-9),          # in space, smooth: impacts with held contacts
    ("space", 0.6, 0.75, 1e-9)])        # in space, rough: frictional impacts on the two frames
def test_a_chain_on_a_tilted_plane_moves_as_on_the_floor_under_tilted_gravity(floor_and_plane, start, c_f, t_end,
                                                                              tol):
    """The chain thrown at the floor under tilted gravity and the same chain turned, thrown at the tilted plane
    under vertical gravity: the same impacts (the floor's O_k/x2_min the plane's O_k/floor) at the same times,
    the same rests and releases, the joint points equal up to the turn at every sample (seen 4e-11 m in the plane
    over 1.5 s, 30 impacts, every link coming to lie on it), the same energy.  In space the floor's friction acts
    on the box axes X1, X3 and the plane's on the frame of the link: the cone is the same (round) at impacts; where
    slow points slide at rest the two bases part at the step-end approximation of the slip direction
    (docs/simulation.md), so the rough run in space stops at 0.7 s."""
    floor, plane = floor_and_plane
    q0, qd0 = (Q0, QD0) if start == "plane" else (Q0_SPACE, QD0_SPACE)
    qb, qdb = turned_start(floor, plane, q0, qd0)
    t = np.linspace(0.0, t_end, 151)
    ra = simulate(floor, t_end, p=floor.parameters({"friction_x2_min": c_f}), q0=q0, qd0=qd0, t_eval=t,
                  rtol=1e-11, atol=1e-13)
    rb = simulate(plane, t_end, p=plane.parameters({"friction_floor": c_f}), q0=qb, qd0=qdb, t_eval=t,
                  rtol=1e-11, atol=1e-13)
    assert ra.status == 0 and rb.status == 0, (ra.message, rb.message)
    assert len(ra.impacts) >= 5
    assert [sorted(c.label.replace("x2_min", "floor") for c in i.contacts) for i in ra.impacts] == \
        [sorted(c.label for c in i.contacts) for i in rb.impacts]
    assert [i.t for i in ra.impacts] == pytest.approx([i.t for i in rb.impacts], abs=1e-8)
    assert [(e.label.replace("x2_min", "floor"), e.kind) for e in ra.contact_events] == \
        [(e.label, e.kind) for e in rb.contact_events]
    gap = max(np.abs(floor.contact_points(floor.layout.reduce(a)) @ TURN.T
                     - plane.contact_points(plane.layout.reduce(b))).max() for a, b in zip(ra.q, rb.q))
    assert gap <= tol
    assert rb.energy_final == pytest.approx(ra.energy_final, rel=tol, abs=tol)
    if start == "plane":                                           # in the plane: every link lies on it at the end
        resting = sorted(name for _, name in rb.resting_final)
        assert resting == ["O1/floor", "O2/floor", "O3/floor", "O4/floor"]


def test_a_rod_coming_down_along_a_boxs_face_rests_on_both_ends_and_slides():
    """A box's contacts are each link's (an edge or a corner can touch it anywhere) and the joint points' (which
    take its place where the link is nearest at an end, gac_redundant): a rod landing end first (e = 0) on the top
    face of a box turned by ALPHA pivots down about that end (its joint point's contact) and lands on the other,
    then slides down the face with g sin a on both ends (every sample's independent signed distance of each end
    within 1e-9 m of the face, never inside), as on a plane; only the joint points' contacts strike."""
    from codegen.scene import box_signed_distance
    turn = ((math.cos(ALPHA), -math.sin(ALPHA), 0.0), (math.sin(ALPHA), math.cos(ALPHA), 0.0), (0.0, 0.0, 1.0))
    block = Obstacle.box("block", (0.0, -0.5, 0.0), (2.0, 0.5, 1.0), rotation=turn, restitution=0.0)
    scene = Scene(name="line_box_face", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.4, 0.3, 0.8, 0.0), obstacles=(block,))
    model = load_model(scene)
    assert [c.name for _, c in model.contacts] == ["L1/block", "O1/block", "O2/block"]
    t = np.linspace(0.0, 1.0, 201)
    r = simulate(model, 1.0, t_eval=t, **TIGHT)
    assert r.status == 0, r.message
    assert [[c.label for c in i.contacts] for i in r.impacts] == [["O2/block"], ["O1/block", "O2/block"]]
    assert [(e.label, e.kind) for e in r.contact_events] == [("O2/block", "rest"), ("O1/block", "rest")]
    flat = r.contact_events[-1].t + 0.05
    sd = np.array([[box_signed_distance(block, x) - R_LINK for x in model.contact_points(model.layout.reduce(q))]
                   for q in r.q])
    assert sd.min() >= -1e-9 and np.abs(sd[t >= flat]).max() <= 1e-9
    velocities = np.array([model.contact_velocities(model.layout.reduce(q), model.layout.reduce(qd))
                           for q, qd in zip(r.q, r.qd)])
    centre_v = 0.5 * (velocities[:, 0] + velocities[:, 1]) @ DOWN
    a = np.flatnonzero(t >= flat)[0]
    assert (centre_v[-1] - centre_v[a]) / (t[-1] - t[a]) == pytest.approx(G * math.sin(ALPHA), rel=1e-9)


def test_a_rod_tipping_about_its_middle_on_a_narrow_box_stops_with_the_line_contact_named():
    """A rod longer than the box is wide lies across its top face (both ends over the edges): held at the middle of
    the stretch over the face (the link's contact, nearest inside), it cannot rest on the two edges at once with one
    point; dropped tilted, it lands on one edge, pivots about it and comes down onto the other: the run stops there
    with GAC_ERR_LINK_LINE naming the held contact before the rod sinks into the box."""
    from codegen.scene import box_signed_distance
    block = Obstacle.box("post", (0.0, -0.5, 0.0), (0.2, 0.5, 0.5), restitution=0.0)
    scene = Scene(name="line_box_narrow", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=G,
                  q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.05, 0.5, 0.3, 0.0), obstacles=(block,))
    model = load_model(scene)
    r = simulate(model, 1.0, t_eval=np.linspace(0.0, 1.0, 201), **TIGHT)
    assert r.status < 0 and "line contact" in r.message and "L1/post" in r.message, r.message
    for q in [*r.q[r.t <= r.t_final], r.q_final]:
        points = model.contact_points(model.layout.reduce(q))
        a, b = points[0], points[1]
        depth = min(box_signed_distance(block, a + s * (b - a)) for s in np.linspace(0.0, 1.0, 2001))
        assert depth - R_LINK >= -1e-9
