"""Forward sensitivities through an impact the law solves in several rounds (gac_sens.c, gac_sens_rounds_at: the impact
map qd+ = R_K(...R_1(qd-)) at fixed q, each round the law on its own active set, differentiated as the chain of the
rounds' differentials), frictionless and frictional (GDI).

A rod (1 m, 1 kg, its centre of mass at its middle) turns in the plane as it falls: its end O_1 strikes the floor
x2_min while its other end O_2, up and to the left, has just passed its closest approach to the wall x1_min (4e-6 m
from it, leaving it at 1e-3 m/s: the rod's turn carries O_2 along a curve that bends away from that wall).  The
floor's impulse at O_1 turns the rod so that O_2 is driven into the wall: round 2 strikes O_2 there, whose impulse
drives O_1 back into the floor: round 3.  The start is the state at the strike carried back 0.05 s along the free
flight (the centre of mass on its parabola, the rod turning at a constant rate).  The final state's sensitivities to
the initial state, g, the rod's length and inertia and both walls' restitutions against central differences of
whole runs with the same impact and the same rounds across the stencil.  With friction on both walls (GDI) the same
strike takes three rounds with both ends sliding on the cone (c_f = 0.3), four with both stuck (c_f = 3), or four
with the two mixed (c_f = 1); the friction coefficients join the directions.

With a small moment of inertia about the joint axis (Izz 1/400 of the rod's m (L/2)^2) and the rod at 45 degrees,
each end's impulse drives the other end into its wall almost as fast as it arrived (the rows' coupling in the mass
metric 0.995): the approach speeds of the rounds shrink by 0.99 a round, so GAC_MAX_ROUNDS rounds end in the
plastic round (record.plastic), which leaves both ends at rest, held.

The paths off the strike's: with both walls rough, the friction coefficient (common to both) where one end's impulse
in one of the rounds just leaves the cone's edge (found by bisection) puts that end at the stick/slide boundary inside
the impact, which ends the sensitivities there (a mode boundary naming the impact and the end), as does, frictionless,
the restitution where the upper end leaves a round at rest (the rounds' count changing); with a rest height of
0.1 m the lower end lands (struck with e = 0, its wall's e not read: the sensitivities' re-run of the rounds takes e =
0 for it after the wall's e does not reproduce them) in an impact of two rounds; and with the side wall replaced by a
plane obstacle at the same place (a link on an obstacle: its row J^T n, no Jacobian row) the strike takes the same
three rounds, and rough (its frame's row J^T t1 in each round's frictional law) three or four.  The last three against
central differences."""
from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import Obstacle, RigidLink, Scene, Wall
from conftest import perturbed_start
from runtime import simulate

OPTIONS = dict(rtol=1e-12, atol=1e-14, contact_tol=1e-5)
L, G = 1.0, 9.81
T_STRIKE = 0.05      # s: O_1 reaches the floor
GAP = 4e-6           # m: O_2's gap to the wall x1_min then
LEAVING = 1e-3       # m/s: O_2's rate away from that wall then
DIRECTIONS = ["q0[X1]", "q0[X2]", "q0[theta_1]", "qd0[X1]", "qd0[X2]", "qd0[theta_1]", "e_x2_min", "e_x1_min", "g",
              "l_1", "Izz_1"]
FRICTIONLESS = {"friction_x2_min": 0.0, "friction_x1_min": 0.0}


def strike_start(phi: float, rate: float):
    """(q0, qd0, wall): the rod at elevation phi (O_2 above and left of O_1) with O_1 on the floor at the origin
    falling at 1 m/s, turning at `rate` (rad/s), O_2 GAP from the wall x1_min (its position, `wall`) and leaving it
    at LEAVING, carried back T_STRIKE along the free flight.  O_1 is the base point (X1, X2); O_1 -> O_2 is
    L (-sin theta, cos theta) with theta the turning coordinate (full layout: theta_2)."""
    theta = math.pi / 2 - phi
    along = lambda t: np.array([-math.sin(t), math.cos(t)])              # O_1 -> O_2 / L
    turn = lambda t: np.array([-math.cos(t), -math.sin(t)])              # d along / d theta
    v1 = np.array([LEAVING + rate * L * math.sin(phi), -1.0])           # O_2's X1 rate: v1_x - rate L sin(phi)
    centre, v_centre = L / 2 * along(theta), v1 + L / 2 * rate * turn(theta)
    gravity = np.array([0.0, -G])
    theta0 = theta - rate * T_STRIKE
    centre0 = centre - v_centre * T_STRIKE + 0.5 * gravity * T_STRIKE ** 2
    v_centre0 = v_centre - gravity * T_STRIKE
    o1, v_o1 = centre0 - L / 2 * along(theta0), v_centre0 - L / 2 * rate * turn(theta0)
    wall = L * along(theta)[0] - GAP
    return (np.array([-math.pi / 2, 0.0, theta0, o1[0], o1[1], 0.0]),
            np.array([0.0, 0.0, rate, v_o1[0], v_o1[1], 0.0]), wall)


def rod_scene() -> Scene:
    """The rod as a rigid link (its inertia a parameter: Ixx small, Iyy = Izz = m L^2 / 12 by default), the floor
    (e = 0.5) and the wall x1_min (e = 0.7), both rough (c_f = 0.3, a parameter: 0 for the frictionless law), placed
    for the three-round strike at elevation 0.5 rad, turning at 2 rad/s."""
    q0, qd0, wall = strike_start(0.5, 2.0)
    inertia = L ** 2 / 12
    return Scene(name="sens_rounds",
                 links=(RigidLink(L, 1.0, (L / 2, 0.0, 0.0), ((1e-3, 0, 0), (0, inertia, 0), (0, 0, inertia))),),
                 walls=(Wall("x2_min", 0.0, 0.5, friction=0.3), Wall("x1_min", wall, 0.7, friction=0.3)),
                 q0=tuple(q0), qd0=tuple(qd0), gravity=G)


@pytest.fixture(scope="module")
def model(compiled):
    """The rod (rod_scene) with the tangent kernels."""
    return compiled(rod_scene(), tangent=True)


def plastic_start(model):
    """(p, q0, qd0) of the strike closed by the plastic round: 45 degrees, Izz = m (L/2)^2 / 400, e = 0.3 on both
    walls, frictionless."""
    q0, qd0, wall = strike_start(math.pi / 4, 2.0)
    izz = 0.25 / 400
    p = model.parameters({"Izz_1": izz, "Iyy_1": izz, "Ixx_1": 1e-5, "wall_x1_min": wall, "e_x2_min": 0.3,
                          "e_x1_min": 0.3, **FRICTIONLESS})
    return p, q0, qd0


def sequence(run):
    """The run's impacts as (contacts, rounds, plastic)."""
    return [(tuple(c.label for c in i.contacts), i.rounds, i.plastic) for i in run.impacts]


def contact_events(run):
    """The run's contact events as (contact, kind)."""
    return [(e.label, e.kind) for e in run.contact_events]


def check_central_differences(model, t_end, p, q0, qd0, directions, matrix, step=1e-6, options=OPTIONS):
    """Each column of d x(t_end) / d direction against a central difference of the final state, to 1e-6 of the
    column's size (at least 1): the perturbed runs meet the same impacts with the same rounds and the same contact
    events as the nominal one."""
    run = simulate(model, t_end, p=p, q0=q0, qd0=qd0, **options)
    nominal = (sequence(run), contact_events(run))

    def final(h, direction):
        p1, q1, qd1 = perturbed_start(model, direction, h, p, q0, qd0)
        run = simulate(model, t_end, p=p1, q0=q1, qd0=qd1, **options)
        assert run.success and (sequence(run), contact_events(run)) == nominal, (direction, h, sequence(run))
        return np.concatenate([model.layout.reduce(run.q_final), model.layout.reduce(run.qd_final)])

    for j, direction in enumerate(directions):
        fd = (final(step, direction) - final(-step, direction)) / (2 * step)
        assert np.abs(fd - matrix[:, j]).max() <= 1e-6 * max(1.0, np.abs(fd).max()), direction


def test_an_impact_of_three_rounds_matches_central_differences(model):
    """O_1 on the floor, then O_2 on the wall, then O_1 again: three rounds, each with its own active contact and
    restitution; the sensitivities carried through (valid, one impact) match central differences at 0.07 s."""
    t_end = 0.07
    q0, qd0, p = np.array(model.scene.q0), np.array(model.scene.qd0), model.parameters(FRICTIONLESS)
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **OPTIONS)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/x1_min"), 3, False)] and r.impacts[0].law == "frictionless"
    impact = r.impacts[0]
    assert impact.t == pytest.approx(T_STRIKE, abs=1e-12)
    assert all(c.impulse > 0.1 for c in impact.contacts)
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    assert all(math.isfinite(v) for v in impact.dt_dp.values())
    check_central_differences(model, t_end, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix)


def test_an_impact_closed_by_the_plastic_round_matches_central_differences(model):
    """At 45 degrees with Izz = m (L/2)^2 / 400 and e = 0.3 on both walls the rounds alternate between the two ends
    until GAC_MAX_ROUNDS, then the plastic round leaves both at rest (held after it): 257 rounds chained, against
    central differences shortly after (the rod then slides down the corner, both ends held)."""
    t_end = 0.055
    p, q0, qd0 = plastic_start(model)
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **OPTIONS)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/x1_min"), 257, True)]
    assert sorted((e.point, e.wall, e.kind) for e in r.contact_events) == [(1, "x2_min", "rest"), (2, "x1_min", "rest")]
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    check_central_differences(model, t_end, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix)


@pytest.mark.parametrize("friction,rounds,modes", [(0.3, 3, ("slides", "slides")), (1.0, 4, ("mixed", "mixed")),
                                                   (3.0, 4, ("stuck", "stuck"))])
def test_an_impact_of_several_frictional_rounds_matches_central_differences(model, friction, rounds, modes):
    """The three-round strike on rough walls (GDI): each round's law takes its rough contact's tangential rows, stuck
    (gamma+_T + e gamma-_T = 0) or sliding on the cone; the ends' total impulses on their cones where they slide in
    every round (c_f = 0.3), well inside where they stick in every round (c_f = 3; their friction's derivatives 0), not
    asserted where the rounds mix the two (c_f = 1); the sensitivities, both friction coefficients among the
    directions, against central differences."""
    t_end = 0.07
    q0, qd0 = np.array(model.scene.q0), np.array(model.scene.qd0)
    p = model.parameters({"friction_x2_min": friction, "friction_x1_min": friction})
    directions = DIRECTIONS + ["friction_x2_min", "friction_x1_min"]
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **OPTIONS)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/x1_min"), rounds, False)] and r.impacts[0].law == "gdi"
    for contact, mode in zip(r.impacts[0].contacts, modes):
        ratio = math.hypot(*contact.impulse_t) / (friction * contact.impulse)
        if mode != "mixed":
            assert (ratio == pytest.approx(1.0, abs=1e-9)) if mode == "slides" else ratio < 0.9, (contact.label, ratio)
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    check_central_differences(model, t_end, p, q0, qd0, directions, r.sensitivities.matrix)


def ratios(run, friction: float) -> list[float]:
    """|L_T| / (c_f L_N) of each contact of the run's first impact: 1 where it slid in every round."""
    return [math.hypot(*c.impulse_t) / (friction * c.impulse) for c in run.impacts[0].contacts]


@pytest.mark.parametrize("end,low,high", [("O2/x1_min", 0.8, 0.9), ("O1/x2_min", 0.9, 1.0)])
def test_a_round_at_the_stick_slide_boundary_ends_the_sensitivities(model, end, low, high):
    """Between c_f = 0.8 and 0.9 (the upper end) and 0.9 and 1.0 (the lower end) an end that slides in every round
    at the lower c_f sticks in one of them at the higher: its total impulse leaves its cone.  Bisected to where it
    does (the ratio |L_T| / (c_f L_N) below 1 by more than 1e-12), c_f 1e-9 above that point puts the end in that
    round on the cone's edge with xi_T = 0: the round's set is not strict there and the sensitivities end at the
    impact with a mode boundary (status 10) naming that end; 1e-6 below it, clear of the boundary, they are carried
    through."""
    t_end = T_STRIKE + 5e-4
    q0, qd0 = np.array(model.scene.q0), np.array(model.scene.qd0)
    index = ["O1/x2_min", "O2/x1_min"].index(end)

    def run(friction, sensitivities=None):
        p = model.parameters({"friction_x2_min": friction, "friction_x1_min": friction})
        r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=sensitivities, **OPTIONS)
        assert r.success and [s[0] for s in sequence(r)] == [("O1/x2_min", "O2/x1_min")], r.message
        return r

    assert ratios(run(low), low)[index] == pytest.approx(1.0, abs=1e-12)
    assert ratios(run(high), high)[index] < 1.0 - 1e-3
    while high - low > 1e-14:
        middle = 0.5 * (low + high)
        if ratios(run(middle), middle)[index] > 1.0 - 1e-12:
            low = middle
        else:
            high = middle
    at = run(high * (1.0 + 1e-9), DIRECTIONS)
    assert at.impacts[0].rounds in (3, 4) and at.impacts[0].law == "gdi"
    s = at.sensitivities
    assert s.code == 10 and "mode boundary" in s.message and f"at {end}" in s.message, s.message
    assert s.t_event == pytest.approx(T_STRIKE, abs=1e-12) and np.isnan(s.matrix).all()
    clear = run(low * (1.0 - 1e-6), DIRECTIONS)
    assert clear.sensitivities.valid and clear.sensitivities.n_impacts == 1, clear.sensitivity_message


def test_a_landing_in_an_impact_of_two_rounds_matches_central_differences(model):
    """With rest_height 0.1 m the lower end's bounce (0.5 m/s, rising 1.3 cm) counts as a landing: it is struck with
    e = 0 and held after, the upper end struck by the wall in round 2; the sensitivities' re-run of the rounds with
    the floor's e = 0.5 does not reproduce them, the re-run with e = 0 for the landed end does, and the
    sensitivities (e_x2_min's column 0: a landing's e is not read) match central differences."""
    t_end = 0.07
    options = dict(OPTIONS, rest_height=0.1)
    q0, qd0, p = np.array(model.scene.q0), np.array(model.scene.qd0), model.parameters(FRICTIONLESS)
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **options)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/x1_min"), 2, False)]
    assert contact_events(r) == [("O1/x2_min", "rest")]
    assert r.contact_events[0].t == pytest.approx(T_STRIKE, abs=1e-12)
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    assert np.abs(r.sensitivities.matrix[:, DIRECTIONS.index("e_x2_min")]).max() == 0.0
    check_central_differences(model, t_end, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, options=options)


@pytest.fixture(scope="module")
def plane_model(compiled):
    """The frictionless rod of `model` with the side wall replaced by a plane obstacle "side" at the same place
    (normal +X1, e = 0.7): the upper end's contact a joint point on an obstacle (O2/side)."""
    q0, qd0, wall = strike_start(0.5, 2.0)
    inertia = L ** 2 / 12
    scene = Scene(name="sens_rounds_plane",
                  links=(RigidLink(L, 1.0, (L / 2, 0.0, 0.0), ((1e-3, 0, 0), (0, inertia, 0), (0, 0, inertia))),),
                  walls=(Wall("x2_min", 0.0, 0.5),),
                  obstacles=(Obstacle.plane("side", (wall, 0.0, 0.0), (1.0, 0.0, 0.0), restitution=0.7),),
                  q0=tuple(q0), qd0=tuple(qd0), gravity=G)
    return compiled(scene, tangent=True)


def test_an_impact_of_three_rounds_on_an_obstacle_matches_central_differences(plane_model):
    """The three-round strike with the link on the plane obstacle in round 2 (its row J^T n and its derivative by
    the closest point's motion, e_side its restitution): carried through and against central differences."""
    model, t_end = plane_model, 0.07
    directions = [d if d != "e_x1_min" else "e_side" for d in DIRECTIONS]
    q0, qd0, p = np.array(model.scene.q0), np.array(model.scene.qd0), model.parameters({})
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **OPTIONS)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/side"), 3, False)] and r.impacts[0].law == "frictionless"
    assert all(c.impulse > 0.1 for c in r.impacts[0].contacts)
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    check_central_differences(model, t_end, p, q0, qd0, directions, r.sensitivities.matrix)


@pytest.fixture(scope="module")
def rough_plane_model(compiled):
    """`plane_model` with friction at both contacts: the floor's c_f and the plane's (friction_side) parameters."""
    q0, qd0, wall = strike_start(0.5, 2.0)
    inertia = L ** 2 / 12
    scene = Scene(name="sens_rounds_rough_plane",
                  links=(RigidLink(L, 1.0, (L / 2, 0.0, 0.0), ((1e-3, 0, 0), (0, inertia, 0), (0, 0, inertia))),),
                  walls=(Wall("x2_min", 0.0, 0.5, friction=0.3),),
                  obstacles=(Obstacle.plane("side", (wall, 0.0, 0.0), (1.0, 0.0, 0.0), restitution=0.7,
                                            friction=0.3),),
                  q0=tuple(q0), qd0=tuple(qd0), gravity=G)
    return compiled(scene, tangent=True)


@pytest.mark.parametrize("friction,rounds", [(0.3, 3), (1.0, 4), (3.0, 4)])
def test_frictional_rounds_on_a_rough_obstacle_match_central_differences(rough_plane_model, friction, rounds):
    """The several-round frictional strike with the side a rough plane obstacle: each round's law takes the link's
    frame row J^T t1 on the plane (its t2, which no motion of the planar model takes, left out as the law leaves it),
    stuck or sliding, its derivative the frame's turning and the closest point's motion (gac_sens_law.frame); both
    friction coefficients among the directions, against central differences."""
    model, t_end = rough_plane_model, 0.07
    directions = [d if d != "e_x1_min" else "e_side" for d in DIRECTIONS] + ["friction_x2_min", "friction_side"]
    q0, qd0 = np.array(model.scene.q0), np.array(model.scene.qd0)
    p = model.parameters({"friction_x2_min": friction, "friction_side": friction})
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=directions, **OPTIONS)
    assert r.success, r.message
    assert sequence(r) == [(("O1/x2_min", "O2/side"), rounds, False)] and r.impacts[0].law == "gdi"
    assert abs(r.impacts[0].contacts[1].impulse_t[0]) > 0.01
    assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, r.sensitivity_message
    check_central_differences(model, t_end, p, q0, qd0, directions, r.sensitivities.matrix)


def test_an_end_at_rest_between_rounds_ends_the_sensitivities(model):
    """Frictionless, with e = 0.1 on the side wall: at e_x2_min = 0.3 the strike takes four rounds (the upper end
    struck again in the fourth), at 0.4 three; bisected to where the count changes, the upper end leaves round 3 at
    rest (normal velocity ~0 after it).  On the side of four rounds it meets round 4 at ~0, on the side of three the
    last round leaves it at ~0, unheld: either way the sensitivities end at the impact with a mode boundary (status
    10) naming that end; 1e-6 (relative) to either side they are carried through."""
    t_end = T_STRIKE + 5e-4
    q0, qd0 = np.array(model.scene.q0), np.array(model.scene.qd0)

    def run(e_floor, sensitivities=None):
        p = model.parameters({**FRICTIONLESS, "e_x2_min": e_floor, "e_x1_min": 0.1})
        r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=sensitivities, **OPTIONS)
        assert r.success and [s[0] for s in sequence(r)] == [("O1/x2_min", "O2/x1_min")], r.message
        return r

    low, high = 0.3, 0.4
    assert run(low).impacts[0].rounds == 4 and run(high).impacts[0].rounds == 3
    while high - low > 1e-15:
        middle = 0.5 * (low + high)
        if run(middle).impacts[0].rounds == 4:
            low = middle
        else:
            high = middle
    for e_floor, rounds in ((low, 4), (high, 3)):
        r = run(e_floor, DIRECTIONS)
        assert sequence(r) == [(("O1/x2_min", "O2/x1_min"), rounds, False)] and not r.contact_events
        s = r.sensitivities
        assert s.code == 10 and "mode boundary" in s.message and "at O2/x1_min" in s.message, (rounds, s.message)
        assert s.t_event == pytest.approx(T_STRIKE, abs=1e-12) and np.isnan(s.matrix).all()
    for e_floor in (low * (1.0 - 1e-6), high * (1.0 + 1e-6)):
        r = run(e_floor, DIRECTIONS)
        assert r.sensitivities.valid and r.sensitivities.n_impacts == 1, (e_floor, r.sensitivity_message)


def test_the_stack_of_257_rounds_fits_a_small_thread(model):
    """The strike closed by the plastic round (257 rounds chained) with sensitivities, run in a thread of 64 kB of
    stack (below musl's 128 kB default for threads): the sensitivities keep only the rounds' trace (9.3 kB here) and
    one round's law at a time, so their stack does not grow with the rounds (docs/generated-c.md, the stack table).
    In a child process, where an overflow ends only the child."""
    tests = Path(__file__).resolve().parent
    script = textwrap.dedent(f"""
        import sys, threading
        sys.path[:0] = [{str(tests.parent)!r}, {str(tests)!r}]
        from runtime import load_model, simulate
        import test_sim_sensitivities_rounds as T
        model = load_model(T.rod_scene(), tangent=True)
        p, q0, qd0 = T.plastic_start(model)
        def run():
            r = simulate(model, 0.055, p=p, q0=q0, qd0=qd0, sensitivities=T.DIRECTIONS, **T.OPTIONS)
            print(r.impacts[0].rounds, r.sensitivities.valid)
        threading.stack_size(64 * 1024)
        thread = threading.Thread(target=run)
        thread.start()
        thread.join()
    """)
    child = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert child.returncode == 0 and child.stdout.split() == ["257", "True"], (child.returncode, child.stderr[-2000:])
