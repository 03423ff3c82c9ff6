"""Two chains in one box (codegen.scene.Chains, codegen.combine): two equal one-link capsule chains thrown head-on along
X1 strike end-on on their centres' line; the velocities after are Newton's law for two equal masses,
v1' = ((1 - e) v1 + (1 + e) v2) / 2, v2' = ((1 + e) v1 + (1 - e) v2) / 2, the linear momentum is kept and the energy
lost is (1 - e^2) m (v1 - v2)^2 / 4."""
import math

import pytest

from codegen.scene import Chains
from codegen.scene import LineLink, Scene, Wall
from runtime import load_model, simulate

LENGTH, MU, RADIUS = 0.4, 1.0, 0.05
V1, V2 = 1.0, -0.5
MASS = MU * LENGTH


def head_on(e: float) -> Chains:
    """Chain 1 from X1 = -0.6 to -0.2, chain 2 from 0.3 to 0.7, both along X1 (theta_1 = -pi/2), no gravity."""
    walls = (Wall("x1_min", -3.0, 1.0), Wall("x1_max", 3.0, 1.0))

    def chain(k, x, v):
        return Scene(name=f"head_on_c{k}", links=(LineLink(LENGTH, MU, radius=RADIUS),), gravity=0.0, walls=walls,
                     q0=(-math.pi / 2, 0.0, -math.pi / 2, x, 0.0, 0.0), qd0=(0.0, 0.0, 0.0, v, 0.0, 0.0))
    return Chains(name=f"head_on_e{int(10 * e)}", chains=(chain(1, -0.6, V1), chain(2, 0.3, V2)), link_restitution=e)


@pytest.fixture(scope="module", params=[1.0, 0.5])
def run(request):
    e = request.param
    model = load_model(head_on(e))
    return e, model, simulate(model, 0.5)


def test_the_chains_strike_once_end_on_when_their_capsules_meet(run):
    e, model, result = run
    assert result.status == 0
    hits = [i for i in result.impacts if any(c.kind == "link" for c in i.contacts)]
    assert len(hits) == 1 and len(result.impacts) == 1
    (contact,) = hits[0].contacts
    # link 1 of each chain (global links 1 and 3) end to end: link 1's end O_2 against link 3 (the one contact of the
    # two ends' that measure the same two points)
    assert contact.wall == "O2-L3" and contact.links == (1, 3)
    gap = 0.3 - (-0.2) - 2 * RADIUS
    assert hits[0].t == pytest.approx(gap / (V1 - V2), rel=1e-9)


def test_velocities_after_the_strike_are_newtons_law_for_equal_masses(run):
    e, model, result = run
    qd = result.impacts[0].qd_after
    v1, v2 = qd[3], qd[6 + 3]                                       # X1 rates of the two chains (full layout)
    assert v1 == pytest.approx(((1 - e) * V1 + (1 + e) * V2) / 2, abs=1e-12)
    assert v2 == pytest.approx(((1 + e) * V1 + (1 - e) * V2) / 2, abs=1e-12)
    assert abs(qd[2]) < 1e-12 and abs(qd[6 + 2]) < 1e-12               # end-on: no spin
    assert qd[4] == pytest.approx(0.0, abs=1e-12) and qd[6 + 4] == pytest.approx(0.0, abs=1e-12)


def test_momentum_is_kept_and_the_energy_lost_is_the_closed_form(run):
    e, model, result = run
    before, after = result.impacts[0].qd_before, result.impacts[0].qd_after
    p_before = MASS * (before[3] + before[9])
    p_after = MASS * (after[3] + after[9])
    assert abs(p_after - p_before) <= 1e-12 * abs(MASS * (abs(V1) + abs(V2)))
    T0 = 0.5 * MASS * (V1 ** 2 + V2 ** 2)
    lost = (1 - e ** 2) * MASS * (V1 - V2) ** 2 / 4
    assert result.energy_initial - result.energy_final == pytest.approx(lost, abs=1e-12 * T0)
    if e == 1.0:
        assert result.energy_final == pytest.approx(T0, rel=1e-12)


def test_an_impact_of_one_chain_is_blamed_on_that_chains_ratios(run):
    """I_f is block-diagonal over the chains: an impact at chain 1's wall moves chain 1 alone, so the cause of its
    limited accuracy names chain 1's own block and ratios and not the mass ratio
    between the chains (chain 2 made 1e6 times heavier), which the whole I_f's condition would show; the strike
    between the chains couples both and is named by the whole chain set's ratios."""
    from runtime.simulate import accuracy_cause
    e, model, result = run
    names = model.parameter_names
    p = model.parameters()
    p[names.index("c2.mu_1")] *= 1e6
    q, qd = model.q0, model.qd0
    wall = next(c for c, (point, contact) in enumerate(model.contacts) if point == 1 and
                getattr(contact, "name", "") == "x1_min")
    own = accuracy_cause(model, p, q, qd, [wall])
    assert "(chain 1's block of it: cond = " in own and "; in chain 1, its most extreme ratio is " in own, own
    assert "masses" not in own, own
    pair = next(c for c, (point, contact) in enumerate(model.contacts) if hasattr(contact, "j"))
    both = accuracy_cause(model, p, q, qd, [pair])
    assert "its most extreme ratio is that of the links' masses: " in both and "block" not in both, both
