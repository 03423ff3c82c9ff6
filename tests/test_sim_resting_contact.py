"""Resting contact and Zeno behaviour: impacts that accumulate end in resting frictionless
contact, a bilateral constraint of the flight equations released when its force would pull.

Independent checks: the contact bias J_dot qd against finite differences of the Jacobian and of the point
velocities; the constrained accelerations against a numpy KKT solve and against finite differences of
d/dt (J qd); contact forces recomputed in numpy along the trajectory; energy on every sample."""
import math

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from conftest import chain, sanitized_build
from runtime import simulate

G = 9.81
ENERGY_TOL = 1e-8      # allowed rise of T + V between samples, relative to E(0) (rtol = 1e-10: ~1e-9 seen)


def planar_drop(n: int, e: float = 0.5) -> Scene:
    """A planar n-link chain dropped tilted and bent onto the floor (e on the floor)."""
    q0 = (-math.pi / 2, 0.0, -0.3) + tuple(0.5 * (-1) ** k for k in range(n - 1)) + (0.0, 0.7, 0.0)
    return Scene(name=f"zeno_planar{n}_{int(10 * e)}", links=tuple(LineLink(0.4, 1.0) for _ in range(n)),
                 walls=(Wall("x2_min", 0.0, e),), q0=q0)


def rod_3d(e: float = 0.5) -> Scene:
    """One link tilted out of every coordinate plane, dropped onto the floor."""
    return Scene(name=f"zeno_rod3d_{int(10 * e)}", links=(LineLink(0.6, 1.0),), walls=(Wall("x2_min", 0.0, e),),
                 q0=(-math.pi / 2 + 0.4, 0.3, -0.5, 0.0, 0.8, 0.0))


def chain_3d(e: float) -> Scene:
    """Two links with a twisted joint (T_2 = Rx(0.5)): the motion is genuinely spatial."""
    c, s = math.cos(0.5), math.sin(0.5)
    return Scene(name=f"zeno_chain3d_{int(10 * e)}", links=(LineLink(0.6, 1.0), LineLink(0.5, 1.0)),
                 twists=(((1, 0, 0), (0, c, -s), (0, s, c)),), walls=(Wall("x2_min", 0.0, e),),
                 q0=(-math.pi / 2 + 0.4, -0.2, -1.0, 0.7, 0.0, 0.8, 0.0))


def swing_up(e: float = 0.5, omega: float = 15.0) -> Scene:
    """Two links lying straight on the floor; the second is thrown upwards at omega rad/s."""
    return Scene(name=f"swing_up_{int(10 * e)}", links=(LineLink(0.5, 1.0), LineLink(0.5, 1.0)),
                 walls=(Wall("x2_min", 0.0, e),), q0=(-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 0.0, 0.0),
                 qd0=(0.0, 0.0, 0.0, omega, 0.0, 0.0, 0.0))


def run(model, t_end, **options):
    options = {"rtol": 1e-10, "atol": 1e-12, **options}
    return simulate(model, t_end, **options)


def reduced(model, result):
    return [model.layout.reduce(q) for q in result.q], [model.layout.reduce(qd) for qd in result.qd]


def energies(model, result) -> np.ndarray:
    qs, qds = reduced(model, result)
    return np.array([sum(model.energy(q, qd)) for q, qd in zip(qs, qds)])


def resting_sets(model, result):
    """The resting set at each sample, rebuilt from the reported events (None next to an event)."""
    index = {(point, wall.name): c for c, (point, wall) in enumerate(model.contacts)}
    events = sorted(result.contact_events, key=lambda e: e.t)
    times = sorted({e.t for e in events} | {i.t for i in result.impacts})
    sets, resting, k = [], set(), 0
    for t in result.t:
        while k < len(events) and (events[k].t < t or events[k].t == 0.0 == t):
            c = index[(events[k].point, events[k].wall)]
            resting = resting | {c} if events[k].kind == "rest" else resting - {c}
            k += 1
        near = any(abs(t - te) < 1e-9 for te in times) and t > 0.0
        sets.append(None if near else sorted(resting))
    return sets


def kkt(model, q, qd, resting):
    """Numpy solve of [[I_f, -N^T], [N, 0]] [qdd, lambda] = [R, -Ndot qd] (N: signed Jacobian rows)."""
    M, R = model.mass_matrix(q), model.bias(q, qd)
    J, b = model.contact_jacobian(q), model.contact_bias(q, qd)
    rows = [model.contact_rows.index((model.contacts[c][0], model.contacts[c][1].axis)) for c in resting]
    sign = np.array([model.contacts[c][1].normal_sign for c in resting], dtype=float)
    N, nb = sign[:, None] * J[rows], sign * b[rows]
    k, nq = len(resting), model.nq
    K = np.block([[M, -N.T], [N, np.zeros((k, k))]])
    solution = np.linalg.solve(K, np.r_[R, -nb])
    return solution[:nq], solution[nq:], N


# --- kernels -------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed,twists", [(3, False), (4, True)])
def test_contact_bias_is_the_derivative_of_the_point_velocities(derived, seed, twists):
    model = derived(chain(3, twists=twists))
    rng = np.random.default_rng(seed)
    for _ in range(3):
        q, qd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        a = model.contact_bias(q, qd)
        eps = 1e-5
        fd_jacobian = (model.contact_jacobian(q + eps * qd) - model.contact_jacobian(q - eps * qd)) @ qd / (2 * eps)
        velocity = lambda x: np.array([model.contact_velocities(x, qd)[p - 1, axis] for p, axis in model.contact_rows])
        fd_velocity = (velocity(q + eps * qd) - velocity(q - eps * qd)) / (2 * eps)
        scale = np.abs(a).max()
        assert np.abs(a - fd_jacobian).max() < 1e-8 * scale
        assert np.abs(a - fd_velocity).max() < 1e-8 * scale


def test_constrained_dynamics_holds_the_contacts(compiled):
    """I_f qdd = R + N^T lambda (numpy), and d/dt(N qd) = N qdd + Ndot qd = 0 with Ndot qd by finite
    differences of the Jacobian; with no contact held it is forward_dynamics."""
    model = compiled(chain(3, twists=True))
    rng = np.random.default_rng(7)
    floor = [c for c, (point, wall) in enumerate(model.contacts) if wall.name == "x2_min"]
    side = [c for c, (point, wall) in enumerate(model.contacts) if wall.name == "x1_max"]
    for resting in ([floor[2]], [floor[1], floor[3]], [floor[0], side[3], floor[3]]):
        q, qd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        qdd, lam = model.constrained_dynamics(q, qd, resting)
        qdd_ref, lam_ref, N = kkt(model, q, qd, resting)
        assert np.abs(qdd - qdd_ref).max() < 1e-9 * np.abs(qdd_ref).max()
        assert np.abs(lam - lam_ref).max() < 1e-9 * np.abs(lam_ref).max()
        residual = model.mass_matrix(q) @ qdd - model.bias(q, qd) - N.T @ lam
        assert np.abs(residual).max() < 1e-9 * np.abs(model.bias(q, qd)).max()
        eps = 1e-5
        Ndot_qd = (kkt(model, q + eps * qd, qd, resting)[2] - kkt(model, q - eps * qd, qd, resting)[2]) @ qd / (2 * eps)
        assert np.abs(N @ qdd + Ndot_qd).max() < 1e-7 * np.abs(Ndot_qd).max()
    q, qd = rng.normal(size=model.nq), rng.normal(size=model.nq)
    assert np.array_equal(model.constrained_dynamics(q, qd, [])[0], model.forward_dynamics(q, qd))


# --- drops that end at rest ------------------------------------------------------------------------
# The restitution e of a wall is a parameter (p[e_WALL]): each scene is built once, with e = 0.5, and run at
# the e of the case.
DROPS = [("planar2", lambda: planar_drop(2), True), ("planar3", lambda: planar_drop(3), True),
         ("rod3d", rod_3d, False)]


@pytest.mark.parametrize("e", [0.0, 0.5])
@pytest.mark.parametrize("label,make,specialise", DROPS, ids=[d[0] for d in DROPS])
def test_drop_ends_at_rest_with_energy_falling(compiled, label, make, specialise, e):
    model = compiled(make(), specialise=specialise)
    result = run(model, 4.0, p={"e_x2_min": e})
    assert result.success, result.message
    assert len(result.impacts) < 100 and result.n_steps < 2000            # bounded: no Zeno cascade
    E = energies(model, result)
    assert np.diff(E).max() <= ENERGY_TOL * E[0]                          # T + V never rises
    for impact in result.impacts:
        assert impact.energy_after <= impact.energy_before + 1e-12 * E[0]
    # at rest on the floor: every point resting, still, at gap 0; nothing ever below the wall
    q = model.layout.reduce(result.q_final)
    assert sorted(result.resting_final) == [(p, "x2_min") for p in range(1, model.n + 2)]
    assert np.abs(result.qd_final).max() < 1e-6
    assert np.abs(model.contact_gaps(q)).max() < 1e-9
    gaps = np.array([model.contact_gaps(x) for x in reduced(model, result)[0]])
    assert gaps.min() > -1e-9
    assert abs(E[-1]) < 1e-9 * E[0]                    # V = 0 flat on the floor, T = 0
    kinds = {ev.kind for ev in result.contact_events}
    assert "rest" in kinds
    table = result.contact_event_table().splitlines()           # what python -m runtime simulate prints
    assert len(table) == 1 + len(result.contact_events) and table[1].split()[0] in kinds


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_forces_push_and_the_resting_points_stay_on_the_wall(compiled, e):
    """Along the whole run, each resting contact has gap 0, normal velocity 0 and a force >= 0, the
    force recomputed in numpy from the kernels (KKT) at every sample."""
    model = compiled(planar_drop(3), specialise=True)
    result = run(model, 2.5, p={"e_x2_min": e})
    qs, qds = reduced(model, result)
    weight = G * sum(link.mass for link in model.scene.links)
    checked = 0
    for q, qd, resting in zip(qs, qds, resting_sets(model, result)):
        if not resting:
            continue
        _, lam, N = kkt(model, q, qd, resting)
        assert lam.min() > -1e-6 * weight
        assert np.abs(model.contact_gaps(q)[resting]).max() < 1e-9
        assert np.abs(N @ qd).max() < 1e-6
        checked += 1
    assert checked > 500


def test_spatial_chain_ends_flat_on_the_floor(compiled):
    """Two links with a twisted joint: all points end resting on the floor.  The contact is frictionless,
    so motion along the floor (sliding, spinning, scissoring of the flat links) is not damped: after the
    last event the energy is constant and all of it is kinetic, tangential to the floor."""
    model = compiled(chain_3d(0.5), specialise=False)
    result = run(model, 4.0)
    assert result.success, result.message
    E = energies(model, result)
    assert np.diff(E).max() <= ENERGY_TOL * E[0]
    assert sorted(result.resting_final) == [(1, "x2_min"), (2, "x2_min"), (3, "x2_min")]
    last = max([ev.t for ev in result.contact_events] + [i.t for i in result.impacts])
    after = result.t > last + 1e-3
    assert after.sum() > 100
    assert np.ptp(E[after]) < 1e-8 * E[0]
    qs, qds = reduced(model, result)
    for q, qd in zip(np.array(qs)[after], np.array(qds)[after]):
        assert np.abs(model.contact_gaps(q)).max() < 1e-9
        assert np.abs(model.contact_velocities(q, qd)[:, 1]).max() < 1e-7      # no vertical motion
        assert abs(model.energy(q, qd)[1]) < 1e-9 * E[0]                     # V = 0: lying flat


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_paper_case1_with_inelastic_walls_collapses_flat_and_rests(compiled, e):
    """Case 1's diamond (O_1 and O_5 coincide) with every wall at e: it lands on its corner, collapses
    and folds flat with all five points resting (a trial stage of a large step after the first impact
    cannot hold the two corner contacts: the step is rejected, not the run)."""
    from codegen.scene import load_scene
    model = compiled(load_scene("paper-case1"), specialise=True)
    p = model.p.copy()
    for k, name in enumerate(model.scene.parameter_names()):
        if name.startswith("e_"):
            p[k] = e
    result = run(model, 3.0, p=p)
    assert result.success, result.message
    assert sorted(result.resting_final) == [(k, "x2_min") for k in range(1, 6)]
    assert np.abs(result.qd_final).max() < 1e-6
    E = np.array([sum(model.energy(q, qd, p)) for q, qd in zip(*reduced(model, result))])
    assert np.diff(E).max() <= ENERGY_TOL * E[0]


# --- release ------------------------------------------------------------------------------------
@pytest.mark.parametrize("e", [0.0, 0.5])
def test_swinging_link_lifts_the_resting_points_off(compiled, e):
    """The chain starts lying on the floor (O_1, O_2 resting, O_3 thrown up).  The swing of link 2 pulls
    O_2 and then O_1 off the floor: their forces fall through 0 (numpy KKT just before, 0 at the event)
    and they leave; the chain lands and comes to rest."""
    model = compiled(swing_up(), specialise=True)
    result = run(model, 3.0, t_eval=np.linspace(0.0, 3.0, 30001), p={"e_x2_min": e})
    assert result.success, result.message
    events = [(ev.point, ev.kind) for ev in result.contact_events]
    assert events[:4] == [(1, "rest"), (2, "rest"), (2, "release"), (1, "release")]
    assert all(ev.t == 0.0 for ev in result.contact_events[:2])
    index = {point: c for c, (point, wall) in enumerate(model.contacts)}
    for release in result.contact_events[2:4]:
        resting = sorted(index[p] for p in (1, 2) if (p, "release") not in
                        [(ev.point, ev.kind) for ev in result.contact_events[2:4] if ev.t < release.t])
        k = np.searchsorted(result.t, release.t) - 1         # the last sample before the release
        q, qd = model.layout.reduce(result.q[k]), model.layout.reduce(result.qd[k])
        _, lam, _ = kkt(model, q, qd, resting)
        assert lam[resting.index(index[release.point])] > 0.0
        # at the event the force is 0: continue the held motion to the event time and solve again
        qdd, lam_event = model.constrained_dynamics(q, qd, resting)
        dt = release.t - result.t[k]
        assert dt < 1e-4
        lam_at = model.constrained_dynamics(q + dt * qd + 0.5 * dt * dt * qdd, qd + dt * qdd, resting)[1]
        weight = G * 1.0
        assert abs(lam_at[resting.index(index[release.point])]) < 1e-3 * weight
        after = (result.t > release.t) & (result.t < release.t + 0.01)
        gaps = [model.contact_gaps(model.layout.reduce(x))[index[release.point]] for x in result.q[after]]
        assert max(gaps) > 0.0                                  # it leaves the floor
    E = energies(model, result)
    assert np.diff(E).max() <= ENERGY_TOL * E[0]
    assert np.abs(result.qd_final).max() < 1e-6
    assert sorted(result.resting_final) == [(1, "x2_min"), (2, "x2_min"), (3, "x2_min")]


def test_sliding_ladder_leaves_the_wall_at_two_thirds_of_its_height(compiled):
    """A uniform rod leaning at 60 degrees on a frictionless wall and floor, from rest: both ends rest,
    the rod slides down, and the top leaves the wall when its height is 2/3 of the initial one, at the
    time of the closed form t = (2 / sqrt(3 g / L)) int_0^w dw / cos(phi), sin(phi) = sin(phi0) - w^2."""
    from scipy.integrate import quad
    phi0, length = math.radians(60.0), 1.0
    scene = Scene(name="ladder", links=(LineLink(length, 1.0, (0.0, 0.0, 0.0)),),
                  walls=(Wall("x1_min", 0.0, 0.5), Wall("x2_min", 0.0, 0.5)),
                  q0=(-math.pi / 2, 0.0, math.pi / 2 - phi0, length * math.cos(phi0) + 2e-16, 0.0, 0.0))
    model = compiled(scene, specialise=True)
    result = run(model, 0.5, rtol=1e-12, atol=1e-14)
    assert result.success, result.message
    events = [(ev.point, ev.wall, ev.kind) for ev in result.contact_events]
    assert sorted(events[:2]) == [(1, "x2_min", "rest"), (2, "x1_min", "rest")]
    assert events[2] == (2, "x1_min", "release")
    w_release = math.sqrt(math.sin(phi0) / 3.0)
    integral = quad(lambda w: 1.0 / math.cos(math.asin(math.sin(phi0) - w * w)), 0.0, w_release, epsabs=1e-15)[0]
    t_release = 2.0 / math.sqrt(3.0 * G / length) * integral
    assert result.contact_events[2].t == pytest.approx(t_release, abs=1e-11)
    at_release = run(model, result.contact_events[2].t, rtol=1e-12, atol=1e-14, t_eval=[])
    top = model.contact_points(model.layout.reduce(at_release.q_final))[1]
    assert top[1] == pytest.approx(2.0 / 3.0 * length * math.sin(phi0), abs=1e-11)
    assert abs(top[0]) < 1e-12                                   # still on the wall until then
    assert np.diff(energies(model, result)).max() <= 1e-10 * sum(model.energy(model.q0, model.qd0))


def random_box_chain(n: int) -> Scene:
    """n links with twisted joints (spatial motion) in a box open at the top, every wall at e = 0.5."""
    c, s = math.cos(0.6), math.sin(0.6)
    walls = tuple(Wall(name, position, 0.5) for name, position in
                  (("x1_min", -1.5), ("x1_max", 1.5), ("x2_min", 0.0), ("x3_min", -1.5), ("x3_max", 1.5)))
    return Scene(name=f"zeno_box{n}", links=tuple(LineLink(0.5, 1.0) for _ in range(n)),
                 twists=(((1, 0, 0), (0, c, -s), (0, s, c)),) * (n - 1), walls=walls,
                 q0=(-math.pi / 2, 0.0) + (0.3,) * n + (0.0, 2.0, 0.0))


@pytest.mark.slow
def test_random_spatial_drops_into_a_box_end_cleanly(compiled):
    """Random throws of 1-3 spatial links into a box (walls, floor and corners; e in {0, 0.3, 0.7}): each run
    finishes (or stops at the base chart's gimbal lock, a separate limit), T + V never rises, nothing sinks
    below a wall, and every impact leaves no contact approaching its wall."""
    rng = np.random.default_rng(8)
    finished = 0
    for trial in range(12):
        n, e = int(rng.integers(1, 4)), float(rng.choice([0.0, 0.3, 0.7]))
        model = compiled(random_box_chain(n), specialise=False)
        p = model.p.copy()
        for k, name in enumerate(model.scene.parameter_names()):
            if name.startswith("e_"):
                p[k] = e
        while True:
            q = np.r_[rng.uniform(-math.pi, math.pi), rng.uniform(-0.6, 0.6), rng.uniform(-math.pi, math.pi, n),
                      rng.uniform(-0.5, 0.5), rng.uniform(0.6, 1.5), rng.uniform(-0.5, 0.5)]
            if model.contact_gaps(q, p).min() > 0.01:
                break
        qd = rng.normal(0.0, 1.5, model.nq)
        result = run(model, 4.0, p=p, q0=q, qd0=qd, max_impacts=3000)
        assert result.success or "gimbal lock" in result.message, (trial, result.message)
        finished += result.success
        E = np.array([sum(model.energy(a, b, p)) for a, b in zip(result.q, result.qd)])
        assert np.diff(E).max() <= ENERGY_TOL * np.abs(E).max(), trial
        gaps = np.array([model.contact_gaps(a, p) for a in result.q])
        assert gaps.min() > -1e-9, trial
    assert finished >= 8                    # 9 of these 12 (3 reach the gimbal lock)


# --- bounded time, options, the backstop ----------------------------------------------------------
def test_at_rest_the_integrator_takes_large_steps(compiled):
    model = compiled(planar_drop(3, 0.5), specialise=True)
    short = run(model, 4.0, t_eval=[])
    long = run(model, 1e4, t_eval=[])
    assert short.success and long.success
    assert len(long.impacts) == len(short.impacts)
    assert long.n_steps - short.n_steps < 100
    assert np.abs(long.qd_final).max() < 1e-6


def test_without_resting_contact_impacts_accumulate_to_the_backstop(compiled):
    model = compiled(planar_drop(3, 0.5), specialise=True)
    result = run(model, 4.0, rest_height=0.0, zeno_impacts=0, max_impacts=300)
    assert result.status == -1 and "max_impacts" in result.message
    assert result.contact_events == []


def test_accumulation_rule_alone_also_ends_the_cascade(compiled):
    """With the bounce-height rule off, a contact that has impacted 8 times at shrinking intervals becomes
    resting: the run finishes at rest."""
    model = compiled(planar_drop(2, 0.5), specialise=True)
    result = run(model, 4.0, rest_height=0.0, zeno_impacts=8)
    assert result.success, result.message
    assert np.abs(result.qd_final).max() < 1e-6
    E = energies(model, result)
    assert np.diff(E).max() <= ENERGY_TOL * E[0]


def test_a_chain_started_at_rest_on_the_floor_stays_there(compiled):
    scene = Scene(name="zeno_rest", links=tuple(LineLink(0.4, 1.0) for _ in range(3)),
                  walls=(Wall("x2_min", 0.0, 1.0),), q0=(-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 0.2, 0.0, 0.0))
    model = compiled(scene, specialise=True)
    result = run(model, 2.0)
    assert result.success, result.message
    assert [(ev.t, ev.kind) for ev in result.contact_events] == [(0.0, "rest")] * 4
    assert result.impacts == [] and result.n_steps < 30
    assert np.abs(result.q_final - scene.q0).max() < 1e-12 and np.abs(result.qd_final).max() < 1e-12


def test_elastic_scenes_never_rest(compiled):
    """e = 1: no contact comes to rest, and switching the feature off changes nothing, bit for bit."""
    from codegen.scene import load_scene
    model = compiled(load_scene("paper-case1"), specialise=True)
    on = run(model, 1.5)
    off = run(model, 1.5, rest_height=0.0, zeno_impacts=0)
    assert on.contact_events == [] and len(on.impacts) == 7
    assert [i.t for i in on.impacts] == [i.t for i in off.impacts]
    assert np.array_equal(on.q, off.q) and on.n_rhs == off.n_rhs


def test_bad_resting_options_are_named(compiled):
    model = compiled(planar_drop(2, 0.5), specialise=True)
    with pytest.raises(ValueError, match=r"^rest_height: must be < 1e300 m and not NaN"):
        run(model, 1.0, rest_height=float("nan"))
    with pytest.raises(ValueError, match=r"^zeno_impacts: must be >= 0"):
        run(model, 1.0, zeno_impacts=-3)


# --- in C, without Python --------------------------------------------------------------------------
ZENO_TOML = """
name = "zeno_c"
restitution = 0.5
[[links]]
count = 3
length = 0.4
mu = 1.0
[walls]
x2_min = 0.0
[initial]
q = [-1.5707963267948966, 0.0, -0.3, 0.5, -0.5, 0.0, 0.7, 0.0]
"""


@pytest.fixture(scope="module")
def zeno_c(tmp_path_factory):
    """The standalone example of a Zeno scene, built strictly with ASan + UBSan."""
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parent.parent
    out = tmp_path_factory.mktemp("zeno_c")
    (out / "zeno.toml").write_text(ZENO_TOML)
    subprocess.run([sys.executable, "-m", "codegen", "--scene", str(out / "zeno.toml"), "--out", str(out),
                    "--standalone", "--no-compile"], check=True, cwd=root, capture_output=True)
    sanitized_build(out, [out / "zeno_c.c", out / "zeno_c_example.c"], "asan")
    return out


@pytest.mark.parametrize("method", ["dopri5", "dop853", "rk4"])
def test_standalone_example_rests_cleanly_under_sanitizers(zeno_c, method):
    """The generated loop in C alone (strict C99, ASan + UBSan): the cascade ends in resting contact."""
    import subprocess
    result = subprocess.run([str(zeno_c / "asan"), "4.0", method, "1e-4" if method == "rk4" else "1e-10"],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "runtime error" not in result.stderr
    assert result.stdout.count("comes to rest") >= 4
    final = [line for line in result.stdout.splitlines() if line.startswith("# impacts")][0]
    assert abs(float(final.split()[-2])) < 1e-6          # final energy: flat on the floor, at rest


def test_standalone_example_is_clean_under_valgrind(zeno_c):
    import shutil
    import subprocess
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed")
    sources = [str(zeno_c / "zeno_c.c"), *sorted(str(p) for p in zeno_c.glob("gac_*.c")),
               str(zeno_c / "zeno_c_example.c"), "-I", str(zeno_c), "-lm"]
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2", "-g", *sources,
                    "-o", str(zeno_c / "plain")], check=True)
    checked = subprocess.run(["valgrind", "--error-exitcode=9", "-q", str(zeno_c / "plain"), "4.0"],
                             capture_output=True, text=True)
    assert checked.returncode == 0, checked.stderr
    assert checked.stdout.count("comes to rest") >= 4
