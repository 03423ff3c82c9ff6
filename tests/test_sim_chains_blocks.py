"""Two chains in one box (codegen.combine): the combined model's kernels are each chain's own on its block (checked
against each chain's own one-chain model on random states), its energy the sum of theirs, and over a tumbling run of
a 2-link and a 3-link capsule chain no link passes through another (within a chain or across the two)."""
import math

import numpy as np
import pytest

from codegen.scene import Chains
from codegen.scene import LineLink, Scene, Wall
from runtime import load_model, simulate

WALLS = (Wall("x1_min", 0.0, 0.7), Wall("x1_max", 2.0, 0.7), Wall("x2_min", 0.0, 0.7), Wall("x2_max", 2.0, 0.7))


def chains() -> Chains:
    """A 2-link chain on the left and a 3-link chain on the right, thrown at each other, spinning (planar, X1-X2)."""
    a = Scene(name="tumble_c1", links=(LineLink(0.4, 1.0, radius=0.04), LineLink(0.3, 1.5, radius=0.05)),
              gravity=9.81, walls=WALLS, q0=(-math.pi / 2, 0.0, -0.5, 1.0, 0.4, 1.0, 0.0),
              qd0=(0.0, 0.0, 4.0, -3.0, 3.0, 1.0, 0.0))
    b = Scene(name="tumble_c2", links=(LineLink(0.3, 1.0, radius=0.03),) * 3, gravity=9.81, walls=WALLS,
              q0=(-math.pi / 2, 0.0, 2.2, 0.9, 0.9, 1.5, 1.2, 0.0), qd0=(0.0, 0.0, -3.0, 2.0, -2.0, -3.0, 1.0, 0.0))
    return Chains(name="tumble", chains=(a, b), link_restitution=0.9)


@pytest.fixture(scope="module")
def models():
    scene = chains()
    return scene, load_model(scene), [load_model(chain) for chain in scene.chains]


def _split(scene, model, own, q):
    """The combined model's coordinates cut into each chain's (full layout, then each chain's own reduction)."""
    full = model.layout.expand(q)
    out, start = [], 0
    for chain, m in zip(scene.chains, own):
        out.append(m.layout.reduce(full[start:start + chain.nq]))
        start += chain.nq
    return out


def test_the_kernels_are_each_chains_own_on_its_block(models):
    scene, model, own = models
    rng = np.random.default_rng(3)
    for _ in range(20):
        q, qd = rng.uniform(-2, 2, model.nq), rng.uniform(-3, 3, model.nq)
        qs, qds = _split(scene, model, own, q), _split(scene, model, own, qd)
        blocks = lambda name, *args: np.concatenate([getattr(m, name)(*a) for m, a in zip(own, zip(*args))])
        assert np.array_equal(model.forward_dynamics(q, qd), blocks("forward_dynamics", qs, qds))
        assert np.array_equal(model.generalized_momentum(q, qd), blocks("generalized_momentum", qs, qds))
        assert np.array_equal(model.contact_points(q), blocks("contact_points", qs))
        assert np.array_equal(model.contact_velocities(q, qd), blocks("contact_velocities", qs, qds))
        assert np.array_equal(model.contact_bias(q, qd), blocks("contact_bias", qs, qds))
        nk = [len(m.layout.contacts) for m in own]
        gaps = np.concatenate([m.contact_gaps(a)[:k] for m, a, k in zip(own, qs, nk)])
        assert np.array_equal(model.contact_gaps(q)[:sum(nk)], gaps)
        M = model.mass_matrix(q)
        n1 = own[0].nq
        assert np.array_equal(M[n1:, :n1], np.zeros_like(M[n1:, :n1]))         # block-diagonal
        assert M[:n1, :n1] == pytest.approx(own[0].mass_matrix(qs[0]), rel=1e-12, abs=1e-14)
        assert M[n1:, n1:] == pytest.approx(own[1].mass_matrix(qs[1]), rel=1e-12, abs=1e-14)
        T, V = model.energy(q, qd)
        parts = [m.energy(a, b) for m, a, b in zip(own, qs, qds)]
        assert T == pytest.approx(sum(t for t, _ in parts), rel=1e-14)
        assert V == pytest.approx(sum(v for _, v in parts), rel=1e-14, abs=1e-14)


def test_the_parameters_are_the_boxs_once_then_each_chains_own(models):
    scene, model, own = models
    names = model.parameter_names
    assert names[:1] == ["g"] and "c1.l_1" in names and "c2.mu_3" in names and "l_1" not in names
    for k, m in enumerate(own, start=1):
        gathered = model.p[scene.parameter_map(k)]
        assert np.array_equal(gathered, m.p)
    # a changed parameter of chain 2 moves chain 2 alone
    p = model.p.copy()
    p[names.index("c2.l_1")] *= 1.5
    q = model.q0
    moved = model.contact_points(q, p) - model.contact_points(q)
    assert np.all(moved[:3] == 0.0) and np.any(moved[3:] != 0.0)


def test_no_link_passes_through_another_over_a_tumbling_run(models):
    scene, model, own = models
    result = simulate(model, 1.5)
    assert result.status == 0, result.message
    links = [c for c in result.impacts for c in c.contacts if c.kind == "link"]
    across = [c for c in links if c.links[0] <= 3 < c.links[1]]       # chain 1's links are 1, 2; chain 2's 4, 5, 6
    assert across, "the chains never struck each other"
    first = len(model.layout.contacts)
    worst = min(float(model.contact_gaps(model.layout.reduce(q))[first:].min()) for q in result.q)
    assert worst > -1e-9
    assert abs(result.energy_residual) <= 1e-7 * result.energy_scale
