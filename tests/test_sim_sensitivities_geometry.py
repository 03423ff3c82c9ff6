"""Forward sensitivities along an obstacle's geometry (gac_contact_normal_tangent, gac_obstacle_feature_change): a
sphere's centre and radius, a bar's ends and radius, a box's centre and half extents and a plane's point as
directions.  One model holds a ball, a bar, a box turned to stand on an edge (a ridge) and a slanted floor plane
below them all.  The gap's and the row J^T n's derivatives along random directions of those parameters (and of q with
them) against sixth-order central differences of the model's own gap and gac_contact_normal; a rod dropped onto
each obstacle (inside its length onto the ball, across the bar, across the ridge's edge and onto its end, a corner,
end first onto the ridge's face and onto the floor), its final state's and its impact time's sensitivities along the obstacle's geometry
against central differences of whole runs (the same impacts across the stencil); a box's rotation entries and a
plane's normal entries are no directions (the C functions refuse them), but the plane's normal turned about its point
is (turn_x_<plane>, turn_y_<plane>, turn_z_<plane>: dn = e_k x n)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from codegen.scene import LineLink, Obstacle, Scene, split_parameter_name
from runtime import load_model, simulate
from runtime.sensitivities import HELD_GEOMETRY_KINDS
from tests.conftest import perturbed_start
from tests.test_sim_obstacle_box import RIDGE_R
from tests.test_sim_sensitivities_obstacle import central

TIGHT = dict(rtol=1e-12, atol=1e-14)
R_LINK = 0.02
FLOOR_N = np.array([0.1, 1.0, 0.05]) / np.linalg.norm([0.1, 1.0, 0.05])
OBSTACLES = (
    Obstacle.sphere("ball", (0.0, 0.5, 0.0), 0.1),
    Obstacle.bar("bar", (3.0, 0.5, -0.5), (3.2, 0.45, 0.5), 0.05),
    Obstacle.box("ridge", (6.0, 0.3, 0.0), (0.2, 0.25, 0.5), RIDGE_R),     # its top edge along X3 at (5.965, 0.618)
    Obstacle.plane("floor", (0.0, -5.0, 0.0), tuple(FLOOR_N)),
)
NEAR = [np.array(o.a) for o in OBSTACLES[:3]] + [np.array((0.0, -4.6, 0.0))]


@pytest.fixture(scope="module")
def model():
    """A free rod of 1 m (capsule radius 0.02 m) among the four obstacles, with the tangent kernels."""
    scene = Scene(name="sens_obstacle_geometry", links=(LineLink(1.0, 1.0, radius=R_LINK),), gravity=9.81,
                  q0=(-math.pi / 2, 0.0, math.pi / 2, 0.5, 1.0, 0.0), obstacles=OBSTACLES)
    return load_model(scene, tangent=True)


def geometry(name: str) -> list[str]:
    """The obstacle's geometry parameters that are directions (not a box's rotation nor a plane's normal)."""
    obstacle = next(o for o in OBSTACLES if o.name == name)
    return [n for n in obstacle.geometry_names if split_parameter_name(n)[0] not in HELD_GEOMETRY_KINDS]


def normal_tangent(model, q, c, dq, dp):
    """(code, d gap, J^T n, d(J^T n)) of contact c along (dq, dp) by gac_contact_normal_tangent."""
    dgap, g, dg = model.ffi.new("double *"), np.zeros(model.nq), np.zeros(model.nq)
    q, dq, dp = (np.ascontiguousarray(x, dtype=float) for x in (q, dq, dp))
    code = model.lib.gac_contact_normal_tangent(model.ffi.addressof(model.c.model), model._ptr(q),
                                                model._ptr(model.p), c, model._ptr(dq), model._ptr(dp), dgap,
                                                model._ptr(g), model._ptr(dg))
    return code, dgap[0], g, dg


CONTACTS = ["L1/ball", "L1/bar", "L1/ridge", "O1/ridge", "O2/ridge", "O1/floor", "O2/floor"]


@pytest.mark.parametrize("label", CONTACTS)
def test_the_gap_and_row_derivatives_along_the_geometry_match_central_differences(model, label):
    """Random states of the rod clear of the obstacle (gap > 0.02 m; its closest point at an end or inside, a box's
    face, edge or corner nearest; a box's and a plane's joint points' contacts too), along a random direction of the
    obstacle's geometry alone and with a random dq: d gap and d(J^T n) against sixth-order central differences (step
    1e-4) of the gap and of gac_contact_normal with p moved, to 1e-9 of their size (seen ~1e-11)."""
    c = [contact.name for _, contact in model.contacts].index(label)
    rng = np.random.default_rng(11 + c)
    name = label.split("/")[1]
    near = NEAR[[o.name for o in OBSTACLES].index(name)]
    index = [model.parameter_names.index(n) for n in geometry(name)]
    checked, turning = 0, 0
    while checked < 12:
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 3), near + rng.uniform(-0.9, 0.9, 3)])
        q[1] = rng.uniform(-1.2, 1.2)                             # theta_0 away from the base chart's lock
        if model.contact_gaps(q)[c] < 0.02:                       # inside or near: the gap may have a kink
            continue
        for with_q in (False, True):
            dq = rng.normal(size=model.nq) if with_q else np.zeros(model.nq)
            dp = np.zeros(len(model.p))
            dp[index] = rng.normal(size=len(index))
            code, dgap, g, dg = normal_tangent(model, q, c, dq, dp)
            assert code == model.lib.GAC_OK

            def at(h):
                p = model.p + h * dp
                return np.concatenate([[model.contact_gaps(q + h * dq, p)[c]], model.contact_normal(q + h * dq, c, p)])

            fd = central(at)
            assert abs(dgap - fd[0]) <= 1e-9 * max(1.0, abs(fd[0])), (name, with_q)
            assert np.abs(dg - fd[1:]).max() <= 1e-9 * max(1.0, np.abs(fd[1:]).max()), (name, with_q)
            turning += not with_q and np.abs(dg).max() > 1e-3
        checked += 1
    assert turning >= (0 if name == "floor" else 4), turning      # the row turns with the obstacle's motion


def rotated(v, omega, angle):
    """v turned by `angle` about the unit axis omega / |omega| (Rodrigues)."""
    k = omega / np.linalg.norm(omega)
    return v * math.cos(angle) + np.cross(k, v) * math.sin(angle) + k * (k @ v) * (1 - math.cos(angle))


def test_the_floors_turn_is_a_direction_of_its_gap_and_row(model):
    """The plane's normal turned about its point, dn = omega x n (omega random, with a random move of its point and a
    random dq): d gap = n . (dx - dpoint) + dn . (x - point) and d(J^T n) against sixth-order central differences of
    the gap and gac_contact_normal with the normal turned by |omega| h (Rodrigues: unit at every step), to 1e-9; a
    change of the normal that stretches it (n . dn != 0) is refused."""
    rng = np.random.default_rng(29)
    c = next(k for k, (_, contact) in enumerate(model.contacts) if contact.name == "O1/floor")   # a joint point's
    normal = [model.parameter_names.index(f"normal_{x}_floor") for x in "xyz"]
    point = [model.parameter_names.index(f"point_{x}_floor") for x in "xyz"]
    checked = 0
    while checked < 12:
        q = np.concatenate([rng.uniform(-math.pi, math.pi, 3), NEAR[3] + rng.uniform(-0.9, 0.9, 3)])
        q[1] = rng.uniform(-1.2, 1.2)
        if model.obstacle_gap(q, 1, "floor")[0] < 0.02:
            continue
        omega, dq, move = rng.normal(size=3), rng.normal(size=model.nq), rng.normal(size=3)
        dp = np.zeros(len(model.p))
        dp[point] = move
        dp[normal] = np.cross(omega, model.p[normal])
        code, dgap, g, dg = normal_tangent(model, q, c, dq, dp)
        assert code == model.lib.GAC_OK

        def at(h):
            p = model.p.copy()
            p[point] += h * move
            p[normal] = rotated(model.p[normal], omega, h * np.linalg.norm(omega))
            return np.concatenate([[model.contact_gaps(q + h * dq, p)[c]], model.contact_normal(q + h * dq, c, p)])

        fd = central(at)
        assert abs(dgap - fd[0]) <= 1e-9 * max(1.0, abs(fd[0]))
        assert np.abs(dg - fd[1:]).max() <= 1e-9 * max(1.0, np.abs(fd[1:]).max())
        assert abs(dgap - (dq @ g + move @ -model.p[normal])) > 1e-6     # the turn's part is there
        checked += 1
    dp = np.zeros(len(model.p))
    dp[normal] = model.p[normal]                                     # along n itself: a stretch
    assert normal_tangent(model, q, c, np.zeros(model.nq), dp)[0] == model.lib.GAC_ERR_BAD_OPTION


def test_a_box_rotation_or_a_plane_normal_is_refused_by_the_c_functions(model):
    """gac_contact_normal_tangent along a box's rotation entry or a plane's normal entry: GAC_ERR_BAD_OPTION, as
    gac_sens_attach's seeds along them (simulate() refuses them by name: tests/test_sim_obstacle_params.py)."""
    q = np.array([0.0, 0.3, 0.2, 6.0, 1.2, 0.0])
    labels = [contact.name for _, contact in model.contacts]
    for c, name in ((labels.index("L1/ridge"), "rotation_21_ridge"), (labels.index("O2/ridge"), "rotation_21_ridge"),
                    (labels.index("O1/floor"), "normal_y_floor")):
        dp = np.zeros(len(model.p))
        dp[model.parameter_names.index(name)] = 1.0
        assert normal_tangent(model, q, c, np.zeros(model.nq), dp)[0] == model.lib.GAC_ERR_BAD_OPTION
    with pytest.raises(ValueError, match=r"'rotation_21_ridge': a box's rotation entry or a plane's normal entry"):
        simulate(model, 0.1, sensitivities=["radius_ball", "rotation_21_ridge"])


# (obstacle, O_1's X1, X2, the rod's tilt from the horizontal (O_2 lower), X3, the closest point on the rod)
STRIKES = {
    "ball": ("ball", 0.65, 1.0, 0.15, 0.0, "inside"),                 # inside its length, off its centre of mass
    "bar": ("bar", 3.6, 0.8, 0.1, 0.05, "inside"),                    # across the bar: both fractions inside
    "edge": ("ridge", 6.785, 0.738, 0.0, 0.1, "inside"),              # level, across the ridge's top edge
    "corner": ("ridge", 6.785, 0.738, 0.0, 0.51, "inside"),          # level, onto the top edge's end (a corner)
    "face": ("ridge", 6.2 + math.cos(0.3), 0.583 + math.sin(0.3), 0.3, 0.05, "end"),   # O_2 onto the ridge's face
    "floor": ("floor", 0.5, -4.5, 0.2, 0.1, "end"),                   # O_2 onto the slanted floor
}


@pytest.mark.parametrize("case", STRIKES)
def test_a_rod_striking_an_obstacle_matches_central_differences_along_its_geometry(model, case):
    """The rod dropped from rest strikes the obstacle once (e = 0.6): the sensitivities are carried through (valid,
    the impact differentiated) and the final state's at T = 0.25 s and the impact time's along each of the
    obstacle's geometry parameters (and q0[X2]) match central differences of whole runs (step 1e-6; the same impacts
    across the stencil) to 1e-6 of their size (seen 1e-10-1.4e-8 for the state, ~1e-10 for the time)."""
    name, x1, x2, tilt, x3, where = STRIKES[case]
    q0, qd0 = np.array([-math.pi / 2, 0.0, math.pi / 2 + tilt, x1, x2, x3]), np.zeros(6)
    p = model.parameters({f"e_{name}": 0.6})
    directions, t_end, step = geometry(name) + ["q0[X2]"], 0.25, 1e-6
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    sequence = [[c.label for c in i.contacts] for i in r.impacts]
    struck = f"O2/{name}" if where == "end" else f"L1/{name}"      # an end strikes: its joint point's contact
    assert r.success and sequence == [[struck]], r.message
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    impact = r.impacts[0]
    s = model.obstacle_gap(model.layout.reduce(impact.q), 1, name)[1]
    assert (0.0 < s < 1.0) == (where == "inside")

    def run(direction, h):
        p1, q1, qd1 = perturbed_start(model, direction, h, p, q0, qd0)
        other = simulate(model, t_end, p=p1, q0=q1, qd0=qd1, **TIGHT)
        assert other.success and [[c.label for c in i.contacts] for i in other.impacts] == sequence, direction
        final = np.concatenate([model.layout.reduce(other.q_final), model.layout.reduce(other.qd_final)])
        return final, other.impacts[0].t

    moved = 0
    for j, direction in enumerate(directions):
        (x_plus, t_plus), (x_minus, t_minus) = run(direction, step), run(direction, -step)
        fd, fd_t = (x_plus - x_minus) / (2 * step), (t_plus - t_minus) / (2 * step)
        column = r.sensitivities.matrix[:, j]
        assert np.abs(fd - column).max() <= 1e-6 * max(1.0, np.abs(fd).max()), direction
        assert abs(impact.dt_dp[direction] - fd_t) <= 1e-6 * max(1.0, abs(fd_t)), direction
        moved += abs(fd_t) > 1e-2
    assert moved >= 2                                               # the strike's time moves with the obstacle


def slope_model(friction: float, specialise: bool = True):
    """A free rod of 1 m (capsule radius 0.02 m) above a plane slope through the origin tilted 0.3 rad (e 0.7, its
    friction a parameter where not 0)."""
    n = (-math.sin(0.3), math.cos(0.3), 0.0)
    slope = Obstacle.plane("slope", (0.0, 0.0, 0.0), n, restitution=0.7, friction=friction)
    scene = Scene(name=f"sens_turn_slope{'_rough' if friction else ''}", links=(LineLink(1.0, 1.0, radius=R_LINK),),
                  gravity=9.81, q0=(-math.pi / 2, 0.0, math.pi / 2 + 0.4, 0.3, 0.8, 0.0), obstacles=(slope,))
    return load_model(scene, tangent=True, specialise=specialise)


@pytest.mark.parametrize("friction, specialise, e, t_end", [
    (0.0, True, 0.7, 0.8), (0.0, False, 0.7, 0.8), (0.3, True, 0.7, 0.8), (0.0, True, 0.0, 0.6),
    (0.3, True, 0.0, 0.6)])
def test_a_slopes_turn_is_a_direction_of_a_whole_run(friction, specialise, e, t_end):
    """The rod dropped onto the slope: bouncing on it (e = 0.7: five impacts by 0.8 s), in the plane and in 3D (its
    turn about X1 too), smooth and rough (c_f 0.3, the frame's rows turning with the normal), and landing on it and
    held there (e = 0: on its lower end, pivoting down, then on both ends from 0.364 s, sliding down lying on it, a
    line contact, to 0.6 s); the final state's sensitivities along the slope's turn about X3 (its tilt), its point's
    height and the start against central differences of whole runs with the normal turned by the step
    (tests/conftest.perturbed_start)."""
    model = slope_model(friction, specialise)
    p = model.parameters({"e_slope": e})
    q0, qd0 = np.array(model.scene.q0, dtype=float), np.zeros(6)
    directions = ["turn_z_slope", "point_y_slope", "q0[X2]"] + (["e_slope"] if e > 0 else [])
    directions += [] if specialise else ["turn_x_slope", "turn_y_slope"]
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **TIGHT)
    assert r.success and r.impacts and r.sensitivities.valid, r.sensitivity_message
    assert (e > 0) == (len(r.impacts) >= 5) and (e > 0) != any(ev.kind == "rest" for ev in r.contact_events)
    assert abs(r.impacts[0].dt_dp["turn_z_slope"]) > 0.1
    from tests.test_sim_sensitivities import central_differences
    central_differences(model, t_end, p, q0, qd0, directions, r.sensitivities.matrix, **TIGHT)


def test_a_turn_is_named_and_a_normal_entry_still_refused(model):
    """turn_x_floor seeds dn = e_x x n on the floor's normal entries (at the run's normal); a normal entry alone is
    refused, the message naming the turns; a turn of an obstacle that is not a plane is unknown."""
    from runtime.sensitivities import directions
    names, _, seed_p = directions(model, ["turn_x_floor", "turn_z_floor"])
    normal = [model.parameter_names.index(f"normal_{x}_floor") for x in "xyz"]
    assert np.allclose(seed_p[0, normal], np.cross([1.0, 0.0, 0.0], FLOOR_N), atol=1e-15)
    assert np.allclose(seed_p[1, normal], np.cross([0.0, 0.0, 1.0], FLOOR_N), atol=1e-15)
    assert np.count_nonzero(seed_p) == 4                           # (e_x x n has no X1 part, e_z x n no X3 part)
    with pytest.raises(ValueError, match=r"'normal_y_floor': .* a plane's normal turns about the box axes "
                                         r"\(turn_x_<plane>, turn_y_<plane>, turn_z_<plane>\)"):
        directions(model, ["normal_y_floor"])
    with pytest.raises(ValueError, match=r"'turn_x_ball': unknown direction; allowed: .*turn_z_floor"):
        directions(model, ["turn_x_ball"])
