"""Forward sensitivities of a whole hybrid run (simulate(sensitivities=...), gac_sens.c): against closed forms of a
vertical rod striking a floor (with and without gravity: the final state's and the impact times' derivatives by
the initial height, speed, restitution, the floor's position and g), against central finite differences of random
3D chains bouncing in a box (the same event sequence across the stencil asserted), and the verdict where the run
meets an event the loop does not differentiate.  Resting contact: tests/test_sim_sensitivities_rest.py."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from codegen.scene import Joint, coordinate_names, scene_from_dict
from conftest import chain, perturbed_start
from runtime import simulate

TIGHT = dict(rtol=1e-12, atol=1e-14)


def rod_scene(gravity: float, e: float, h0: float, v0: float, friction: float = 0.0):
    """A vertical uniform rod (a line link, 1 m) above the floor x2_min = 0, O_1 its lower end at height h0, moving
    at v0 along X2: an impact at O_1 has its impulse through the centre of mass, so the rod never turns."""
    walls = {"x2_min": 0.0}
    return scene_from_dict({"name": "sens_rod", "gravity": gravity,
                            "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}],
                            "walls": walls, "restitution": e, "friction": friction,
                            "initial": {"q": [-math.pi / 2, 0.0, 0.0, 0.0, h0, 0.0],
                                        "qd": [0.0, 0.0, 0.0, 0.0, v0, 0.0]}})


E, U, H0, T = 0.7, 2.0, 0.5, 0.6


@pytest.fixture(scope="module")
def free_rod(compiled):
    return compiled(rod_scene(0.0, E, H0, -U), specialise=True, tangent=True)


def test_rod_without_gravity_matches_the_closed_form(free_rod):
    """g = 0, speed U down from H0: one bounce at t* = H0/U, then h(T) = e (U T - H0) and qd(T) = e U, so
    dh/dh0 = -e, dh/dqd0 = -e T (qd0 = -U), dh/de = U T - H0, dh/d(floor) = 1 + e; dt*/dh0 = 1/U, dt*/dqd0 = H0/U^2."""
    names = ["q0[X2]", "qd0[X2]", "e_x2_min", "wall_x2_min"]
    r = simulate(free_rod, T, sensitivities=names, **TIGHT)
    assert r.success and len(r.impacts) == 1
    s = r.sensitivities
    assert s.valid and r.sensitivity_status == "valid" and s.n_impacts == 1
    assert s.matrix.shape == (2 * free_rod.nq, 4)
    expected = {("q[X2]", "q0[X2]"): -E, ("q[X2]", "qd0[X2]"): -E * T, ("q[X2]", "e_x2_min"): U * T - H0,
                ("q[X2]", "wall_x2_min"): 1 + E, ("qd[X2]", "q0[X2]"): 0.0, ("qd[X2]", "qd0[X2]"): -E,
                ("qd[X2]", "e_x2_min"): U, ("qd[X2]", "wall_x2_min"): 0.0}
    for key, value in expected.items():
        assert s[key] == pytest.approx(value, abs=1e-8), key
    for row in ("q[theta_1]", "q[X1]", "qd[theta_1]", "qd[X1]"):      # nothing turns or drifts
        assert np.allclose([s[row, d] for d in names], 0.0, atol=1e-10)
    dt = r.impacts[0].dt_dp
    assert dt["q0[X2]"] == pytest.approx(1 / U, abs=1e-10)
    assert dt["qd0[X2]"] == pytest.approx(H0 / U ** 2, abs=1e-10)
    assert dt["e_x2_min"] == pytest.approx(0.0, abs=1e-12)
    assert dt["wall_x2_min"] == pytest.approx(-1 / U, abs=1e-10)


def test_the_saltation_term_is_what_gives_the_closed_form(free_rod):
    """Without the saltation term (f+ - D Delta f-) dt* the jump would be S+ = D Delta S-: for the initial height
    D Delta keeps dh = 1 and dqd = 0, so dh(T)/dh0 would stay 1; the closed form -e needs the term (it moves dh by
    -(1 + e) U dt*/dh0 = -(1 + e))."""
    s = simulate(free_rod, T, sensitivities=["q0[X2]"], **TIGHT).sensitivities
    without_saltation = 1.0
    assert s["q[X2]", "q0[X2]"] == pytest.approx(-E, abs=1e-8)
    assert abs(s["q[X2]", "q0[X2]"] - without_saltation) > 1.0


def falling_rod(compiled):
    """The rod under gravity (g = 9.81), dropped from rest: one model for every restitution and drop height (e_x2_min is
    in p, the height in q0; rod_start)."""
    return compiled(rod_scene(9.81, E, H0, 0.0), specialise=True, tangent=True)


def rod_start(model, h0: float) -> np.ndarray:
    """The rod's start (full layout) with its lower end at height h0."""
    q0 = np.array(model.scene.q0)
    q0[coordinate_names(model.n).index("X2")] = h0
    return q0


def test_bouncing_rod_impact_times_match_the_closed_form(compiled):
    """Dropped from rest at h0 under g: t1 = sqrt(2 h0 / g), t2 = t1 (1 + 2 e), so dt1/dh0 = t1 / (2 h0),
    dt1/dg = -t1 / (2 g), dt1/de = 0, dt2 = (1 + 2 e) dt1 along h0 and g, dt2/de = 2 t1."""
    e, h0, g = 0.8, 1.0, 9.81
    model = falling_rod(compiled)
    p, q0 = model.parameters({"e_x2_min": e}), rod_start(model, h0)
    t1 = math.sqrt(2 * h0 / g)
    t2 = t1 * (1 + 2 * e)
    r = simulate(model, t2 + 0.05, p=p, q0=q0, sensitivities=["q0[X2]", "e_x2_min", "g"], **TIGHT)
    assert r.success and len(r.impacts) == 2 and r.sensitivities.valid
    first, second = r.impacts[0].dt_dp, r.impacts[1].dt_dp
    assert r.impacts[0].t == pytest.approx(t1, rel=1e-10) and r.impacts[1].t == pytest.approx(t2, rel=1e-10)
    assert first["q0[X2]"] == pytest.approx(t1 / (2 * h0), rel=1e-8)
    assert first["g"] == pytest.approx(-t1 / (2 * g), rel=1e-8)
    assert first["e_x2_min"] == pytest.approx(0.0, abs=1e-10)
    assert second["q0[X2]"] == pytest.approx((1 + 2 * e) * t1 / (2 * h0), rel=1e-8)
    assert second["g"] == pytest.approx(-(1 + 2 * e) * t1 / (2 * g), rel=1e-8)
    assert second["e_x2_min"] == pytest.approx(2 * t1, rel=1e-8)


BOX = 3.0
DIRECTIONS = ["q0[theta_2]", "qd0[X1]", "qd0[theta_0]", "e_x1_min", "l_1", "g"]


def box_run(seed: int):
    """A twisted 3-link chain (slender, rigid, slender) thrown in a box of half-width BOX with g = 0 and random
    restitutions: (p, q0, qd0)."""
    rng = np.random.default_rng(seed)
    over = {"g": 0.0}
    for axis in ("x1", "x2", "x3"):
        over[f"wall_{axis}_min"], over[f"wall_{axis}_max"] = -BOX, BOX
        over[f"e_{axis}_min"], over[f"e_{axis}_max"] = rng.uniform(0.5, 1.0, 2)
    n = 3
    q0 = np.zeros(n + 5)
    q0[2:5] = rng.uniform(-0.5, 0.5, 3)
    q0[5:8] = -0.3
    qd0 = rng.normal(0, 2.0, n + 5)
    qd0[:2] *= 0.2                                   # slow base turns: far from the base chart's lock
    return over, q0, qd0


def central_differences(model, t_end, p, q0, qd0, directions, matrix, step=1e-6, **options):
    """Every column of d x(t_end)/d(direction) (``matrix``) against a central difference of the final state (step
    ``step``), to 1e-6 of the column's size (at least 1e-5: the difference's own noise, rtol / step times the
    state's size), where the perturbed runs meet the same impacts (each impact's contacts, in any order, the impacts
    in order) as the nominal one."""
    nominal = simulate(model, t_end, p=p, q0=q0, qd0=qd0, **options)
    sequence = [sorted(c.label for c in i.contacts) for i in nominal.impacts]

    def final(h, direction):
        p1, q1, qd1 = perturbed_start(model, direction, h, p, q0, qd0)
        run = simulate(model, t_end, p=p1, q0=q1, qd0=qd1, **options)
        assert run.success and [sorted(c.label for c in i.contacts) for i in run.impacts] == sequence, direction
        return np.concatenate([model.layout.reduce(run.q_final), model.layout.reduce(run.qd_final)])

    for j, direction in enumerate(directions):
        fd = (final(step, direction) - final(-step, direction)) / (2 * step)
        column = matrix[:, j]
        assert np.abs(fd - column).max() <= 1e-6 * max(10.0, np.abs(fd).max()), direction


@pytest.mark.parametrize("seed", [6, pytest.param(7, marks=pytest.mark.slow)])    # seed 7: five impacts, -m slow
def test_random_chains_in_a_box_match_central_differences(compiled, seed):
    """Several frictionless single-contact impacts: the final state's sensitivities against central differences."""
    model = compiled(stopped_chain(), tangent=True)
    over, q0, qd0 = box_run(seed)
    p = model.parameters(dict(over, **UNSTOPPED))
    t_end = 1.5
    r = simulate(model, t_end, p=p, q0=q0, qd0=qd0, sensitivities=DIRECTIONS, **TIGHT)
    assert r.success and len(r.impacts) >= 3, r.message
    assert r.sensitivities.valid, r.sensitivity_message
    assert all(len(i.contacts) == 1 for i in r.impacts)
    central_differences(model, t_end, p, q0, qd0, DIRECTIONS, r.sensitivities.matrix, **TIGHT)


def stopped_chain():
    """The box tests' twisted 3-link chain with stops at +-0.5 rad on both joints (restitution 0.6)."""
    scene = chain(3, ("line", "rigid"), twists=True)
    return dataclasses.replace(scene, joints=tuple(Joint(lower=-0.5, upper=0.5, limit_restitution=0.6)
                                                   for _ in range(2)))


# the stops moved out of reach: the box tests' chain as if it had none, on the stopped chain's model (one build)
UNSTOPPED = {"lower_2": -1e3, "upper_2": 1e3, "lower_3": -1e3, "upper_3": 1e3}

STOP_DIRECTIONS = ["q0[theta_2]", "qd0[theta_3]", "qd0[X2]", "e_limit_2", "upper_3", "e_x1_min", "l_1"]


# seed 6 (stops and single contacts only; seed 10 has both) with -m slow
@pytest.mark.parametrize("seed, contact_tol, several", [pytest.param(6, 1e-6, 0, marks=pytest.mark.slow), (10, 0.02, 3)])
def test_joint_stops_and_several_contacts_match_central_differences(compiled, seed, contact_tol, several):
    """Impacts at joint stops (a unit row, gap theta_k - limit) and, with a wide simultaneity window (contact_tol),
    impacts of several contacts at once (walls and stops together, Newton's law on the contacts that took an
    impulse, the set held fixed; one of seed 10's takes a contact with no impulse that leaves clear of it): the
    final state's sensitivities against central differences, the same impacts across the stencil.  No rule puts a
    contact at rest (rest_height = 0, zeno_impacts = 0).  (Step 1e-5: at
    1e-6 the difference's noise on this run's eleven events reaches 1e-6.)"""
    model = compiled(stopped_chain(), tangent=True)
    over, q0, qd0 = box_run(seed)
    q0[5:8] = 0.0
    p = model.parameters(over)
    options = dict(TIGHT, contact_tol=contact_tol, rest_height=0.0, zeno_impacts=0)
    r = simulate(model, 1.5, p=p, q0=q0, qd0=qd0, sensitivities=STOP_DIRECTIONS, **options)
    assert r.success and r.sensitivities.valid, r.sensitivity_message
    kinds = [c.kind for i in r.impacts for c in i.contacts]
    assert kinds.count("stop") >= 3 and kinds.count("wall") >= 2, kinds
    assert sum(len(i.contacts) > 1 for i in r.impacts) == several
    central_differences(model, 1.5, p, q0, qd0, STOP_DIRECTIONS, r.sensitivities.matrix, step=1e-5, **options)


def test_a_landing_is_differentiated(compiled):
    """A rod dropped with e = 0.05 bounces once, then lands (its next bounce below the rest height): both impacts
    and the resting contact after them are differentiated (tests/test_sim_sensitivities_rest.py checks the numbers);
    the landing's event carries its impact's time derivatives."""
    model = falling_rod(compiled)
    r = simulate(model, 0.5, p=model.parameters({"e_x2_min": 0.05}), q0=rod_start(model, 0.3),
                 sensitivities=["q0[X2]", "e_x2_min"])
    assert r.success
    s = r.sensitivities
    assert s.valid, s.message
    landing = [e for e in r.contact_events if e.kind == "rest"][0]
    assert landing.dt_dp == r.impacts[-1].dt_dp
    assert np.all(np.isfinite(s.matrix))
    assert r.impacts[0].t < landing.t and r.impacts[0].dt_dp["q0[X2]"] == pytest.approx(
        1 / math.sqrt(2 * 0.3 * 9.81), rel=1e-5)


def rough_rod(friction: float):
    """The rod tilted 0.7 rad from the vertical, thrown down and sideways and turning, onto a floor with e = 0.8 and
    the given Coulomb coefficient: it strikes with O_1, then O_2, then O_1 again within 0.5 s."""
    return scene_from_dict({"name": "sens_rough_rod", "gravity": 9.81,
                            "links": [{"length": 1.0, "mu": 1.0, "J": [0.0, 0.0, 0.0]}],
                            "walls": {"x2_min": 0.0}, "restitution": 0.8, "friction": friction,
                            "initial": {"q": [-math.pi / 2, 0.0, 0.7, 0.0, 0.3, 0.0],
                                        "qd": [0.0, 0.0, 1.5, 0.8, -1.0, 0.0]}})


def test_impacts_that_stick_on_a_rough_floor_match_central_differences(compiled):
    """c_f = 2: at each of the three impacts the struck end sticks (|L_T| < c_f L_N), so the frictional law is
    Newton's restitution along the normal and the tangent alike (xi = gamma+ + e gamma- = 0 on both rows): its
    saltation is the frictionless one with the tangential rows active.  Dropping them gives the frictionless law's
    derivative, which the differences refute."""
    model = compiled(rough_rod(2.0), specialise=True, tangent=True)
    names = ["q0[X2]", "qd0[X1]", "qd0[theta_1]", "e_x2_min", "g", "l_1"]
    r = simulate(model, 0.5, sensitivities=names, **TIGHT)
    assert r.success and len(r.impacts) == 3 and r.sensitivity_status == "valid"
    for impact in r.impacts:
        assert impact.law == "gdi"
        contact = impact.contacts[0]
        assert 0.0 < abs(contact.impulse_t[0]) < 2.0 * contact.impulse       # stuck, and friction at work
    p, q0, qd0 = model.p.copy(), np.array(model.scene.q0), np.array(model.scene.qd0)
    central_differences(model, 0.5, p, q0, qd0, names, r.sensitivities.matrix, **TIGHT)


def test_impacts_that_slide_on_a_rough_floor_match_central_differences(compiled):
    """A rod in 3D (J_xx > 0), tilted, turning and thrown sideways onto a floor with c_f = 0.3: four impacts, each
    struck end sliding (its impulse on the cone, L_T = -c_f L_N u, u the direction of xi_T over both tangential
    axes).  The slide's differential, dL_T + c_f u dL_N + c_f L_N Du d xi_T = -dc_f L_N u with
    Du = (I - u u^T) / |xi_T|, against central differences of seven directions, the friction coefficient among them;
    dropping Du (exact only with one tangential axis) fails it."""
    scene = scene_from_dict({"name": "sens_rough_rod3d", "gravity": 9.81,
                             "links": [{"length": 1.0, "mu": 1.0, "J": [0.01, 0.0, 0.0]}],
                             "walls": {"x2_min": 0.0}, "restitution": 0.6, "friction": 0.3,
                             "initial": {"q": [-math.pi / 2 + 0.3, 0.4, 0.7, 0.0, 0.3, 0.0],
                                         "qd": [0.5, -0.7, 1.5, 0.8, -1.0, 0.6]}})
    model = compiled(scene, specialise=True, tangent=True)
    names = ["q0[X2]", "qd0[X1]", "qd0[X3]", "qd0[theta_1]", "e_x2_min", "g", "friction_x2_min"]
    r = simulate(model, 0.5, sensitivities=names, **TIGHT)
    assert r.success and len(r.impacts) == 4 and r.sensitivity_status == "valid"
    for impact in r.impacts:
        contact = impact.contacts[0]
        assert impact.law == "gdi" and min(abs(t) for t in contact.impulse_t) > 0.0      # both tangents at work
        assert math.hypot(*contact.impulse_t) == pytest.approx(0.3 * contact.impulse, rel=1e-9)   # on the cone
    p, q0, qd0 = model.p.copy(), np.array(scene.q0), np.array(scene.qd0)
    central_differences(model, 0.5, p, q0, qd0, names, r.sensitivities.matrix, **TIGHT)


def test_a_sliding_impact_in_the_plane_matches_central_differences(compiled):
    """The planar rod on a floor with c_f = 0.2: three impacts, each sliding along the one tangential axis."""
    model = compiled(rough_rod(2.0), specialise=True, tangent=True)     # the rough rod's model, c_f = 0.2 through p
    p = model.parameters({"friction_x2_min": 0.2})
    names = ["q0[X2]", "qd0[X1]", "qd0[theta_1]", "e_x2_min", "friction_x2_min"]
    r = simulate(model, 0.5, p=p, sensitivities=names, **TIGHT)
    assert r.sensitivity_status == "valid" and len(r.impacts) == 3
    contact = r.impacts[0].contacts[0]
    assert abs(contact.impulse_t[0]) == pytest.approx(0.2 * contact.impulse, rel=1e-9)   # on the cone: sliding
    q0, qd0 = np.array(model.scene.q0), np.array(model.scene.qd0)
    central_differences(model, 0.5, p, q0, qd0, names, r.sensitivities.matrix, **TIGHT)


def test_sensitivities_at_the_samples_follow_the_closed_form(free_rod):
    """The rod without gravity at every 1 ms sample: h(t) = h0 + qd0 t before the bounce at t* = H0/U and
    e (U t - H0) after, so dh/dh0 = 1 then -e, dh/dqd0 = t then -e t, dh/de = 0 then U t - H0 (each sample's S formed
    by one more step of the directions from its step's start)."""
    names = ["q0[X2]", "qd0[X2]", "e_x2_min"]
    r = simulate(free_rod, T, sensitivities=names, sensitivities_at_samples=True, **TIGHT)
    at = r.sensitivities.at_samples
    assert at.shape == (len(r.t), 2 * free_rod.nq, 3)
    row = r.sensitivities.rows.index("q[X2]")
    before = r.t <= H0 / U + 1e-12                  # a sample at t* itself is the state just before the impact
    expected = np.where(before[:, None], np.stack([np.ones_like(r.t), r.t, 0 * r.t], axis=1),
                        np.stack([-E + 0 * r.t, -E * r.t, U * r.t - H0], axis=1))
    assert np.abs(at[:, row, :] - expected).max() < 1e-8
    assert np.array_equal(at[-1], r.sensitivities.matrix)                   # the last sample is t_end
    with pytest.raises(ValueError, match="sensitivities_at_samples: needs sensitivities"):
        simulate(free_rod, 0.1, sensitivities_at_samples=True)


def test_sensitivities_at_the_samples_match_central_differences_of_the_samples(compiled):
    """The rod thrown onto the rough floor (three stuck impacts, gravity, turning): S at every 10 ms sample against
    central differences of the samples themselves, for a coordinate, a velocity and a parameter."""
    model = compiled(rough_rod(2.0), specialise=True, tangent=True)
    names, samples, step = ["q0[X2]", "qd0[theta_1]", "g"], np.linspace(0.0, 0.5, 51), 1e-6
    r = simulate(model, 0.5, t_eval=samples, sensitivities=names, sensitivities_at_samples=True, **TIGHT)
    sequence = [i.t for i in r.impacts]
    full = coordinate_names(model.n)

    def trajectory(h, direction):
        q0, qd0, p = np.array(model.scene.q0), np.array(model.scene.qd0), model.p.copy()
        if direction.startswith("q0["):
            q0[full.index(direction[3:-1])] += h
        elif direction.startswith("qd0["):
            qd0[full.index(direction[4:-1])] += h
        else:
            p[model.parameter_names.index(direction)] += h
        run = simulate(model, 0.5, t_eval=samples, p=p, q0=q0, qd0=qd0, **TIGHT)
        assert len(run.impacts) == len(sequence)
        free = list(model.layout.free)
        return np.hstack([run.q[:, free], run.qd[:, free]])

    impacts = np.array(sequence)
    clear = np.array([np.min(np.abs(impacts - t)) > 2e-3 for t in samples])   # the jump moves with the impact time
    for j, direction in enumerate(names):
        fd = (trajectory(step, direction) - trajectory(-step, direction)) / (2 * step)
        error = np.abs(fd[clear] - r.sensitivities.at_samples[clear, :, j])
        assert error.max() <= 1e-6 * max(10.0, np.abs(fd[clear]).max()), direction


def test_bad_direction_names_say_what_is_allowed(free_rod):
    for bad in (["q0[theta_5]"], ["qd0[Y]"], ["mass"], [], ["g", "g"]):
        with pytest.raises(ValueError, match="sensitivities"):
            simulate(free_rod, 0.1, sensitivities=bad)
    with pytest.raises(ValueError, match=r"allowed: q0\[theta_1\], q0\[X1\], q0\[X2\].*e_x2_min"):
        simulate(free_rod, 0.1, sensitivities=["mass"])
    s = simulate(free_rod, 0.1, sensitivities=["q0[4]"], **TIGHT).sensitivities   # index 4 of Eq. 13: X2
    assert s["q[X2]", "q0[4]"] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("method, options", [("dop853", dict(rtol=1e-12, atol=1e-12)), ("rk4", dict(dt=2e-4))])
def test_every_integrator_carries_them(compiled, method, options):
    """DOP853's and RK4's own weights take the sensitivities over their steps as DOPRI5's do: a link length's column
    against a central difference, on the box run of seed 6."""
    model = compiled(stopped_chain(), tangent=True)
    over, q0, qd0 = box_run(6)
    p = model.parameters(dict(over, **UNSTOPPED))
    r = simulate(model, 1.5, method=method, p=p, q0=q0, qd0=qd0, sensitivities=["l_1"], **options)
    assert r.success and len(r.impacts) == 3 and r.sensitivities.valid
    index, h, ends = model.parameter_names.index("l_1"), 1e-6, []
    for step in (h, -h):
        p1 = p.copy()
        p1[index] += step
        run = simulate(model, 1.5, method=method, p=p1, q0=q0, qd0=qd0, **options)
        ends.append(np.concatenate([model.layout.reduce(run.q_final), model.layout.reduce(run.qd_final)]))
    fd = (ends[0] - ends[1]) / (2 * h)
    assert np.abs(fd - r.sensitivities.matrix[:, 0]).max() <= 1e-6 * np.abs(fd).max()
