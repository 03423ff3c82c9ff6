"""Link-link contacts in the hybrid loop (gac_link.c as contacts of kind GAC_CONTACT_LINK): a free three-link chain
folding until links 1 and 3 strike (energy kept at e = 1, the free chain's linear and angular momenta kept, Newton's
law v+ = -e v- on the pair's relative normal velocity, no penetration), and a tumbling spatial chain of capsules
whose pairs never overlap at the samples (an independent segment distance on result.q)."""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import LineLink, LinkPair, Scene, SceneError, Wall, coordinate_names, scene_from_dict
from runtime import load_model, simulate
from tests.test_sim_link_contact import closest_distance

TOL = dict(rtol=1e-10, atol=1e-12)
POSITION_TOL = 1e-6          # m: the loop's contact_tol default order; a pair's gap must stay above -POSITION_TOL


def folding_scene(e: float) -> Scene:
    """Three planar capsule links (radius 0.05 m), no gravity, folding at both joints so that links 1 and 3 meet."""
    names = coordinate_names(3)
    q0, qd0 = np.zeros(8), np.zeros(8)
    q0[names.index("theta_2")] = q0[names.index("theta_3")] = 1.8
    qd0[names.index("theta_2")] = qd0[names.index("theta_3")] = 1.0
    qd0[names.index("X1")], qd0[names.index("theta_1")] = 0.3, -0.2      # the whole chain moves and turns too
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), 0.05) for l, mu in ((1.0, 1.0), (0.8, 1.5), (1.1, 0.7)))
    return Scene(name=f"fold3_e{int(round(100 * e))}", links=links, gravity=0.0, q0=tuple(q0), qd0=tuple(qd0),
                 link_restitution=e)


@pytest.fixture(scope="module", params=[1.0, 0.5])
def folding(request):
    return request.param, load_model(folding_scene(request.param))


def pair_rate(model, q, qd, i, j):
    """n . (v_P - v_Q) of links i, j at their closest points, from the joint points' velocities."""
    _, s, t, n = model.link_gap(q, i, j)
    v = model.contact_velocities(q, qd)
    return float(n @ ((1 - s) * v[i - 1] + s * v[i] - (1 - t) * v[j - 1] - t * v[j]))


def pair_distance(model, q_full, i, j):
    """The segments' distance of links i, j at a full-layout q, by the joint points and an independent numpy
    closest-point search (tests/test_sim_link_contact.py)."""
    r = model.contact_points(model.layout.reduce(q_full))
    return closest_distance(r[i - 1], r[i], r[j - 1], r[j])


def test_the_link_pair_is_a_contact_of_the_model(folding):
    e, model = folding
    assert [(point, pair.name, pair.links, pair.restitution) for point, pair in model.contacts] == \
        [(1, "L1-L3", (1, 3), e), (1, "O1-L3", (1, 3), e), (1, "O2-L3", (1, 3), e), (3, "O3-L1", (3, 1), e),
         (3, "O4-L1", (3, 1), e)]                        # the pair's, then each end's against the other link
    gap = model.contact_gaps(model.q0)[0]
    assert gap == pytest.approx(model.link_gap(model.q0, 1, 3)[0]) and gap > 0.0


def test_links_strike_by_newtons_law_keeping_momentum(folding):
    e, model = folding
    r = simulate(model, 1.0, **TOL)
    assert r.status == 0, r.message
    assert len(r.impacts) >= 1
    impact = r.impacts[0]
    (c,) = impact.contacts
    assert (c.kind, c.wall, c.links) == ("link", "O1-L3", (1, 3)) and c.impulse > 0.0   # link 1's end O_1
    exported = r.to_json()["impacts"][0]["contacts"][0]
    assert exported["kind"] == "link" and exported["links"] == [1, 3]
    q, qd_m, qd_p = (model.layout.reduce(x) for x in (impact.q, impact.qd_before, impact.qd_after))
    assert abs(model.link_gap(q, 1, 3)[0]) <= POSITION_TOL                  # located at the touch
    v_minus, v_plus = pair_rate(model, q, qd_m, 1, 3), pair_rate(model, q, qd_p, 1, 3)
    assert v_minus < 0.0
    assert v_plus == pytest.approx(-e * v_minus, rel=1e-9, abs=1e-12)      # Newton's law on the pair
    # a free chain without gravity: the momenta conjugate to X1, X2 (linear) and theta_1 (angular about O_1) are
    # the chain's own, and the pair's impulses are internal
    names = [coordinate_names(3)[k] for k in model.layout.free]
    conjugate = [names.index(x) for x in ("X1", "X2", "theta_1")]
    p_m, p_p = model.generalized_momentum(q, qd_m), model.generalized_momentum(q, qd_p)
    scale = np.abs(p_m).max()
    assert np.abs(p_p[conjugate] - p_m[conjugate]).max() <= 1e-11 * scale
    if e == 1.0:
        assert impact.energy_after == pytest.approx(impact.energy_before, rel=1e-11)
        assert r.energy_final == pytest.approx(r.energy_initial, rel=1e-8)
    else:
        assert impact.energy_after < impact.energy_before
    # no penetration at the samples, by an independent distance
    gaps = [pair_distance(model, q, 1, 3) - 0.1 for q in r.q]
    assert min(gaps) >= -POSITION_TOL


@pytest.mark.parametrize("seed", [1, 3])
def test_a_tumbling_spatial_chain_of_capsules_never_overlaps(seed):
    """Four capsule links with twisted joints, random joint angles and fast random joint rates, no gravity: every
    pair's gap at every sample stays above -POSITION_TOL (an independent segment distance on result.q), and the
    energy is kept at e = 1."""
    twists = (((1.0, 0, 0), (0, 0.0, -1.0), (0, 1.0, 0.0)), ((1.0, 0, 0), (0, 0.6, -0.8), (0, 0.8, 0.6)),
              ((1.0, 0, 0), (0, 0.0, 1.0), (0, -1.0, 0.0)))
    radii = (0.08, 0.06, 0.07, 0.05)
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), r) for l, mu, r in zip((1.0, 0.7, 0.9, 0.6), (1.0, 2.0, 0.5, 1.5),
                                                                            radii))
    rng = np.random.default_rng(seed)
    q0 = np.zeros(9)
    q0[3:6] = rng.uniform(-2.5, 2.5, 3)                                   # theta_2..theta_4
    qd0 = np.concatenate([rng.uniform(-1.0, 1.0, 3), rng.choice([-1, 1], 3) * rng.uniform(4.0, 8.0, 3),
                          rng.uniform(-0.5, 0.5, 3)])
    scene = Scene(name="capsule_tumble", links=links, twists=twists, gravity=0.0, link_restitution=1.0)
    model = load_model(scene)                    # one model for both seeds: the start is the run's, not the scene's
    assert model.contact_gaps(q0).min() > 0.0
    r = simulate(model, 4.0, q0=q0, qd0=qd0, **TOL)
    assert r.status == 0, r.message
    assert len(r.impacts) >= 2 and all(c.kind == "link" for i in r.impacts for c in i.contacts)
    assert r.energy_final == pytest.approx(r.energy_initial, rel=1e-8)
    worst = min(pair_distance(model, q, i, j) - radii[i - 1] - radii[j - 1]
                for q in r.q for i, j in scene.link_pairs())
    assert worst >= -POSITION_TOL


def test_sensitivities_are_carried_through_a_link_impact():
    """(Checked against central differences in tests/test_sim_sensitivities_link.py.)"""
    model = load_model(folding_scene(1.0), tangent=True)
    r = simulate(model, 1.0, sensitivities=["q0[theta_2]"], **TOL)
    assert r.status == 0, r.message
    s = r.sensitivities
    assert s.valid and s.n_impacts == len(r.impacts) >= 1, r.sensitivity_message


def test_the_scene_file_sets_the_links_restitution():
    base = {"links": [{"length": 1.0, "mu": 1.0, "radius": 0.05}] * 3, "walls": {"x2_min": -2.0}}
    assert scene_from_dict({**base, "restitution": {"default": 0.7, "links": 0.4}}).link_restitution == 0.4
    assert scene_from_dict({**base, "restitution": {"default": 0.7}}).link_restitution == 0.7
    assert scene_from_dict({**base, "restitution": 0.3}).link_restitution == 0.3
    with pytest.raises(SceneError, match=r"restitution\.links: must be in \[0, 1\]"):
        scene_from_dict({**base, "restitution": {"default": 0.7, "links": 1.5}})
    bare = {"links": [{"length": 1.0, "mu": 1.0}] * 3}
    assert scene_from_dict(bare).link_restitution is None          # no capsules: the scene is as before


def test_the_law_with_rounds_takes_a_link_pair_with_a_wall():
    """A link pair and O_1 on the floor struck at once (gac_impact_complementarity: the rounds' law): no impulse
    pulls, neither contact approaches after, e = 1 keeps the energy, and the pair's row is its J^T n."""
    names = coordinate_names(3)
    q_full = np.zeros(8)
    q_full[names.index("theta_2")] = q_full[names.index("theta_3")] = 1.9
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), 0.05) for l, mu in ((1.0, 1.0), (0.8, 1.5), (1.1, 0.7)))
    scene = Scene(name="fold3_floor", links=links, gravity=0.0, walls=(Wall("x2_min", -0.05, 1.0, (1,)),),
                  q0=tuple(q_full), link_restitution=1.0)
    model = load_model(scene)
    kinds = [type(w).__name__ for _, w in model.contacts]
    assert kinds == ["Wall"] + ["LinkPair"] * 5                 # the pair's contact, then its ends
    q = model.q0
    rng = np.random.default_rng(3)
    struck = 0
    for _ in range(40):
        qd = rng.uniform(-2.0, 2.0, model.nq)
        v_wall = model.contact_velocities(q, qd)[0, 1]
        v_pair = pair_rate(model, q, qd, 1, 3)
        if v_wall >= 0.0 or v_pair >= 0.0:
            continue                                     # both approaching
        qd_plus, F = model.impact(q, qd, [0, 1], mode="complementarity")
        assert (F >= 0.0).all() and F.max() > 0.0
        after = (model.contact_velocities(q, qd_plus)[0, 1], pair_rate(model, q, qd_plus, 1, 3))
        assert min(after) >= -1e-12 * max(abs(v_wall), abs(v_pair))
        T0, T1 = model.energy(q, qd)[0], model.energy(q, qd_plus)[0]
        assert T1 == pytest.approx(T0, rel=1e-11)
        struck += 1
    assert struck >= 3


def test_a_chain_folding_onto_itself_on_the_floor_rests_with_its_links_on_each_other():
    """The shipped capsule-chain without its joint stops folds on the floor until links 1 and 3 press on each other:
    the pair lands like a wall's contact (struck again and again, then held by its normal J^T n and its bias) and the
    run goes on to t_end with link 1 lying on link 3's end O_3 (that end's contact) and the others on the floor; the pair's gap held (never below
    round-off), its force half of link 1's weight (link 1's far end on the floor), the energy balance closed."""
    data = tomllib.loads((Path(__file__).parents[1] / "codegen" / "scenes" / "capsule-chain.toml").read_text())
    for key in ("lower", "upper", "limit_restitution"):
        data["links"][1].pop(key)
    data["name"] = "capsule_chain_unstopped"
    model = load_model(scene_from_dict(data))
    r = simulate(model, 8.0, t_eval=np.linspace(0.0, 8.0, 801), **TOL)
    assert r.status == 0, r.message
    assert any(c.kind == "link" for i in r.impacts for c in i.contacts) and len(r.impacts) < 200
    # link 1 lies on O_3, the end of link 3 (the end's contact against link 1 holds it)
    assert sorted(r.resting_final) == [(2, "x2_min"), (3, "O3-L1"), (3, "x2_min"), (4, "x2_min")]
    assert any(e.kind == "rest" and e.wall == "O3-L1" for e in r.contact_events)
    names = [(point, contact.name) for point, contact in model.contacts]
    pair = names.index((3, "O3-L1"))
    gaps = np.array([model.contact_gaps(model.layout.reduce(x))[pair] for x in r.q])
    assert gaps.min() >= -1e-12
    resting = [names.index(c) for c in r.resting_final]
    q, qd = model.layout.reduce(r.q_final), model.layout.reduce(r.qd_final)
    _, lam = model.constrained_dynamics(q, qd, resting)
    assert (lam > 0.0).all()
    assert lam[resting.index(pair)] == pytest.approx(0.5 * 0.6 * 9.81, rel=1e-6)
    assert abs(r.energy_drift) <= 1e-9


def test_the_shipped_capsule_fold_strikes_its_links_and_comes_to_rest():
    """The shipped capsule-fold: links 1 and 3 strike each other three times as it lands (Newton's law at the scene's
    restitution.links, 0.8), its joint springs open it again, and the chain comes to rest on the floor without the pair
    ever pressing together; the energy balance closes."""
    model = load_model("capsule-fold")
    assert [pair.name for _, pair in model.contacts if isinstance(pair, LinkPair)] == \
        ["L1-L3", "O1-L3", "O2-L3", "O3-L1", "O4-L1"]
    r = simulate(model, 8.0, t_eval=[], **TOL)
    assert r.status == 0, r.message
    strikes = [i for i in r.impacts if any(c.kind == "link" for c in i.contacts)]
    assert len(strikes) == 3 and all(i.t < 1.0 for i in strikes)
    assert len(r.resting_final) >= 2 and {wall for _, wall in r.resting_final} == {"x2_min"}
    assert abs(r.energy_drift) <= 1e-8
