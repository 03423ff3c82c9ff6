"""Wall crossings of capsule link pairs that the event search used to miss with the adaptive DOP853 (docs/simulation.md,
"Events", pass-throughs), each a fuzz study case (studies/fuzz.py) that stopped with "a point lies beyond its wall at
an impact" and now runs on:

  * 0-10/9 (3 links, obstacles): after an impact the pair's gap opens and falls back through 0 between two samples,
    and the segments then intersect (the gap flat at minus the radii, its normal velocity meaningless): the first
    point inside the body that the pass-through search meets no longer ends the search, the halves before it are
    searched for the crossing first;
  * 0-27/9 (two chains): a short link nearly parallel to a long one strikes it at one end and, 3e-7 s later, at its
    other end; the return located from the normal velocity inside the intersected segments lay deep inside, and is
    no longer taken as the event (the pass-through search finds the crossing);
  * 0-49/0 (8 links): the gap bounces up and down between two samples while the links' point speeds exceed its rate
    650-fold, so the pass-through search spent its evaluations next to the step's start; an interval with a sign
    change that the search's limits leave unsplit is now located as the crossing it holds;
  * 0-74/6 (7 links, resting link pairs): all three, with contacts held.

Since the impact law's rounds are carried in long double, 0-10/9, 0-49/0 and 0-74/6 take other paths by round-off
and meet no crossing near their former stops; they are kept as runs checked for penetration, and 0-27/9 still strikes
its crossing in the window.

Each run is checked independently: from model.contact_points at the samples (dense around the former stop) and at
the impact states, numpy segment distances (studies.fuzz.segment_distance) less the radii for every link pair and the
points' and capsules' distances to the walls at the run's positions, against the study's position tolerance."""
import re
from dataclasses import replace

import numpy as np
import pytest

from runtime.simulate import simulate
from studies import fuzz


def rebuild(case: str):
    """The model and run of a fuzz case 'seed-structure/run', as ``python -m studies fuzz --case`` draws it."""
    _, model, run = fuzz.rebuild_case(case)
    return model, run


def deepest(model, run, states) -> float:
    """The deepest overlap (m, < 0) over the full-layout states: every link pair's segment distance less its radii,
    every wall's contact points and capsules (fuzz.capsule_wall_gaps, line links included), every obstacle."""
    scene = model.scene
    names = scene.parameter_names()
    radii = fuzz.point_radii(scene)
    pairs = fuzz.all_link_pairs(scene)
    rows = fuzz.chain_rows(scene)
    walls = [[replace(w, position=float(run.p[names.index(f"wall_{w.name}")])) for w in chain.walls]
             for chain in fuzz.chains_of(scene)]
    obstacles = [o.with_geometry([run.p[model.parameter_names.index(name)] for name in o.geometry_names])
                 for o in getattr(scene, "obstacles", ())]
    worst = np.inf
    for q in states:
        points = model.contact_points(model.layout.reduce(q), run.p)
        gaps = fuzz.pair_gaps(points, radii, pairs)
        for chain, chain_walls, r in zip(fuzz.chains_of(scene), walls, rows):
            gaps += fuzz.capsule_wall_gaps(points[r.start:r.stop], [link.radius for link in chain.links],
                                           chain_walls, every_link=True)
        if obstacles:
            gaps += fuzz.obstacle_gaps(points, [link.radius for link in scene.links], obstacles)
        worst = min([worst] + gaps)
    return worst


CASES = [   # case, t_end (past the former stop and the misses after it), the former stop's time, a window after it
    ("0-10/9", 0.3, 0.238896075723, None),            # holding the crossing it missed (401 samples there) until
                                                      # the impact law's rounds went to long double: another path
    ("0-27/9", 0.05, 0.0366792565713, 1e-6),          # the crossing it missed, still struck in its window
    pytest.param("0-49/0", 0.09, 0.0815170988835, None,   # its impacts' rounds refined since: another path, no
                 marks=pytest.mark.slow),              # crossing left there to find
    ("0-74/6", 1.41, 1.36677079333, None),            # the same since the long-double rounds
]


@pytest.mark.parametrize("case, t_end, t_stop, window", CASES, ids=[getattr(c, "values", c)[0]
                                                                    for c in CASES])
def test_a_crossing_once_missed_is_located(case, t_end, t_stop, window):
    model, run = rebuild(case)
    t_eval = np.union1d(np.linspace(0.0, t_end, 101), np.linspace(t_stop, t_stop + (window or 0.0), 401))
    r = simulate(model, t_end, p=run.p, q0=run.q0, qd0=run.qd0, t_eval=t_eval, **run.options)
    assert r.status == 0, r.message
    if window is not None:
        assert any(t_stop < i.t <= t_stop + window for i in r.impacts)       # the crossing, struck
    states = list(r.q) + [i.q for i in r.impacts]
    simultaneity = 100 * (run.options["atol"] + run.options["rtol"] * run.extent)
    tolerance = fuzz.PEN_TOL * max(1.0, run.extent) + simultaneity           # the study's, as check_run's
    assert deepest(model, run, states) >= -tolerance


def test_a_run_that_still_stops_names_the_contact_the_depth_the_step_and_cond_I_f():
    """RK4 at dt = 0.95 ms (fuzz case 0-12/1, 8 links): point O4 is found beyond wall x1_max, and the message says
    which contact, how deep against the depth allowed, in which step, and that cond(I_f) (about 1e8) cannot explain
    it while the fixed step can."""
    model, run = rebuild("0-12/1")
    r = simulate(model, run.t_end, p=run.p, q0=run.q0, qd0=run.qd0, t_eval=[], **run.options)
    assert r.status == -1 and "a point lies beyond its wall" in r.message
    detail = re.search(r"\((O\d+/x\d_m..): gap (\S+) m at t = (\S+) s, deeper than the (\S+) m allowed .* in the step "
                       r"from (\S+) s to (\S+) s \(h = (\S+) s\); cond\(I_f\) = (\S+) at its start: not I_f's "
                       r"conditioning .*: the fixed step dt = (\S+) s too long for the motion\)$", r.message)
    assert detail, r.message
    label, gap, t, depth, t0, t1, h, cond, dt = detail.groups()
    assert label == "O4/x1_max" and -float(gap) > float(depth) > 0.0
    assert float(t0) == pytest.approx(r.t_final) and float(t0) < float(t) <= float(t1)
    assert float(h) == pytest.approx(run.options["dt"], rel=1e-3) and float(dt) == pytest.approx(run.options["dt"],
                                                                                                  rel=1e-5)
    assert float(cond) == pytest.approx(np.linalg.cond(model.mass_matrix(model.layout.reduce(r.q_final), run.p)),
                                        rel=1e-2)
