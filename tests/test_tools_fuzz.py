"""The fuzz study (studies/fuzz.py): its distribution, its independent checks (each one shown to fail on a
doctored result), a fast sample in the default run and 1,000 runs in the slow one."""
from dataclasses import dataclass, field

import numpy as np
import pytest

from studies import fuzz
from runtime.model import load_model
from runtime.simulate import Contact, Impact


def test_structures_are_deterministic_valid_and_cover_the_distribution():
    """200 structures (no compilation): the same seed gives the same scenes, every scene passes the scene
    validation (done by the Scene constructor), and the draw covers n = 1 ... 8, planar and spatial chains,
    line and rigid links, lengths and masses over 1e-3 ... 1e2 m and 1e-4 ... 1e4 kg, gravity on and off."""
    scenes = [fuzz.random_structure(np.random.default_rng([7, i]), i) for i in range(200)]
    again = [fuzz.random_structure(np.random.default_rng([7, i]), i) for i in range(200)]
    assert scenes == again
    assert {s.n for s in scenes} == set(range(1, 9))
    planar = [not any(w.name.startswith("x3") for w in s.walls) for s in scenes]
    assert 0.2 < np.mean(planar) < 0.5
    kinds = {link.kind for s in scenes for link in s.links}
    assert kinds == {"line", "rigid"}
    lengths = [link.length for s in scenes for link in s.links]
    masses = [link.mass for s in scenes for link in s.links]
    assert min(lengths) < 3e-3 and max(lengths) > 30 and min(masses) < 1e-3 and max(masses) > 1e3
    assert {s.gravity for s in scenes} == {0.0, 9.81}
    capsules = [s for s in scenes if fuzz.has_capsules(s)]
    rough = [s for s in capsules if any(w.friction > 0.0 for w in s.walls)]
    assert 0.15 < (len(capsules) - len(rough)) / len(scenes) < 0.35              # a quarter: frictionless structures
    assert 0.05 < len(rough) / len(scenes) < 0.15                                # a tenth: capsules on rough walls
    radii = [link.radius for s in capsules for link in s.links if link.radius > 0.0]
    assert fuzz.RADIUS_RANGE[0] <= min(radii) and max(radii) <= fuzz.RADIUS_RANGE[1]
    assert any(s.link_pairs() for s in capsules)


def test_capsules_leave_the_other_structures_and_their_runs_as_they_were():
    """The capsule draw comes from a child stream of the structure's seed: a structure without capsules is the one
    drawn without them (capsules=False), and its rng is left at the same point for its runs."""
    for i in range(40):
        rng = np.random.default_rng([0, i])
        scene = fuzz.random_structure(rng, i)
        rng_old = np.random.default_rng([0, i])
        old = fuzz.random_structure(rng_old, i, capsules=False)
        assert rng.uniform() == rng_old.uniform()
        if not fuzz.has_capsules(scene):
            assert scene == old
        else:
            assert [link.length for link in scene.links] == [link.length for link in old.links]


def small_structure():
    """A structure of up to 3 links (structure 0 of seed 3), its compiled model and the stream its runs come from: the
    tests below that need some compiled structure share it (one build)."""
    rng = np.random.default_rng(3)
    scene = fuzz.random_structure(rng, 0, n_max=3)
    return rng, scene, fuzz.study_model(scene)


def test_runs_start_strictly_inside_their_box_with_every_restitution_kind():
    """Runs of one compiled structure: new numbers each time, every contact point strictly inside its
    box, restitutions 0, 1 and in between, all three integrators."""
    rng, scene, model = small_structure()
    runs = [fuzz.random_run(rng, scene, model) for _ in range(60)]
    names = scene.parameter_names()
    restitutions = set()
    for run in runs:
        assert model.contact_gaps(model.layout.reduce(run.q0), run.p).min() > 0.0
        restitutions |= {float(run.p[i]) for i, name in enumerate(names) if name.startswith("e_")}
        assert 0.05 <= run.t_end <= fuzz.T_END_MAX
    assert {0.0, 1.0} <= restitutions and any(0.0 < e < 1.0 for e in restitutions)
    assert {run.options["method"] for run in runs} == {"dopri5", "dop853", "rk4"}
    assert len({tuple(run.p) for run in runs}) == len(runs)


@dataclass
class FakeResult:
    q: np.ndarray
    qd: np.ndarray
    q_final: np.ndarray
    qd_final: np.ndarray
    impacts: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    loss_friction: float = 0.0
    energy_scale: float = 1.0


def test_each_independent_check_can_fail():
    """Doctored results: a sample beyond a wall, a NaN, an impact that gains energy, an elastic impact that
    loses it, a run over its budget: check_run reports each; the untouched result passes."""
    rng, scene, model = small_structure()
    run = fuzz.random_run(rng, scene, model)
    run.options = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}
    names = scene.parameter_names()
    for i, name in enumerate(names):
        if name.startswith("e_"):
            run.p[i] = 1.0
    q, qd = run.q0, run.qd0
    clean = FakeResult(np.array([q]), np.array([qd]), q, qd)
    assert fuzz.check_run(model, run, clean, 0.1, 20.0) == []
    # a point pushed 1 mm through the lowest wall
    sunk = q.copy()
    wall = names.index("wall_x2_min")
    run_sunk = fuzz.Run(run.p.copy(), q, qd, run.t_end, run.options, run.extent)
    points = model.contact_points(model.layout.reduce(q), run.p)
    run_sunk.p[wall] = points[:, 1].min() + 1e-3
    assert "penetration" in fuzz.check_run(model, run_sunk, FakeResult(np.array([sunk]), np.array([qd]), q, qd),
                                           0.1, 20.0)[0]
    nan = qd.copy()
    nan[0] = np.nan
    assert fuzz.check_run(model, run, FakeResult(np.array([q]), np.array([nan]), q, qd), 0.1, 20.0) == \
        ["non-finite state"]
    point, wall_of = model.contacts[0]
    gain = Impact(0.1, [Contact(point, wall_of.name, 1.0)], 0.0, 0.0, False, q, qd, 1.1 * qd)
    assert "energy gain" in fuzz.check_run(model, run, FakeResult(np.array([q]), np.array([qd]), q, qd, [gain]),
                                           0.1, 20.0)[0]
    loss = Impact(0.1, [Contact(point, wall_of.name, 1.0)], 0.0, 0.0, False, q, qd, 0.9 * qd, law_elastic=True)
    assert "elastic impact" in fuzz.check_run(model, run, FakeResult(np.array([q]), np.array([qd]), q, qd, [loss]),
                                              0.1, 20.0)[0]
    assert "over budget" in fuzz.check_run(model, run, clean, 30.0, 20.0)[0]
    gift = FakeResult(np.array([q]), np.array([qd]), q, qd, loss_friction=-1e-3)
    assert "friction gave energy" in fuzz.check_run(model, run, gift, 0.1, 20.0)[0]


@pytest.mark.slow      # runs with wall-time budgets: on a loaded machine they end early
def test_fast_sample_has_no_failure():
    """16 runs on 4 structures of up to 4 links (about a minute on 2 cores): every run ends at t_end or with
    a physical stop, and passes the independent checks."""
    outcomes = fuzz.fuzz(runs=16, per_structure=4, seed=11, n_max=4, jobs=2)
    assert len(outcomes) == 16
    assert [o for o in outcomes if o.failed] == []
    assert sum(o.outcome == "ok" for o in outcomes) >= 10


@pytest.mark.slow
def test_thousand_runs_have_no_failure():
    """The study of record (docs/validation.md): 1,000 runs, 50 structures of up to 8 links x 20, a 5 s budget each."""
    outcomes = fuzz.fuzz(runs=1000, per_structure=20, seed=0, budget=5.0, jobs=None)
    assert len(outcomes) == 1000
    failed = [(o.case, o.violations or o.message[:160]) for o in outcomes if o.failed]
    assert failed == []


def corner_scene(e_left: float):
    """A rod in a corner: O1 slides at 0.3 m/s towards the left wall (restitution e_left) while O2 falls onto
    the floor (e = 1); both arrive at t_hit = (sqrt(1 + 2 g 0.1) - 1) / g, in closed form."""
    import math
    from codegen.scene import scene_from_dict
    t_hit = (math.sqrt(1.0 + 2.0 * 9.81 * 0.1) - 1.0) / 9.81
    data = {"name": "corner", "gravity": 9.81, "links": [{"length": 1.0, "mu": 1.0}],
            "walls": {"x1_min": 0.0, "x1_max": 5.0, "x2_min": 0.0, "x2_max": 5.0},
            "restitution": {"x1_min": e_left, "x2_min": 1.0, "x1_max": 1.0, "x2_max": 1.0},
            "initial": {"q": [-math.pi / 2, 0.0, math.atan2(-0.6, -0.8), 0.3 * t_hit, 0.9, 0.0],   # O2 at (0.6, 0.1)
                        "qd": [0.0, 0.0, 0.0, -0.3, -1.0, 0.0]}}
    return scene_from_dict(data), t_hit


@pytest.mark.parametrize("e_left", [0.0, 0.5, 1.0])
def test_the_energy_check_follows_the_law_not_the_walls(e_left):
    """An impact on an e = 1 floor with a contact on a wall of restitution e_left: the law is elastic only when
    e_left = 1, and the energy it takes is the work-energy identity's sum of F_k v_k- (1 - e_k) / 2 (Newton's
    law v_k+ = -e_k v_k-), which vanishes for e_left = 1.  The study's checks and simulate's own accept each run."""
    from runtime.simulate import simulate
    scene, t_hit = corner_scene(0.5)
    model = load_model(scene)                                  # one model: e_left is a parameter
    run = fuzz.Run(p=model.parameters({"e_x1_min": e_left}), q0=np.array(scene.q0), qd0=np.array(scene.qd0),
                   t_end=0.1, options={"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}, extent=5.0)
    result = simulate(model, run.t_end, p=run.p, **run.options)
    assert result.status == 0 and result.warnings == [], result.message
    assert fuzz.check_run(model, run, result, 0.1, 20.0) == []
    impact, = result.impacts
    assert impact.t == pytest.approx(t_hit, abs=1e-12)
    assert sorted(c.label for c in impact.contacts) == ["O1/x1_min", "O2/x2_min"]
    assert all(c.impulse > 0 for c in impact.contacts)
    assert impact.law_elastic == (e_left == 1.0)
    v_before = {"O1/x1_min": 0.3, "O2/x2_min": 1.0 + 9.81 * t_hit}            # approach speeds, closed form
    e = {"O1/x1_min": e_left, "O2/x2_min": 1.0}
    loss = sum(c.impulse * v_before[c.label] * (1.0 - e[c.label]) / 2.0 for c in impact.contacts)
    assert impact.energy_before - impact.energy_after == pytest.approx(loss, abs=1e-10 * impact.energy_before)
    if e_left < 1.0:
        assert loss > 0.01 * impact.energy_before


@pytest.mark.slow      # runs with wall-time budgets: on a loaded machine they end early
def test_rough_sample_has_no_failure():
    """Runs of two structures whose walls have Coulomb friction (structures 4 and 11 of the study's stream): every
    run ends cleanly and passes the independent checks, friction's loss included."""
    outcomes = []
    for index in (4, 11):
        outcomes += fuzz.run_structure((11, index, 3, 10.0, 4))
    assert len(outcomes) == 6
    assert [o for o in outcomes if o.failed] == []
    assert sum(o.outcome == "ok" for o in outcomes) >= 3


def test_a_structure_runs_through_the_study_path():
    """One small structure with rough walls, two runs, through the study's own worker (run_structure): outcomes
    come back as rows (no exception), so the slow samples above test the physics, not the plumbing."""
    outcomes = fuzz.run_structure((11, 4, 2, 30.0, 1))          # a one-link structure: quick to build
    assert len(outcomes) == 2 and not any(o.outcome.startswith("exception") for o in outcomes)
    assert all(isinstance(o.planar, bool) for o in outcomes)


def test_the_accuracy_summary_names_each_flagged_runs_cause():
    """A run whose least accurate impact is above 1e-10 is listed with its accuracy and cause; the others are not."""
    def outcome(case, roundoff, cause=""):
        return fuzz.Outcome(case, 3, False, "dopri5", 0, "ok", False, roundoff=roundoff, cause=cause)
    text = fuzz.accuracy_summary([outcome("0-1/0", 0.0), outcome("0-2/1", 2.2e-10, "the base chart is near its "
                                  "singular pose"), outcome("0-3/0", 9e-11)])
    lines = text.splitlines()
    assert lines[0].startswith("impact accuracy: 1 of 3 runs state an impact less accurate than 1e-10, 0 than 1e-6")
    assert lines[1:] == ["- 0-2/1: 2.2e-10, the base chart is near its singular pose"]


CAPSULE_CASE = (11, 7, 3)      # seed, structure, n_max: three links, capsules on links 1 and 2, the pair (1, 3)


def test_a_capsule_structure_runs_through_the_study_path():
    """A structure with capsule links and a link pair, two runs, through run_structure: the outcomes say it has
    capsules, and both runs end cleanly and pass the checks, the capsules' included."""
    seed, index, n_max = CAPSULE_CASE
    scene = fuzz.random_structure(np.random.default_rng([seed, index]), index, n_max)
    assert fuzz.has_capsules(scene) and scene.link_pairs() == [(1, 3)]
    outcomes = fuzz.run_structure((seed, index, 2, 30.0, n_max))
    assert len(outcomes) == 2 and all(o.capsules for o in outcomes)
    assert [(o.case, o.violations, o.message) for o in outcomes if o.failed] == []
    assert fuzz.capsule_summary(outcomes).startswith("capsules: 1 of 1 structures (2 runs) have capsule links; "
                                                     "0 of their runs failed")


def test_segment_distance_against_a_dense_search():
    """The independent closest-points computation against a 401 x 401 grid of (s, t): never above the grid's least
    distance and within the grid's resolution below it, for skew, parallel, collinear and crossing segments and a
    segment of zero length."""
    rng = np.random.default_rng(2)
    cases = [tuple(rng.normal(size=(4, 3))) for _ in range(40)]
    a0, a1 = np.zeros(3), np.array([1.0, 0, 0])
    cases += [(a0, a1, np.array([0.2, 0.3, 0]), np.array([0.9, 0.3, 0])),          # parallel
              (a0, a1, np.array([1.5, 0, 0]), np.array([2.5, 0, 0])),              # collinear, apart
              (a0, a1, np.array([0.5, -1, 0]), np.array([0.5, 1, 0])),             # crossing
              (a0, a1, np.array([0.5, 0.5, 0.5]), np.array([0.5, 0.5, 0.5]))]      # a point
    grid = np.linspace(0.0, 1.0, 401)
    for b in cases:
        p0, p1, q0, q1 = (np.asarray(x, dtype=float) for x in b)
        A = p0 + grid[:, None] * (p1 - p0)
        B = q0 + grid[:, None] * (q1 - q0)
        brute = np.linalg.norm(A[:, None, :] - B[None, :, :], axis=2).min()
        d = fuzz.segment_distance(p0, p1, q0, q1)
        step = (np.linalg.norm(p1 - p0) + np.linalg.norm(q1 - q0)) / 400
        assert brute - step <= d <= brute + 1e-12


def test_each_capsule_check_can_fail():
    """Doctored states of the capsule structure: a wall moved to half a radius inside a capsule's end (the joint
    point itself still clear of it), and links 1 and 3 folded across each other: check_run reports each with its
    capsule check; the untouched start passes."""
    seed, index, n_max = CAPSULE_CASE
    rng = np.random.default_rng([seed, index])
    scene = fuzz.random_structure(rng, index, n_max)
    model = fuzz.study_model(scene)
    run = fuzz.random_run(rng, scene, model)
    names = scene.parameter_names()
    reach = max(link.radius for link in scene.links)
    assert all(run.p[names.index(f"l_{i}")] >= fuzz.LENGTH_PER_RADIUS[0] * reach for i in range(1, scene.n + 1))
    run.options = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}
    q, qd = run.q0, run.qd0
    clean = FakeResult(np.array([q]), np.array([qd]), q, qd)
    assert fuzz.check_run(model, run, clean, 0.1, 20.0) == []
    # a wall half a radius inside link 2's capsule
    r = scene.links[1].radius
    points = model.contact_points(model.layout.reduce(q), run.p)
    sunk = fuzz.Run(run.p.copy(), q, qd, run.t_end, run.options, run.extent)
    sunk.p[names.index("wall_x2_min")] = min(points[1, 1], points[2, 1]) - r / 2
    violations = fuzz.check_run(model, sunk, clean, 0.1, 20.0)
    assert any(v.startswith("capsule penetrates a wall by") for v in violations), violations
    # links 1 and 3 folded across each other: the deepest of a grid of the two joint angles, lengths 1, 0.5, 1 m
    folded = fuzz.Run(run.p.copy(), q, qd, run.t_end, run.options, run.extent)
    for i, length in enumerate((1.0, 0.5, 1.0), start=1):
        folded.p[names.index(f"l_{i}")] = length
    for name in names:
        if name.startswith("wall_"):
            folded.p[names.index(name)] = 1e3 if name.endswith("max") else -1e3
    radii = [link.radius for link in scene.links]
    states = []
    for a in np.linspace(-np.pi, np.pi, 25):
        for b in np.linspace(-np.pi, np.pi, 25):
            state = q.copy()
            state[3:5] = a, b
            gap = fuzz.pair_gaps(model.contact_points(model.layout.reduce(state), folded.p), radii, [(1, 3)])[0]
            states.append((gap, state))
    gap, state = min(states, key=lambda item: item[0])
    assert gap < -1e-4 and model.link_gap(model.layout.reduce(state), 1, 3, folded.p)[0] == pytest.approx(gap)
    fold = FakeResult(np.array([state]), np.array([qd]), state, qd)
    violations = fuzz.check_run(model, folded, fold, 0.1, 20.0)
    assert any(v.startswith("capsules overlap by") for v in violations), violations
    assert not any(v.startswith("capsule penetrates") for v in violations)


OBSTACLE_CASE = (11, 13, 1)    # seed, structure, n_max: one capsule link; the study puts obstacles into its runs


def test_an_obstacle_structure_runs_through_the_study_path():
    """A structure the study gives fixed obstacles, two runs through run_structure as the study calls it: each run has
    one or two obstacles, ends cleanly and passes the checks, the obstacles' included; called without the keyword
    (as the tests that reproduce a structure do), the same runs have none."""
    seed, index, n_max = OBSTACLE_CASE
    assert fuzz.has_obstacle_runs(seed, index)
    outcomes = fuzz.run_structure((seed, index, 2, 30.0, n_max, True))
    assert [o.obstacles for o in outcomes] == [1, 2]
    assert [(o.case, o.violations, o.message) for o in outcomes if o.failed] == []
    assert fuzz.obstacle_summary(outcomes).startswith("obstacles: 1 of 1 structures (2 runs, 3 obstacles) have fixed "
                                                      "obstacles; 0 of their runs failed, 0 on an obstacle check")
    assert [o.obstacles for o in fuzz.run_structure((seed, index, 2, 30.0, n_max))] == [0, 0]


def test_obstacles_leave_the_structures_and_their_runs_as_they_were():
    """The obstacles come from their own stream after the run is drawn (random_structure and random_run know nothing of
    them): the run's parameters are the first of the obstacle model's, the structure's links are kept, and each
    obstacle is centred in the run's box, clear of the start."""
    seed, index, n_max = OBSTACLE_CASE
    rng = np.random.default_rng([seed, index])
    scene = fuzz.random_structure(rng, index, n_max)
    model = fuzz.study_model(scene)
    run = fuzz.random_run(rng, scene, model)
    obstacle_rng = np.random.default_rng([seed, index, fuzz.OBSTACLE_STREAM, 0])
    obstacles = fuzz.random_obstacles(obstacle_rng, scene, model, run)
    assert 1 <= len(obstacles) <= 2
    with_obstacles, obstacle_model, obstacle_run = fuzz.obstacle_run(obstacle_rng, scene, model, run, obstacles,
                                                                     fuzz.study_model)
    assert with_obstacles.links == scene.links and with_obstacles.obstacles[0].name == obstacles[0].name
    geometry = sum(len(o.geometry_names) for o in obstacles)                  # each one's e, then the geometry
    assert np.array_equal(obstacle_run.p[:len(run.p)], run.p) and len(obstacle_run.p) == len(run.p) + len(obstacles) \
        + geometry
    assert obstacle_run.p[len(run.p) + len(obstacles):].tolist() == [x for o in obstacles for x in o.geometry_values]
    assert with_obstacles.obstacles == tuple(o.with_geometry(o.geometry_values) for o in with_obstacles.obstacles)
    assert [o.segment[0] for o in obstacle_model.scene.obstacles] == [(fuzz.OBSTACLE_PARKED,) * 3] * len(obstacles)
    names = scene.parameter_names()
    points = model.contact_points(model.layout.reduce(run.q0), run.p)
    radii = [link.radius for link in scene.links]
    assert min(fuzz.obstacle_gaps(points, radii, obstacles)) > fuzz.OBSTACLE_CLEAR * run.extent
    for o in obstacles:
        centre = (np.array(o.segment[0]) + np.array(o.segment[1])) / 2
        for k, axis in enumerate("123"):
            if f"wall_x{axis}_min" in names:
                assert run.p[names.index(f"wall_x{axis}_min")] < centre[k] < run.p[names.index(f"wall_x{axis}_max")]


def test_the_obstacle_check_can_fail_and_its_box_distance_is_right():
    """The independent box distance against a dense search along the segment (inside the box too) and the scene's own;
    a link moved into a sphere, a bar and a box in turn (named as the study names them, so that their models are the
    study's): check_run reports it on its obstacle check, the obstacle where the run's p puts it; clear, it passes.
    The sphere moved elsewhere runs on the same compiled model."""
    from codegen.scene import Obstacle
    rng = np.random.default_rng(4)
    for _ in range(30):
        box = Obstacle.box("b", rng.normal(size=3), rng.uniform(0.1, 1.0, 3), fuzz._rotation(rng))
        p0, p1 = rng.normal(size=3) * 1.5, rng.normal(size=3) * 1.5
        samples = p0 + np.linspace(0.0, 1.0, 20001)[:, None] * (p1 - p0)
        excess = np.abs((samples - box.a) @ np.array(box.box_rotation)) - box.half_extents
        dense = (np.linalg.norm(np.maximum(excess, 0.0), axis=1) + np.minimum(excess.max(axis=1), 0.0)).min()
        assert fuzz.box_signed_distance(samples[7], box.a, box.half_extents, box.box_rotation) == \
            pytest.approx(np.linalg.norm(np.maximum(excess[7], 0.0)) + min(excess[7].max(), 0.0), abs=1e-14)
        d = fuzz.segment_box_distance(p0, p1, box)
        assert dense - np.linalg.norm(p1 - p0) / 20000 <= d <= dense + 1e-12     # within the grid's resolution
        assert d == pytest.approx(box.distance(p0, p1), abs=1e-9)
    seed, index, n_max = OBSTACLE_CASE
    rng = np.random.default_rng([seed, index])
    scene = fuzz.random_structure(rng, index, n_max)
    model = fuzz.study_model(scene)
    run = fuzz.random_run(rng, scene, model)
    run.options = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}
    q, qd = run.q0, run.qd0
    points = model.contact_points(model.layout.reduce(q), run.p)
    mid, size = (points[0] + points[1]) / 2, run.extent * 1e-2
    centre = mid + 3 * run.extent                  # clear of the start; the doctored state puts the link's middle here
    sunk = q.copy()
    sunk[-3:] += centre - mid                      # the free base's position: the whole chain translated
    bar = np.array([run.extent * 0.1, 0.0, 0.0])
    models = []
    for obstacle in (Obstacle.sphere("sphere_a", tuple(centre), size),
                     Obstacle.sphere("sphere_a", tuple(centre + 0.5 * size), 0.5 * size),
                     Obstacle.bar("bar_a", tuple(centre - bar), tuple(centre + bar), size),
                     Obstacle.box("box_a", tuple(centre), (size,) * 3, fuzz._rotation(rng))):
        _, obstacle_model, obstacle_run = fuzz.obstacle_run(np.random.default_rng(0), scene, model, run, (obstacle,),
                                                            fuzz.study_model)
        moved = obstacle_model.contact_points(obstacle_model.layout.reduce(sunk), obstacle_run.p)
        assert np.allclose((moved[0] + moved[1]) / 2, centre)
        clean = FakeResult(np.array([q]), np.array([qd]), q, qd)
        assert fuzz.check_run(obstacle_model, obstacle_run, clean, 0.1, 20.0) == []
        doctored = FakeResult(np.array([q, sunk]), np.array([qd, qd]), q, qd)
        violations = fuzz.check_run(obstacle_model, obstacle_run, doctored, 0.1, 20.0)
        assert any(v.startswith("obstacle penetrated by a link by") for v in violations), (obstacle.kind, violations)
        models.append(obstacle_model)
    assert models[0].lib is models[1].lib and len({id(m.lib) for m in models}) == 3   # one model per obstacle structure


CHAINS_CASE = (11, 21, 2)      # seed, structure, n_max: three planar chains of 1, 1 and 2 links in one box


def test_multi_chain_structures_come_from_their_own_stream():
    """A tenth of the structures are drawn as several chains (has_chain_runs, a stream apart): two or three chains of
    1 ... 4 links, each with a capsule, every radius in range; the study's other structures are random_structure's,
    and without the study's flag every structure is.  The study's pairs across chains are the model's table's."""
    several = [i for i in range(300) if fuzz.has_chain_runs(0, i)]
    assert 0.05 < len(several) / 300 < 0.15
    scenes = [fuzz.random_chains(fuzz.chains_stream(0, i), i) for i in several]
    assert {len(s.chains) for s in scenes} == {2, 3}
    assert {c.n for s in scenes for c in s.chains} == {1, 2, 3, 4}
    assert all(any(link.radius > 0.0 for link in c.links) for s in scenes for c in s.chains)
    radii = [link.radius for s in scenes for link in s.links if link.radius > 0.0]
    assert fuzz.RADIUS_RANGE[0] <= min(radii) and max(radii) <= fuzz.RADIUS_RANGE[1]
    for s in scenes:
        assert fuzz.pairs_across(s) == [(c.i, c.j) for c in s.cross_link_pairs()]
    for i in range(40):
        scene, _ = fuzz.draw_structure(0, i, 8, True)
        one, _ = fuzz.draw_structure(0, i, 8, False)
        assert one == fuzz.random_structure(np.random.default_rng([0, i]), i)
        assert (scene != one) == fuzz.has_chain_runs(0, i)


def test_a_multi_chain_structure_runs_through_the_study_path():
    """Three chains in one box, two runs through run_structure as the study calls it: the outcomes say three chains,
    links of two chains strike in each run, and both runs end cleanly and pass the checks, every pair across the
    chains included."""
    seed, index, n_max = CHAINS_CASE
    assert fuzz.has_chain_runs(seed, index)
    outcomes = fuzz.run_structure((seed, index, 2, 30.0, n_max, True, True))
    assert [o.chains for o in outcomes] == [3, 3] and all(o.strikes_across > 0 for o in outcomes)
    assert [(o.case, o.violations, o.message) for o in outcomes if o.failed] == []
    assert fuzz.chains_summary(outcomes).startswith("several chains: 1 of 1 structures (2 runs) are several chains in "
                                                    "one box: 11-21 (3 chains); 0 of their runs failed")


def test_the_checks_across_chains_can_fail():
    """Doctored states of the three-chain structure: chain 2 moved so that its first link's middle lies on chain 1's,
    and a wall moved half a radius into chain 3's capsule: check_run reports the overlap across chains (not as
    a pair of one chain) and the wall on its link check; the untouched start passes."""
    seed, index, n_max = CHAINS_CASE
    rng = fuzz.chains_stream(seed, index)
    scene = fuzz.random_chains(rng, index, n_max)
    model = fuzz.study_model(scene)
    run = fuzz.random_chains_run(rng, scene, model)
    run.options = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-12}
    q, qd = run.q0, run.qd0
    points = model.contact_points(model.layout.reduce(q), run.p)
    radii, pairs = fuzz.point_radii(scene), fuzz.all_link_pairs(scene)
    assert min(fuzz.pair_gaps(points, radii, pairs)) > 0.0
    clean = FakeResult(np.array([q]), np.array([qd]), q, qd)
    assert fuzz.check_run(model, run, clean, 0.1, 20.0) == []
    rows = fuzz.chain_rows(scene)
    one, two = rows[0].start, rows[1].start
    crossed = q.copy()
    base = scene.state_offset(2) + scene.chains[1].n + 2                 # chain 2's X1, X2, X3 in the full layout
    crossed[base:base + 3] += (points[one] + points[one + 1] - points[two] - points[two + 1]) / 2
    moved = model.contact_points(model.layout.reduce(crossed), run.p)
    assert np.allclose(moved[two] + moved[two + 1], points[one] + points[one + 1])
    violations = fuzz.check_run(model, run, FakeResult(np.array([crossed]), np.array([qd]), crossed, qd), 0.1, 20.0)
    assert any(v.startswith("capsules of two chains overlap by") for v in violations), violations
    assert not any(v.startswith("capsules overlap by") for v in violations)
    link = next(i for i in rows[2][:-1] if radii[i] > 0.0)            # chain 3's capsule: the segment of rows i, i + 1
    r = radii[link]
    sunk = fuzz.Run(run.p.copy(), q, qd, run.t_end, run.options, run.extent)
    sunk.p[scene.parameter_names().index("wall_x2_min")] = min(points[link, 1], points[link + 1, 1]) - r / 2
    violations = fuzz.check_run(model, sunk, clean, 0.1, 20.0)
    assert any(v.startswith("a link penetrates a wall by") for v in violations), violations


def test_the_sensitivities_mode_says_how_far_each_run_was_differentiated():
    """With sensitivities (run_structure's eighth argument, --sensitivities): each run that reached its end says
    'valid' or the status of its first event not differentiated (the library's words) and its time; the summary
    counts them."""
    from runtime.sensitivities import STATUS_WORDS
    outcomes = fuzz.run_structure((11, 4, 3, 60.0, 2, True, True, True))
    ended = [o for o in outcomes if o.status == 0]
    assert len(ended) == 2 and not any(o.failed for o in outcomes)
    assert {o.sensitivities for o in ended} <= set(STATUS_WORDS.values())
    assert any(o.sensitivities == "valid" and o.sensitivity_t == -1.0 for o in ended)
    assert any(o.sensitivities != "valid" and 0.0 < o.sensitivity_t for o in ended)
    summary = fuzz.sensitivity_summary(outcomes)
    assert summary.startswith("Sensitivities: 1 of the 2 runs that reached t_end (50.0 %)")
    assert all(o.sensitivities == "" for o in fuzz.run_structure((11, 4, 3, 60.0, 2, True, True)))
