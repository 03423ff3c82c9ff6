"""Fuzz study: random admissible scenes through the hybrid loop, each run checked independently.

    python -m studies fuzz [--runs N] [--per-structure K] [--seed S] [--jobs J] [--budget SECONDS]
                           [--json FILE] [--case ID] [--sensitivities]

The distribution (``random_structure`` and ``random_run``): n = 1 ... 8 links; lengths 1e-3 ... 1e2 m and
masses 1e-4 ... 1e4 kg (log-uniform, per link, so ratios of 1e5 within a chain occur); slender line links
(cross-section radius 1e-3 ... 1e-1 of the length, the axial inertia sometimes 1e-8 of that) and thick
rigid bodies (a random box, centre of mass off the axis, principal axes turned); planar chains (parallel
joint axes, start in the X1-X2 plane) and spatial ones with random twists; gravity 0 or 9.81; a box around
the start, often cramped (margins 1e-3 ... 1 of the chain's extent, so that a side can be shorter than the
chain); restitution per wall 0, 1 or uniform in [0, 1]; Coulomb friction on the walls of 30 % of the structures
(c_f uniform in [0, 1.5] per wall and run, drawn so that the other structures' runs are unchanged); capsule links
on a quarter of the structures, all frictionless ones, and on a third of the rough ones (capsules on rough walls,
from a stream of their own: the frictionless structures are unchanged) (each link a capsule with probability 0.7,
at least one; radius r log-uniform in 5e-5 ... 5e-2 m; every link's length, capsule or not, log-uniform in 20 R ... 2e4 R
(at most 1e2 m) with R the chain's largest radius, so that a capsule is thin against every link; every
non-adjacent pair of links with a capsule strikes the other, restitution 0, 1 or uniform in [0, 1]; the box
margins add the largest radius and the start is redrawn until no pair overlaps); fixed obstacles in the study's runs
of a fifth of the structures (has_obstacle_runs, from the stream [seed, structure, OBSTACLE_STREAM]; per run, from
[seed, structure, OBSTACLE_STREAM, run], after the run is drawn: one or two spheres, bars or boxes of 1e-2 ... 0.3 of
the chain's extent, centred inside the run's box and clear of its start, restitution 0, 1 or uniform; the structure
is compiled once per set of obstacles' names and kinds, with the obstacles parked far away (obstacle_structure), and
each run sets its obstacles' places and sizes through the parameter vector); several chains in one box
for a tenth of the study's structures (has_chain_runs, from the stream [seed, structure, CHAINS_STREAM], the
structure and its runs from [seed, structure, CHAINS_STREAM, 1], so every other structure and its runs are as they
were; run_structure draws them only when the study asks, as it does obstacles): two chains, three in a quarter of
them, of 1 ... 4 links each (random_chains: kinds, twists and capsules as above, at least one capsule per chain, one
link restitution for every pair; no obstacles), each run placing every chain's base uniformly in a cube as wide as
the chains together and redrawing until no link pair of a chain or across two chains overlaps, each base driven
towards the others (random_chains_run); rates up to 20 rad/s; DOPRI5 and DOP853 at rtol 1e-11 ... 1e-6 (atol = rtol
x the shortest link, at least 1e-16) and RK4 at dt 1e-5 ... 1e-3 s.  A *structure* (n, link kinds, twists, planar
or not) is compiled once; its runs draw new lengths, masses, inertias, walls, restitutions, start and integrator
through the parameter vector and the start override (a structure of several chains: each chain's own parameters,
c2.l_1 ..., in the model's vector; the chains' coordinates stacked, chain k's after the earlier chains').

Every run is checked independently of the engine's own checks (``check_run``):
  * no NaN in the samples, the impact states and the final state;
  * penetration: the compiled gap kernel on every sample and impact state >= -PEN_TOL (relative to the
    chain's extent, plus the simultaneity window of the adaptive methods; RK4_PEN x the extent for RK4);
  * capsules against walls, in numpy from the joint points (model.contact_points): a capsule link's wall gap,
    the distance of its segment's nearest point (an end point) to the wall less its radius, >= -the same tolerance;
    with several chains every chain's links (its rows of the joint points, counted here from the chains' sizes)
    against the walls its own points touch, line links included;
  * capsules against capsules: for every link pair of the scene, the distance of the two segments (an
    independent closest-points computation, not the model's link_gap) less r_i + r_j >= -the same tolerance;
    with several chains every chain's own pairs and every pair of links of two chains with a capsule among them
    (all_link_pairs, reported apart as "capsules of two chains overlap");
  * obstacles: every link's gap to every obstacle, the distance of its segment from a sphere's centre or a bar's
    segment less both radii, or for a box the least of an own point-box signed distance along the segment (dense
    samples, then a ternary search) less the link's radius, >= -the same tolerance;
  * no energy gain at an impact: T from the recorded velocities at the impact configuration, after <=
    before (1 + tol), tol = max(ENERGY_TOL, 10 x the impact's stated round-off bound);
  * e = 1 kept: where every contact that took an impulse is on a wall with e = 1, |T_after + energy taken
    by landings - T_before| <= tol T_before;
  * honest accuracy: an impact whose round-off bound exceeds 1e-6 is named in the result's warnings;
  * friction only takes energy: the energy it took >= -ENERGY_TOL x the run's energy scale;
  * the run ends within its wall-time budget (the ``max_wall_time`` it was given, plus slack).
Outcomes are classed by message (numbers stripped).  A run *fails* on a violated check, an exception,
or a stop from the engine's own post-impact checks or a non-finite state (FAILURE_PATTERNS); a stop with
a physical reason (an RK4 step past stability, the wall-time budget, max_impacts) is a clean end.
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import multiprocessing
import re
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from codegen.scene import (Chains, LineLink, Obstacle, RigidLink, Scene, SceneError, Wall, WALL_NAMES,
                           contact_points as scene_contact_points)

PEN_TOL = 1e-9            # m per m of the chain's extent (at least 1e-9 m), see check_run
RK4_PEN = 1e-5            # RK4 has no tolerance: its crossings are located on a cubic Hermite interpolant
ENERGY_TOL = 1e-7         # relative energy change allowed at an impact (round-off of ill-conditioned laws)
BUDGET = 20.0             # s of wall time per run
BUDGET_SLACK = 5.0        # s beyond the budget before a run counts as over it
T_END_MAX = 2.0           # s
ROUGH_SHARE = 0.3         # structures whose walls have Coulomb friction (c_f uniform in [0, 1.5] per run and wall)
ROUGH_STREAM = 7919       # the random stream that decides it, apart from the structure's own
CAPSULE_SHARE = 0.25      # structures with capsule links (drawn among the frictionless ones)
CAPSULE_STREAM = 104729   # the child stream of the structure's seed that decides it and draws the radii
ROUGH_CAPSULE_SHARE = 1 / 3  # rough structures with capsule links (a tenth of all), capsules on rough walls
ROUGH_CAPSULE_STREAM = 130363  # the child stream that decides it and draws their radii
CAPSULE_LINK = 0.7        # probability that a link of a capsule structure is a capsule
RADIUS_RANGE = (5e-5, 5e-2)       # m, log-uniform
LENGTH_PER_RADIUS = (20.0, 2e4)   # a capsule structure's link lengths / its largest radius, log-uniform
START_TRIES = 200         # starts drawn before a capsule structure's run gives up finding one without overlap
OBSTACLE_SHARE = 0.2      # structures whose runs have fixed obstacles in the box (the study's runs; see run_structure)
OBSTACLE_STREAM = 7       # the random stream [seed, structure, OBSTACLE_STREAM(, run)] that decides it and draws them
OBSTACLE_TRIES = 50       # placements drawn per obstacle before it is left out
OBSTACLE_CLEAR = 1e-2     # an obstacle's least gap to every link at the start, per m of the chain's extent
OBSTACLE_PARKED = 1e6     # m: where the obstacles of an obstacle model's own scene sit (every run moves them via p)
CHAINS_SHARE = 0.1        # structures drawn as several chains in one box (the study's; see draw_structure)
CHAINS_STREAM = 23        # the random stream [seed, structure, CHAINS_STREAM(, 1)] that decides it and draws them

# Stops that are failures of the engine: its own post-impact checks and non-finite states.
FAILURE_PATTERNS = (
    "still approaches", "energy increased", "elastic impact changed", "could not be solved to round-off",
    "NaN or infinite", "complementarity problem has no solution", "frictional impact law's solve",
    "gained kinetic energy",
)


# ---------------------------------------------------------------------------
# the distribution
# ---------------------------------------------------------------------------
def _log_uniform(rng, lo: float, hi: float) -> float:
    return float(10 ** rng.uniform(math.log10(lo), math.log10(hi)))


def _rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _random_link(rng, kind: str, planar: bool, radius: float = 0.0, reach: float = 0.0):
    """A link of the given kind and capsule radius; in a chain whose largest radius is reach > 0 the length is drawn
    against it (LENGTH_PER_RADIUS, with the same number of draws)."""
    lo, hi = (1e-3, 1e2) if reach == 0.0 else (reach * LENGTH_PER_RADIUS[0], min(1e2, reach * LENGTH_PER_RADIUS[1]))
    length, mass = _log_uniform(rng, lo, hi), _log_uniform(rng, 1e-4, 1e4)
    if kind == "line":
        mu = mass / length
        r = length * _log_uniform(rng, 1e-3, 1e-1)
        axial = mu * r * r / 2 * (_log_uniform(rng, 1e-8, 1.0) if rng.uniform() < 0.3 else 1.0)
        return LineLink(length, mu, (axial, mu * r * r / 4, mu * r * r / 4), radius)
    a, b, c = length, length * rng.uniform(0.05, 1.0), length * rng.uniform(0.05, 1.0)
    moments = mass / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    R = np.eye(3) if planar else _rotation(rng)
    inertia = R @ np.diag(moments) @ R.T
    inertia = (inertia + inertia.T) / 2
    com = (length * rng.uniform(0.1, 0.9), 0.0 if planar else length * rng.uniform(-0.2, 0.2),
           0.0 if planar else length * rng.uniform(-0.2, 0.2))
    return RigidLink(length, mass, com, tuple(map(tuple, inertia)), radius)


def random_structure(rng, index: int, n_max: int = 8, capsules: bool = True, rough_capsules: bool = True) -> Scene:
    """A compiled model's worth of randomness: n, link kinds, twists, planar or spatial, gravity, capsule radii.  The
    numbers (lengths, masses, walls, start) are redrawn per run.  capsules=False: the structure as drawn before
    capsules were part of the distribution (the same draws without the radii); rough_capsules=False: as drawn before
    capsules joined the rough structures."""
    n = int(rng.integers(1, n_max + 1))
    planar = rng.uniform() < 0.35
    kinds = [str(rng.choice(["line", "rigid"])) for _ in range(n)]
    links = tuple(_random_link(rng, kind, planar) for kind in kinds)
    twists = ()
    if not planar and n > 1:
        twists = tuple(tuple(map(tuple, np.eye(3) if rng.uniform() < 0.3 else _rotation(rng))) for _ in range(n - 1))
    gravity = float(rng.choice([0.0, 9.81]))
    # friction on the walls of some structures, drawn apart so that the frictionless structures and their runs
    # stay those of earlier releases of this study
    rough = np.random.default_rng([index, ROUGH_STREAM]).uniform() < ROUGH_SHARE
    # capsules on some frictionless structures (as drawn since capsules joined the study), drawn from a child stream of the
    # structure's seed so that the other structures and their runs stay as they were
    side = _child_stream(rng, CAPSULE_STREAM)
    link_e = None
    if capsules and not rough and side.uniform() < CAPSULE_SHARE / (1.0 - ROUGH_SHARE):
        links, link_e = _capsules(side, links)
    # and on some rough ones, from a stream of their own (the frictionless structures stay as drawn above)
    rough_side = _child_stream(rng, ROUGH_CAPSULE_STREAM)
    if capsules and rough_capsules and rough and rough_side.uniform() < ROUGH_CAPSULE_SHARE:
        links, link_e = _capsules(rough_side, links)
    walls = tuple(Wall(name, -1e3 if name.endswith("min") else 1e3, 1.0, friction=0.5 if rough else 0.0)
                  for name in WALL_NAMES if not (planar and name.startswith("x3")))
    q0 = [-math.pi / 2, 0.0] + [0.0] * n + [0.0, 0.0, 0.0]
    return Scene(name=f"fuzz{index}", links=links, twists=twists, gravity=gravity, walls=walls, q0=tuple(q0),
                 link_restitution=link_e)


def _capsules(side, links):
    """Capsules drawn from the stream side: each link one with probability CAPSULE_LINK (at least one), radius
    log-uniform in RADIUS_RANGE; and the link pairs' restitution (0, 1 or uniform)."""
    n = len(links)
    capsule = side.uniform(size=n) < CAPSULE_LINK
    capsule[int(side.integers(n))] |= not capsule.any()
    radii = [_log_uniform(side, *RADIUS_RANGE) if c else 0.0 for c in capsule]
    return (tuple(replace(link, radius=r) for link, r in zip(links, radii)),
            float(side.choice([0.0, 1.0, side.uniform()])))


def _child_stream(rng, key: int):
    """An independent stream from rng's seed (a SeedSequence child), leaving rng's own draws untouched."""
    seq = rng.bit_generator.seed_seq
    return np.random.default_rng(np.random.SeedSequence(seq.entropy, spawn_key=tuple(seq.spawn_key) + (key,)))


def has_capsules(scene: Scene) -> bool:
    return any(link.radius > 0.0 for link in scene.links)


@dataclass
class Run:
    """One run of a structure: everything simulate() is given."""

    p: np.ndarray
    q0: np.ndarray
    qd0: np.ndarray
    t_end: float
    options: dict
    extent: float


def random_run(rng, scene: Scene, model) -> Run:
    """New lengths, masses, inertias (same link kinds and radii), a box around a random start (clear of the
    capsules, no link pair overlapping), restitutions, rates and an integrator."""
    planar = scene.walls and not any(w.name.startswith("x3") for w in scene.walls)
    reach = max(link.radius for link in scene.links)
    links = tuple(_random_link(rng, link.kind, planar, link.radius, reach) for link in scene.links)
    names = scene.parameter_names()
    p = model.p.copy()
    values = [v for link in links for v in link.param_values()]
    p[1:1 + len(values)] = values
    p[0] = scene.gravity
    n = scene.n
    radii = [link.radius for link in scene.links]
    for _ in range(START_TRIES):                 # capsule structures: a start where no pair overlaps
        q = np.zeros(scene.nq)
        q[2:2 + n] = rng.uniform(-math.pi, math.pi, n)
        if planar:
            q[0] = -math.pi / 2
        else:
            q[0] = rng.uniform(-math.pi, math.pi)
            q[1] = rng.uniform(-1.2, 1.2)
        q_model = model.layout.reduce(q)
        points = model.contact_points(q_model, p)
        if min(pair_gaps(points, radii, scene.link_pairs()), default=1.0) > 0.0:
            break
    else:
        raise ValueError(f"{scene.name}: no start without overlapping capsules in {START_TRIES} draws")
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = float(max((hi - lo).max(), min(link.length for link in links)))
    _draw_box(rng, names, p, lo, hi, extent, reach)
    omega = _log_uniform(rng, 0.1, 20.0)
    qd = np.zeros(scene.nq)
    qd[:2 + n] = rng.uniform(-omega, omega, 2 + n)
    qd[2 + n:] = rng.uniform(-1.0, 1.0, 3) * omega * extent
    if planar:
        qd[0] = qd[1] = qd[-1] = 0.0
    t_end, options = _draw_end_and_integrator(rng, model, q_model, qd, p, extent, min(link.length for link in links))
    return Run(p, q, qd, t_end, options, extent)


def _draw_box(rng, names, p: np.ndarray, lo, hi, extent: float, reach: float) -> None:
    """The walls around the start's points (lo, hi: their least and largest coordinates; margins 1e-3 ... 1 of the
    extent plus the largest radius), the walls' restitutions and friction coefficients, written into p."""
    for name in names:
        if name.startswith("wall_"):
            axis, side = int(name[6]) - 1, name.endswith("max")
            margin = extent * _log_uniform(rng, 1e-3, 1.0) + reach     # the box clears every capsule at the start
            p[names.index(name)] = hi[axis] + margin if side else lo[axis] - margin
        elif name.startswith("e_"):
            p[names.index(name)] = float(rng.choice([0.0, 1.0, rng.uniform()]))
        elif name.startswith("friction_"):
            p[names.index(name)] = float(rng.uniform(0.0, 1.5))


def _draw_end_and_integrator(rng, model, q_model, qd: np.ndarray, p, extent: float, shortest: float):
    """t_end (5 extents at the start's fastest point speed, 0.05 ... T_END_MAX s) and the integrator's options."""
    speed = max(float(np.abs(model.contact_velocities(q_model, model.layout.reduce(qd), p)).max()), 1e-6)
    t_end = float(min(T_END_MAX, max(0.05, 5.0 * extent / speed)))
    kind = rng.uniform()
    if kind < 0.4:
        method = "dopri5"
    elif kind < 0.8:
        method = "dop853"
    else:
        method = "rk4"
    if method == "rk4":
        options = {"method": "rk4", "dt": _log_uniform(rng, 1e-5, 1e-3)}
    else:
        rtol = _log_uniform(rng, 1e-11, 1e-6)
        options = {"method": method, "rtol": rtol, "atol": max(rtol * shortest, 1e-16)}
    return t_end, options


# ---------------------------------------------------------------------------
# several chains in one box
# ---------------------------------------------------------------------------
def has_chain_runs(seed: int, index: int) -> bool:
    """Whether the study draws structure ``index`` as several chains (random_chains) instead of random_structure's one
    chain: a stream apart from the structure's, so that every one-chain structure and its runs are as they were."""
    return bool(np.random.default_rng([seed, index, CHAINS_STREAM]).uniform() < CHAINS_SHARE)


def chains_stream(seed: int, index: int):
    """The stream a multi-chain structure and its runs are drawn from."""
    return np.random.default_rng([seed, index, CHAINS_STREAM, 1])


def random_chains(rng, index: int, n_max: int = 8) -> Chains:
    """Two chains (three in a quarter of the draws) of 1 ... min(4, n_max) links each, in one frictionless box: link
    kinds, twists and capsule radii as random_structure's capsule structures (each link a capsule with probability
    CAPSULE_LINK, at least one per chain; the lengths drawn against the scene's largest radius), planar or spatial
    for all of them, one restitution for every pair of capsule links (within a chain and across chains).  Each
    chain's own start (scene.q0) is its chain straightened from the origin, moved along X1 clear of the chains before
    it; the runs draw their own starts (random_chains_run)."""
    count = 3 if rng.uniform() < 0.25 else 2
    planar = rng.uniform() < 0.35
    gravity = float(rng.choice([0.0, 9.81]))
    link_e = float(rng.choice([0.0, 1.0, rng.uniform()]))
    walls = tuple(Wall(name, -1e3 if name.endswith("min") else 1e3, 1.0)
                  for name in WALL_NAMES if not (planar and name.startswith("x3")))
    sizes = [int(rng.integers(1, min(4, n_max) + 1)) for _ in range(count)]
    capsules = []
    for n in sizes:
        capsule = rng.uniform(size=n) < CAPSULE_LINK
        capsule[int(rng.integers(n))] |= not capsule.any()
        capsules.append([_log_uniform(rng, *RADIUS_RANGE) if c else 0.0 for c in capsule])
    reach = max(r for radii in capsules for r in radii)
    chains, cursor = [], -0.9e3
    for k, (n, radii) in enumerate(zip(sizes, capsules), start=1):
        links = tuple(_random_link(rng, str(rng.choice(["line", "rigid"])), planar, r, reach) for r in radii)
        twists = ()
        if not planar and n > 1:
            twists = tuple(tuple(map(tuple, np.eye(3) if rng.uniform() < 0.3 else _rotation(rng)))
                           for _ in range(n - 1))
        q0 = [-math.pi / 2, 0.0] + [0.0] * n + [0.0, 0.0, 0.0]
        chain = Scene(name=f"fuzz{index}_c{k}", links=links, twists=twists, gravity=gravity, walls=walls,
                      q0=tuple(q0), link_restitution=link_e)
        points = scene_contact_points(chain, np.array(q0))
        q0[n + 2] = cursor - points[:, 0].min() + reach         # the chain's least X1 just after the cursor
        cursor += points[:, 0].max() - points[:, 0].min() + 3 * reach
        chains.append(replace(chain, q0=tuple(q0)))
    return Chains(name=f"fuzz{index}", chains=tuple(chains), link_restitution=link_e)


def random_chains_run(rng, scene: Chains, model) -> Run:
    """A run of several chains: each chain's links redrawn as random_run's (same kinds and radii), their parameters
    written to the chain's own names in p (c2.l_1 ...); a start where each chain's angles are random and its base is
    placed uniformly in a cube as wide as the chains' extents together (no link pair of a chain or across chains
    overlapping: redrawn up to START_TRIES times), a box around it, restitutions, rates (each chain's base driven
    towards the others' centre by a random share of its speed, so that they meet) and an integrator."""
    planar = not any(w.name.startswith("x3") for w in scene.walls)
    reach = max(link.radius for link in scene.links)
    names = scene.parameter_names()
    p = model.p.copy()
    p[names.index("g")] = scene.gravity
    shortest = math.inf
    for k, chain in enumerate(scene.chains, start=1):
        links = tuple(_random_link(rng, link.kind, planar, link.radius, reach) for link in chain.links)
        values = [v for link in links for v in link.param_values()]
        own = chain.parameter_names()[1:1 + len(values)]          # the chain's link parameters, after g
        for name, value in zip(own, values):
            p[names.index(scene.combined_name(k, name))] = value
        shortest = min([shortest] + [link.length for link in links])
    pairs, radii = all_link_pairs(scene), point_radii(scene)
    bases = [scene.state_offset(k) + chain.n + 2 for k, chain in enumerate(scene.chains, start=1)]
    for _ in range(START_TRIES):
        q = np.zeros(scene.nq)
        for k, chain in enumerate(scene.chains, start=1):
            s = scene.state_offset(k)
            q[s + 2:s + 2 + chain.n] = rng.uniform(-math.pi, math.pi, chain.n)
            if planar:
                q[s] = -math.pi / 2
            else:
                q[s] = rng.uniform(-math.pi, math.pi)
                q[s + 1] = rng.uniform(-1.2, 1.2)
        points = model.contact_points(model.layout.reduce(q), p)     # every base at the origin
        span = sum(float(np.ptp(points[rows], axis=0).max()) for rows in chain_rows(scene))
        for b in bases:
            q[b:b + 3] = rng.uniform(-span / 2, span / 2, 3)
            if planar:
                q[b + 2] = 0.0
        q_model = model.layout.reduce(q)
        points = model.contact_points(q_model, p)
        if min(pair_gaps(points, radii, pairs), default=1.0) > 0.0:
            break
    else:
        raise ValueError(f"{scene.name}: no start without overlapping capsules in {START_TRIES} draws")
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = float(max((hi - lo).max(), shortest))
    _draw_box(rng, names, p, lo, hi, extent, reach)
    omega = _log_uniform(rng, 0.1, 20.0)
    qd = np.zeros(scene.nq)
    centre = points.mean(axis=0)
    for k, (chain, rows) in enumerate(zip(scene.chains, chain_rows(scene)), start=1):
        s, n = scene.state_offset(k), chain.n
        qd[s:s + 2 + n] = rng.uniform(-omega, omega, 2 + n)
        towards = centre - points[rows].mean(axis=0)
        towards /= max(float(np.linalg.norm(towards)), 1e-300)
        qd[s + 2 + n:s + 5 + n] = (rng.uniform(-1.0, 1.0, 3) + rng.uniform(0.0, 2.0) * towards) * omega * extent
        if planar:
            qd[s] = qd[s + 1] = qd[s + 4 + n] = 0.0
    t_end, options = _draw_end_and_integrator(rng, model, q_model, qd, p, extent, shortest)
    return Run(p, q, qd, t_end, options, extent)


def draw_structure(seed: int, index: int, n_max: int, chains: bool, rough_capsules: bool = True):
    """The study's structure ``index`` and the stream its runs are drawn from: several chains where ``chains`` and
    has_chain_runs say so, else random_structure's chain (rough_capsules=False: as drawn before capsules joined the
    rough structures)."""
    if chains and has_chain_runs(seed, index):
        rng = chains_stream(seed, index)
        return random_chains(rng, index, n_max), rng
    rng = np.random.default_rng([seed, index])
    return random_structure(rng, index, n_max, rough_capsules=rough_capsules), rng


def draw_run(rng, scene, model) -> Run:
    return random_chains_run(rng, scene, model) if isinstance(scene, Chains) else random_run(rng, scene, model)


def has_obstacle_runs(seed: int, index: int) -> bool:
    """Whether the study puts fixed obstacles into structure ``index``'s runs: a stream apart from the structure's,
    so that its chain, parameters and runs are those drawn without obstacles."""
    return bool(np.random.default_rng([seed, index, OBSTACLE_STREAM]).uniform() < OBSTACLE_SHARE)


def random_obstacles(rng, scene: Scene, model, run: Run) -> tuple[Obstacle, ...]:
    """One or two fixed obstacles for a run (spheres, bars or boxes, sizes 1e-2 ... 0.3 of the chain's extent), each
    centred inside the run's box (in the plane of motion of a planar chain) and at least OBSTACLE_CLEAR x the extent
    from every link at the start; a draw that finds no such place in OBSTACLE_TRIES is left out."""
    names = scene.parameter_names()
    walls = {w.name: float(run.p[names.index(f"wall_{w.name}")]) for w in scene.walls}
    points = model.contact_points(model.layout.reduce(run.q0), run.p)
    radii = [link.radius for link in scene.links]
    lo = [walls.get(f"x{k + 1}_min", float(points[:, k].mean())) for k in range(3)]
    hi = [walls.get(f"x{k + 1}_max", float(points[:, k].mean())) for k in range(3)]
    obstacles = []
    for j in range(int(rng.integers(1, 3))):
        kind = str(rng.choice(["sphere", "bar", "box"]))
        for _ in range(OBSTACLE_TRIES):
            centre = rng.uniform(lo, hi)
            size = run.extent * _log_uniform(rng, 1e-2, 0.3)
            name = f"{kind}_{'ab'[j]}"
            if kind == "sphere":
                o = Obstacle.sphere(name, tuple(centre), size)
            elif kind == "bar":
                axis = rng.normal(size=3)
                axis *= run.extent * rng.uniform(0.1, 0.5) / np.linalg.norm(axis)
                o = Obstacle.bar(name, tuple(centre - axis), tuple(centre + axis), size / 3)
            else:
                o = Obstacle.box(name, tuple(centre), tuple(size * rng.uniform(0.2, 1.0, 3)), _rotation(rng))
            if min(obstacle_gaps(points, radii, [o])) <= OBSTACLE_CLEAR * run.extent:
                continue
            try:                                     # the structure's own start (scene.q0) must be clear of it too
                replace(scene, obstacles=(*obstacles, o))
            except SceneError:
                continue
            obstacles.append(o)
            break
    return tuple(obstacles)


def obstacle_structure(obstacles) -> tuple[Obstacle, ...]:
    """The obstacles with their names, kinds, links and restitutions but a fixed geometry, parked OBSTACLE_PARKED m
    out along every axis with unit sizes: the scene of a structure with these is the same for every run that draws
    obstacles of the same names and kinds, so its model is compiled (and cached) once; each run moves the obstacles
    to its own places through the parameter vector (obstacle_run)."""
    far = [OBSTACLE_PARKED] * 3
    parked = {"sphere": far + [1.0], "capsule": far + [OBSTACLE_PARKED + 1.0, OBSTACLE_PARKED, OBSTACLE_PARKED, 1.0],
              "box": far + [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]}
    return tuple(o.with_geometry(parked[o.kind]) for o in obstacles)


def obstacle_run(rng, scene: Scene, model, run: Run, obstacles, load) -> tuple[Scene, object, Run]:
    """The structure with the run's obstacles, the model of the structure with obstacles of those names and kinds
    (``load``: scene -> compiled model, given the parked obstacle_structure: an obstacle's geometry is a runtime
    parameter) and the run with the obstacles' restitutions (0, 1 or uniform) and geometry after its parameters."""
    before = scene.parameter_names()
    structure = replace(scene, obstacles=obstacle_structure(obstacles))
    scene = replace(scene, obstacles=tuple(obstacles))           # validated: the structure's own start is clear
    model = load(structure)
    names = model.parameter_names
    if names[:len(run.p)] != before or names != scene.parameter_names():
        raise AssertionError("obstacles changed the order of the structure's parameters")
    p = model.p.copy()
    p[:len(run.p)] = run.p
    for o in obstacles:
        p[names.index(f"e_{o.name}")] = float(rng.choice([0.0, 1.0, rng.uniform()]))
    for o in scene.obstacles:                                     # the run's places and sizes
        for name, value in zip(o.geometry_names, o.geometry_values):
            p[names.index(name)] = value
    return scene, model, replace(run, p=p)


# ---------------------------------------------------------------------------
# the checks
# ---------------------------------------------------------------------------
@dataclass
class Outcome:
    case: str                 # "structure-seed/run": rerun with --case
    n: int
    planar: bool
    method: str
    status: int
    outcome: str              # 'ok', the stop message with numbers stripped, or 'exception: ...'
    failed: bool
    violations: list = field(default_factory=list)
    impacts: int = 0
    seconds: float = 0.0
    message: str = ""
    roundoff: float = 0.0     # the largest relative accuracy an impact of the run states (record.roundoff), or 0
    inaccurate: bool = False  # the run stopped with an impact whose accuracy is useless (GAC_ERR_IMPACT_ACCURACY)
    cause: str = ""           # for a run whose least accurate impact is above 1e-10: why (runtime accuracy_cause)
    capsules: bool = False    # the structure has capsule links (and link pairs)
    obstacles: int = 0        # fixed obstacles in the run's box
    chains: int = 1           # chains in the box (random_chains: 2 or 3)
    strikes_across: int = 0   # impacts with a contact between links of two chains (a pair's or an end's, global links)
    sensitivities: str = ""   # with --sensitivities: 'valid' (differentiated to the run's end), or the status of the
                              # first event not differentiated (runtime.sensitivities.STATUS_WORDS)
    sensitivity_t: float = -1.0   # s: that event's time (-1: none)


def classify(message: str) -> str:
    return re.sub(r"[-+]?\d[\d.]*(e[-+]?\d+)?", "#", message)[:120]


def segment_distance(a0, a1, b0, b1) -> float:
    """min |a(s) - b(t)| over 0 <= s, t <= 1 for the segments a(s) = a0 + s (a1 - a0), b(t) = b0 + t (b1 - b0): the
    smallest of the candidates, the interior stationary point (when the segments are not parallel) and the minimum
    along each edge of the unit square (one clamped quadratic)."""
    d1, d2, r = a1 - a0, b1 - b0, a0 - b0
    aa, bb, ab = float(d1 @ d1), float(d2 @ d2), float(d1 @ d2)
    pairs = []
    det = aa * bb - ab * ab
    if det > 1e-12 * aa * bb:                   # the normal equations of |r + s d1 - t d2|^2
        s = (ab * float(d2 @ r) - bb * float(d1 @ r)) / det
        t = (aa * float(d2 @ r) - ab * float(d1 @ r)) / det
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
            pairs.append((s, t))
    for s in (0.0, 1.0):
        pairs.append((s, min(max(float((r + s * d1) @ d2) / bb, 0.0), 1.0) if bb > 0.0 else 0.0))
    for t in (0.0, 1.0):
        pairs.append((min(max(-float((r - t * d2) @ d1) / aa, 0.0), 1.0) if aa > 0.0 else 0.0, t))
    return min(float(np.linalg.norm(r + s * d1 - t * d2)) for s, t in pairs)


def pair_gaps(points: np.ndarray, radii, pairs) -> list[float]:
    """Each link pair's gap from the joint points O_1..O_{n+1} (rows of points): the distance of the segments
    O_i O_{i+1} and O_j O_{j+1} less r_i + r_j."""
    return [segment_distance(points[i - 1], points[i], points[j - 1], points[j]) - radii[i - 1] - radii[j - 1]
            for i, j in pairs]


def chains_of(scene) -> tuple:
    """The one-chain scenes of a scene: a Chains' chains, or the scene itself."""
    return tuple(scene.chains) if isinstance(scene, Chains) else (scene,)


def chain_rows(scene) -> list[range]:
    """The rows of each chain's joint points O_1..O_{n+1} in the model's contact_points (a chain's n + 1 points after
    the earlier chains'), counted here from the chains' sizes."""
    rows, start = [], 0
    for chain in chains_of(scene):
        rows.append(range(start, start + chain.n + 1))
        start += chain.n + 1
    return rows


def point_radii(scene) -> list[float]:
    """The capsule radius of the link that starts at each joint point (0 at each chain's last point), in the rows of
    contact_points: pair_gaps' radii, link i being the segment of rows i - 1 and i."""
    return [r for chain in chains_of(scene) for r in [link.radius for link in chain.links] + [0.0]]


def all_link_pairs(scene) -> list[tuple[int, int]]:
    """Every link pair that must stay apart, numbered as pair_gaps reads them (link i: the segment of rows i - 1, i,
    the global link number of a model of several chains): each chain's own pairs (Scene.link_pairs: not adjacent, a
    capsule among them), then pairs_across."""
    rows = chain_rows(scene)
    return [(rows[k].start + i, rows[k].start + j) for k, chain in enumerate(chains_of(scene))
            for i, j in chain.link_pairs()] + pairs_across(scene)


def pairs_across(scene) -> list[tuple[int, int]]:
    """Every pair of links of two different chains with radii adding up to more than 0 (all_link_pairs' numbers)."""
    rows, radii = chain_rows(scene), point_radii(scene)
    links = [[rows[k].start + i for i in range(1, chain.n + 1)] for k, chain in enumerate(chains_of(scene))]
    return [(i, j) for k in range(len(links)) for l in range(k + 1, len(links))
            for i in links[k] for j in links[l] if radii[i - 1] + radii[j - 1] > 0.0]


def box_signed_distance(x, centre, half_extents, rotation) -> float:
    """The signed distance (m, negative inside) of point x from an oriented box: in the box's axes y = R^T (x - c),
    the length of y's excess over the half extents outside, the largest |y_k| - h_k (<= 0) inside."""
    excess = np.abs(np.asarray(rotation).T @ (np.asarray(x) - np.asarray(centre))) - np.asarray(half_extents)
    return float(np.linalg.norm(np.maximum(excess, 0.0)) + min(float(excess.max()), 0.0))


def segment_box_distance(p0, p1, obstacle) -> float:
    """The least signed distance of segment p0-p1 from a box obstacle: 257 samples along it, then a ternary search
    about the least sample (the signed distance of a convex body is convex along a line)."""
    f = lambda s: box_signed_distance(p0 + s * (p1 - p0), obstacle.a, obstacle.half_extents, obstacle.box_rotation)
    grid = np.linspace(0.0, 1.0, 257)
    values = [f(s) for s in grid]
    k = int(np.argmin(values))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, 256)]
    for _ in range(60):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        lo, hi = (lo, m2) if f(m1) <= f(m2) else (m1, hi)
    return min(values[k], f(0.5 * (lo + hi)))


def obstacle_gaps(points: np.ndarray, radii, obstacles) -> list[float]:
    """Each link's gap to each fixed obstacle it can touch, from the joint points: a sphere's or bar's the distance of
    the two segments less both radii, a box's the least signed distance of the link's segment less its radius."""
    gaps = []
    for o in obstacles:
        for i in (o.links or range(1, len(radii) + 1)):
            p0, p1 = points[i - 1], points[i]
            if o.kind == "box":
                gaps.append(segment_box_distance(p0, p1, o) - radii[i - 1])
            else:
                a, b = (np.asarray(x, dtype=float) for x in o.segment)
                gaps.append(segment_distance(p0, p1, a, b) - radii[i - 1] - o.radius)
    return gaps


def check_obstacles(model, run: Run, states, pen_tol: float) -> list[str]:
    """No link inside a fixed obstacle beyond pen_tol on full-layout states (obstacle_gaps), each obstacle where the
    run's parameters put it."""
    names = model.parameter_names
    obstacles = [o.with_geometry([run.p[names.index(name)] for name in o.geometry_names]) for o in model.scene.obstacles]
    if not obstacles:
        return []
    radii = [link.radius for link in model.scene.links]
    deepest = min((min(obstacle_gaps(model.contact_points(model.layout.reduce(q), run.p), radii, obstacles))
                   for q in states), default=math.inf)
    if deepest < -pen_tol:
        return [f"obstacle penetrated by a link by {-deepest:.3g} m > {pen_tol:.3g} m"]
    return []


def capsule_wall_gaps(points: np.ndarray, radii, walls, every_link: bool = False) -> list[float]:
    """Each capsule link's gap to each wall from the joint points: the signed distance of its segment's nearest
    point (the nearer end, the distance being linear along the segment) less its radius; every_link: the links of
    no thickness too (their nearer joint point's distance)."""
    gaps = []
    for w in walls:
        inward = points[:, w.axis] - w.position if w.side < 0 else w.position - points[:, w.axis]
        gaps += [min(inward[p - 1] for p in (i, i + 1) if p in w.points) - r for i, r in enumerate(radii, start=1)
                 if (r > 0.0 or every_link) and (i in w.points or i + 1 in w.points)]
    return gaps


def check_capsules(model, run: Run, states, pen_tol: float) -> list[str]:
    """The capsules' checks (module docstring) on full-layout states: walls at the run's positions in p.  Several
    chains: every chain's links against the walls its own points touch (each link, a capsule or not: a line link's
    gap is its nearer joint point's), every chain's own pairs and every pair across chains (all_link_pairs)."""
    scene = model.scene
    several = isinstance(scene, Chains)
    radii = point_radii(scene)
    if not any(radii):
        return []
    names = scene.parameter_names()
    rows = chain_rows(scene)
    pairs, across = all_link_pairs(scene), set(pairs_across(scene))
    chains = [(chain, [link.radius for link in chain.links],
               [replace(w, position=float(run.p[names.index(f"wall_{w.name}")])) for w in chain.walls])
              for chain in chains_of(scene)]
    violations = []
    deepest_wall = deepest_pair = deepest_across = math.inf
    for q in states:
        points = model.contact_points(model.layout.reduce(q), run.p)
        for (chain, chain_radii, walls), r in zip(chains, rows):
            gaps = capsule_wall_gaps(points[r.start:r.stop], chain_radii, walls, every_link=several)
            deepest_wall = min([deepest_wall] + gaps)
        gaps = pair_gaps(points, radii, pairs)
        deepest_pair = min([deepest_pair] + [g for g, pair in zip(gaps, pairs) if pair not in across])
        deepest_across = min([deepest_across] + [g for g, pair in zip(gaps, pairs) if pair in across])
    if deepest_wall < -pen_tol:
        what = "a link" if several else "capsule"
        violations.append(f"{what} penetrates a wall by {-deepest_wall:.3g} m > {pen_tol:.3g} m")
    if deepest_pair < -pen_tol:
        violations.append(f"capsules overlap by {-deepest_pair:.3g} m > {pen_tol:.3g} m")
    if deepest_across < -pen_tol:
        violations.append(f"capsules of two chains overlap by {-deepest_across:.3g} m > {pen_tol:.3g} m")
    return violations


def check_run(model, run: Run, result, seconds: float, budget: float) -> list[str]:
    """The independent checks (module docstring); returns the violations."""
    p, layout, violations = run.p, model.layout, []
    arrays = [result.q, result.qd, result.q_final, result.qd_final] + \
             [a for i in result.impacts for a in (i.qd_before, i.qd_after)]
    if not all(np.all(np.isfinite(a)) for a in arrays):
        return ["non-finite state"]
    method = run.options["method"]
    window = 0.0 if method == "rk4" else 100 * (run.options["atol"] + run.options["rtol"] * run.extent)
    pen_tol = PEN_TOL * max(1.0, run.extent) + window + (RK4_PEN * run.extent if method == "rk4" else 0.0)
    states = [layout.reduce(q) for q in result.q] + [layout.reduce(i.q) for i in result.impacts]
    if states and model.contacts:
        deepest = min(float(model.contact_gaps(q, p).min()) for q in states)
        if deepest < -pen_tol:
            violations.append(f"penetration {-deepest:.3g} m > {pen_tol:.3g} m")
    violations += check_capsules(model, run, list(result.q) + [i.q for i in result.impacts], pen_tol)
    violations += check_obstacles(model, run, list(result.q) + [i.q for i in result.impacts], pen_tol)
    for impact in result.impacts:
        q = layout.reduce(impact.q)
        T0 = model.energy(q, layout.reduce(impact.qd_before), p)[0]
        T1 = model.energy(q, layout.reduce(impact.qd_after), p)[0]
        tol = max(ENERGY_TOL, 10 * impact.roundoff)
        if impact.roundoff > 1e-6 and not any(f"{impact.t:.9g}" in w for w in result.warnings):
            violations.append(f"impact at t = {impact.t:.6g} s with round-off bound {impact.roundoff:.2g} not "
                              "named in the warnings")
            break
        if T1 > T0 * (1 + tol) + 1e-300:
            violations.append(f"energy gain at t = {impact.t:.6g} s: {T0!r} -> {T1!r} J")
            break
        if impact.law_elastic:
            if abs(T1 + impact.energy_rest - T0) > tol * T0:
                violations.append(f"elastic impact at t = {impact.t:.6g} s changed T: {T0!r} -> {T1!r} J")
                break
    if result.loss_friction < -ENERGY_TOL * result.energy_scale:
        violations.append(f"friction gave energy: {result.loss_friction!r} J")
    if seconds > budget + BUDGET_SLACK:
        violations.append(f"over budget: {seconds:.1f} s")
    return violations


def study_model(scene, tangent: bool = False):
    """The study's compiled model of a scene (cached): the general layout, so that every structure keeps the
    coordinates it was drawn with, with both base charts and the long-double kernels of the impact's accuracy; with
    ``tangent`` its tangent kernels too (the sensitivities' runs)."""
    from runtime.model import load_model
    return load_model(scene, specialise=False, tangent=tangent)


def sensitivity_directions(model) -> list[str]:
    """The directions a --sensitivities run carries: g (where the scene has gravity among its parameters), the first
    coordinate's start and start velocity, the first restitution and the first friction coefficient."""
    names = list(model.parameter_names)
    first = model.scene.full_coordinate_names()[model.layout.free[0]]
    directions = [f"q0[{first}]", f"qd0[{first}]"]
    directions += [name for name in names if name == "g"]
    directions += [name for name in names if name.split(".")[-1].startswith("e_")][:1]
    directions += [name for name in names if name.split(".")[-1].startswith("friction_")][:1]
    return directions


def run_structure(args) -> list[Outcome]:
    """Compile one structure and run its runs (one worker's job).  args: (seed, index, runs, budget, n_max[,
    obstacles[, chains]]); obstacles True (the study's runs): a structure that has_obstacle_runs puts each run's
    random_obstacles into the box, the structure compiled once per obstacles' names and kinds and the run's obstacles
    set through p (obstacle_run; False: the runs as drawn);
    chains True (the study's runs): a structure that has_chain_runs is drawn as several chains (random_chains, no
    obstacles; False: random_structure's chain); sensitivities True: the models carry tangent kernels and each run
    its sensitivities along sensitivity_directions (the run itself is the same), the outcome naming how far they
    went."""
    seed, index, runs, budget, n_max = args[:5]
    obstacle_runs = bool(args[5]) if len(args) > 5 else False
    chain_runs = bool(args[6]) if len(args) > 6 else False
    with_sensitivities = bool(args[7]) if len(args) > 7 else False
    load = functools.partial(study_model, tangent=with_sensitivities)
    from runtime.simulate import accuracy_cause, impact_contact_indices, simulate
    scene, rng = draw_structure(seed, index, n_max, chain_runs)
    count = len(chains_of(scene))
    obstacle_runs = obstacle_runs and count == 1 and has_obstacle_runs(seed, index)
    planar = not any(wall.name.startswith("x3") for wall in scene.walls)   # a planar structure has no X3 walls
    capsules = has_capsules(scene)
    outcomes = []
    try:
        model = load(scene)
    except Exception as exc:                           # noqa: BLE001 - reported as an outcome
        return [Outcome(f"{seed}-{index}/{k}", scene.n, False, "-", -1, f"exception: {classify(str(exc))}", True,
                        message=str(exc), capsules=capsules, chains=count) for k in range(runs)]
    for k in range(runs):
        case = f"{seed}-{index}/{k}"
        try:
            run = draw_run(rng, scene, model)
        except ValueError as exc:                      # no start without overlapping capsules: the draw's limit
            outcomes.append(Outcome(case, scene.n, planar, "-", -1, f"no start: {classify(str(exc))}", False,
                                    message=str(exc), capsules=capsules, chains=count))
            continue
        run_model, obstacles = model, ()
        if obstacle_runs:
            obstacle_rng = np.random.default_rng([seed, index, OBSTACLE_STREAM, k])
            obstacles = random_obstacles(obstacle_rng, scene, model, run)
        if obstacles:
            try:
                _, run_model, run = obstacle_run(obstacle_rng, scene, model, run, obstacles, load)
            except Exception as exc:                   # noqa: BLE001 - reported as an outcome
                outcomes.append(Outcome(case, scene.n, planar, run.options["method"], -1,
                                        f"exception: {classify(str(exc))}", True, message=str(exc),
                                        capsules=capsules, obstacles=len(obstacles), chains=count))
                continue
        start = time.perf_counter()
        extra = {"sensitivities": sensitivity_directions(run_model)} if with_sensitivities else {}
        try:
            result = simulate(run_model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, max_wall_time=budget,
                              t_eval=np.linspace(0.0, run.t_end, 201), **run.options, **extra)
        except ValueError as exc:                      # a refused setting (an RK4 step past stability)
            seconds = time.perf_counter() - start
            outcomes.append(Outcome(case, scene.n, planar, run.options["method"], -1,
                                    f"refused: {classify(str(exc))}", False, seconds=seconds, message=str(exc),
                                    capsules=capsules, obstacles=len(obstacles), chains=count))
            continue
        except Exception:                              # noqa: BLE001 - a traceback is a failure
            outcomes.append(Outcome(case, scene.n, planar, run.options["method"], -1, "exception", True,
                                    message=traceback.format_exc()[-400:], capsules=capsules,
                                    obstacles=len(obstacles), chains=count))
            continue
        seconds = time.perf_counter() - start
        violations = check_run(run_model, run, result, seconds, budget)
        text = "ok" if result.status == 0 else classify(result.message)
        failed = bool(violations) or any(pattern in result.message for pattern in FAILURE_PATTERNS)
        roundoff = max([i.roundoff for i in result.impacts], default=0.0)
        across = set(pairs_across(scene))              # (a pair's contact or an end's: the two links it joins)
        strikes = sum(any(c.kind == "link" and tuple(sorted(c.links)) in across for c in i.contacts)
                      for i in result.impacts)
        inaccurate = "could not be solved to round-off" in result.message   # GAC_ERR_IMPACT_ACCURACY
        cause = ""
        if roundoff > 1e-10:                           # the least accurate impact's cause, as the warnings name it
            worst = max(result.impacts, key=lambda i: i.roundoff)
            reduce = run_model.layout.reduce
            cause = accuracy_cause(run_model, run.p, reduce(worst.q), reduce(worst.qd_before),
                                   impact_contact_indices(run_model, worst), worst.law, worst.residual,
                                   worst.roundoff_cause)
        sens, sens_t = "", -1.0
        if with_sensitivities and result.sensitivities is not None:
            sens = "valid" if result.sensitivities.valid else result.sensitivities.status
            if not result.sensitivities.valid and result.sensitivities.t_event is not None:
                sens_t = float(result.sensitivities.t_event)
        outcomes.append(Outcome(case, scene.n, planar, run.options["method"], result.status, text, failed,
                                violations, len(result.impacts), seconds, result.message, roundoff, inaccurate,
                                cause, capsules, len(obstacles), count, strikes, sens, sens_t))
    return outcomes


def fuzz(runs: int = 1000, per_structure: int = 10, seed: int = 0, jobs: int | None = None,
         budget: float = BUDGET, n_max: int = 8, progress=None, obstacles: bool = True,
         chains: bool = True, sensitivities: bool = False) -> list[Outcome]:
    """Run ``runs`` random runs (``per_structure`` per compiled structure) on ``jobs`` processes; ``obstacles``: fixed
    obstacles in the runs of a share of the structures; ``chains``: a share of the structures drawn as several
    chains; ``sensitivities``: each run carries its sensitivities (run_structure)."""
    structures = max(1, math.ceil(runs / per_structure))
    tasks = [(seed, index, min(per_structure, runs - index * per_structure), budget, n_max, obstacles, chains,
              sensitivities) for index in range(structures)]
    outcomes: list[Outcome] = []
    start = time.perf_counter()
    jobs = jobs or multiprocessing.cpu_count()
    with multiprocessing.get_context("spawn").Pool(jobs) as pool:
        for done, batch in enumerate(pool.imap_unordered(run_structure, tasks), start=1):
            outcomes += batch
            if progress:
                failed = sum(o.failed for o in outcomes)
                progress(f"[{done}/{structures}] {len(outcomes)} runs, {failed} failed, "
                         f"{time.perf_counter() - start:.0f} s")
    return sorted(outcomes, key=lambda o: [int(x) for x in re.split(r"[-/]", o.case)])


def table(outcomes: list[Outcome]) -> str:
    counts: dict[tuple[bool, str], int] = {}
    for o in outcomes:
        key = (o.failed, o.outcome if not o.violations else "check: " + classify(o.violations[0]))
        counts[key] = counts.get(key, 0) + 1
    lines = ["| outcome | runs | failure |", "|---|---|---|"]
    for (failed, text), count in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0][1])):
        lines.append(f"| {text} | {count} | {'yes' if failed else ''} |")
    return "\n".join(lines)


def accuracy_summary(outcomes: list[Outcome]) -> str:
    """How many runs state an impact less accurate than 1e-10 and 1e-6 (record.roundoff) and how many stop with an
    impact whose accuracy is useless (GAC_ERR_IMPACT_ACCURACY)."""
    n = len(outcomes)
    worse_10 = sum(o.roundoff > 1e-10 or o.inaccurate for o in outcomes)
    worse_6 = sum(o.roundoff > 1e-6 or o.inaccurate for o in outcomes)
    stopped = sum(o.inaccurate for o in outcomes)
    flagged = [f"- {o.case}: {o.roundoff:.2g}, {o.cause}" for o in outcomes if o.roundoff > 1e-10 and o.cause]
    return (f"impact accuracy: {worse_10} of {n} runs state an impact less accurate than 1e-10, {worse_6} than 1e-6; "
            f"{stopped} stop with an impact of useless accuracy" + "".join("\n" + line for line in flagged))


def sensitivity_summary(outcomes: list[Outcome]) -> str:
    """How far the sensitivities of the runs that reached their end went: differentiated to it, or the status of the
    first event not differentiated (runs that stopped left out: the run itself ended)."""
    ended = [o for o in outcomes if o.sensitivities and o.status == 0]
    if not ended:
        return ""
    counts: dict[str, int] = {}
    for o in ended:
        counts[o.sensitivities] = counts.get(o.sensitivities, 0) + 1
    valid = counts.get("valid", 0)
    lines = [f"Sensitivities: {valid} of the {len(ended)} runs that reached t_end ({100 * valid / len(ended):.1f} %) "
             "differentiated to their end; the others ended by:", "", "| first event not differentiated | runs |",
             "|---|---|"]
    for text, count in sorted(counts.items(), key=lambda kv: -kv[1]):
        if text != "valid":
            lines.append(f"| {text} | {count} |")
    return "\n".join(lines) + "\n"


def capsule_summary(outcomes: list[Outcome]) -> str:
    """How many structures (and their runs) have capsule links, and how those runs ended."""
    structures = {o.case.split("/")[0] for o in outcomes}
    runs = [o for o in outcomes if o.capsules]
    with_caps = {o.case.split("/")[0] for o in runs}
    checks = sum(any(v.startswith("caps") for v in o.violations) for o in runs)
    return (f"capsules: {len(with_caps)} of {len(structures)} structures ({len(runs)} runs) have capsule links; "
            f"{sum(o.failed for o in runs)} of their runs failed, {checks} on a capsule check, "
            f"{sum(o.outcome == 'ok' for o in runs)} ended ok")


def chains_summary(outcomes: list[Outcome]) -> str:
    """Which structures are several chains in one box, how many runs they had and how those ended."""
    structures = {o.case.split("/")[0] for o in outcomes}
    runs = [o for o in outcomes if o.chains > 1]
    several = sorted({o.case.split("/")[0]: o.chains for o in runs}.items(),
                     key=lambda kv: [int(x) for x in kv[0].split("-")])
    checks = sum(any(v.startswith(("capsule", "a link")) for v in o.violations) for o in runs)
    listed = ", ".join(f"{case} ({count} chains)" for case, count in several)
    return (f"several chains: {len(several)} of {len(structures)} structures ({len(runs)} runs) are several chains in "
            f"one box{': ' + listed if listed else ''}; {sum(o.failed for o in runs)} of their runs failed, {checks} on "
            f"a wall or link-pair check, {sum(o.outcome == 'ok' for o in runs)} ended ok; "
            f"{sum(o.strikes_across > 0 for o in runs)} runs had links of two chains strike "
            f"({sum(o.strikes_across for o in runs)} such impacts)")


def obstacle_summary(outcomes: list[Outcome]) -> str:
    """How many structures (and their runs) have fixed obstacles, and how those runs ended."""
    structures = {o.case.split("/")[0] for o in outcomes}
    runs = [o for o in outcomes if o.obstacles]
    with_obstacles = {o.case.split("/")[0] for o in runs}
    checks = sum(any(v.startswith("obstacle") for v in o.violations) for o in runs)
    return (f"obstacles: {len(with_obstacles)} of {len(structures)} structures ({len(runs)} runs, "
            f"{sum(o.obstacles for o in runs)} obstacles) have fixed obstacles; {sum(o.failed for o in runs)} of their "
            f"runs failed, {checks} on an obstacle check, {sum(o.outcome == 'ok' for o in runs)} ended ok")


# ---------------------------------------------------------------------------
# the command
# ---------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m studies fuzz", description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=1000, help="runs in all (default 1000)")
    parser.add_argument("--per-structure", type=int, default=10, help="runs per compiled structure (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the study (default 0)")
    parser.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--budget", type=float, default=BUDGET, help=f"s of wall time per run (default {BUDGET:g})")
    parser.add_argument("--n-max", type=int, default=8, help="largest number of links (default 8)")
    parser.add_argument("--json", metavar="FILE", help="write every outcome as JSON")
    parser.add_argument("--case", metavar="SEED-STRUCTURE/RUN", help="rerun one case and print its scene and call")
    parser.add_argument("--sensitivities", action="store_true",
                        help="carry sensitivities along g, the first coordinate's start and velocity, a restitution "
                             "and a friction coefficient in every run (tangent kernels: slower builds), and report "
                             "how far they went")
    return parser


def rebuild_case(case: str, n_max: int = 8):
    """The scene, model and run of one case 'SEED-STRUCTURE/RUN' of the study, drawn as run_structure draws it
    (its obstacles too)."""
    seed, index, k = map(int, re.fullmatch(r"(\d+)-(\d+)/(\d+)", case).groups())
    scene, rng = draw_structure(seed, index, n_max, True)
    model = study_model(scene)
    for _ in range(k + 1):
        run = draw_run(rng, scene, model)
    if not isinstance(scene, Chains) and has_obstacle_runs(seed, index):   # the run's obstacles, as run_structure's
        obstacle_rng = np.random.default_rng([seed, index, OBSTACLE_STREAM, k])
        obstacles = random_obstacles(obstacle_rng, scene, model, run)
        if obstacles:
            scene, model, run = obstacle_run(obstacle_rng, scene, model, run, obstacles, study_model)
    return scene, model, run


def _rerun(case: str, budget: float, n_max: int) -> int:
    match = re.fullmatch(r"(\d+)-(\d+)/(\d+)", case)
    if not match:
        print(f"error: --case: expected SEED-STRUCTURE/RUN (e.g. 0-12/3), got {case!r}", file=sys.stderr)
        return 2
    seed, index, k = map(int, match.groups())
    scene, model, run = rebuild_case(case, n_max)
    print(f"scene: {scene}")
    print(f"simulate(model, {run.t_end!r}, p={run.p.tolist()!r}, q0={run.q0.tolist()!r}, "
          f"qd0={run.qd0.tolist()!r}, **{run.options!r})")
    outcome = next(o for o in run_structure((seed, index, k + 1, budget, n_max, True, True)) if o.case == case)
    print(json.dumps(asdict(outcome), indent=1, default=str))
    return 1 if outcome.failed else 0


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    if args.case:
        return _rerun(args.case, args.budget, args.n_max)
    for option, good, allowed in (("--runs", args.runs >= 1, ">= 1"), ("--per-structure", args.per_structure >= 1, ">= 1"),
                                  ("--n-max", 1 <= args.n_max <= 8, "in 1..8"),
                                  ("--budget", math.isfinite(args.budget) and args.budget > 0, "a finite time > 0 s"),
                                  ("--jobs", args.jobs is None or args.jobs >= 1, ">= 1")):
        if not good:
            print(f"error: {option}: must be {allowed}, got {getattr(args, option[2:].replace('-', '_'))}",
                  file=sys.stderr)
            return 2
    if args.json:
        from codegen.outputs import output_file_problem
        problem = output_file_problem("--json", args.json)
        if problem:
            print(f"error: {problem}", file=sys.stderr)
            return 2
    start = time.perf_counter()
    outcomes = fuzz(args.runs, args.per_structure, args.seed, args.jobs, args.budget, args.n_max,
                    progress=lambda m: print(m, file=sys.stderr, flush=True), sensitivities=args.sensitivities)
    print(f"## Fuzz: {len(outcomes)} runs, seed {args.seed}, {time.perf_counter() - start:.0f} s\n")
    print(table(outcomes))
    print()
    print(accuracy_summary(outcomes))
    print(capsule_summary(outcomes))
    print(obstacle_summary(outcomes))
    print(chains_summary(outcomes))
    print(sensitivity_summary(outcomes))
    failed = [o for o in outcomes if o.failed]
    for o in failed[:50]:
        several = f", {o.chains} chains" if o.chains > 1 else ""
        print(f"FAILED {o.case} ({o.method}, n = {o.n}{several}): {o.violations or o.message[:200]}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump([asdict(o) for o in outcomes], handle, indent=1, default=str)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
