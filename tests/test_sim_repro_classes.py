"""Classes of runs that went wrong silently, each on a small deterministic scene.

An impact that leaves a contact at rest on its wall: a rod (length L = 1 m, mass m = 1 kg, moment of inertia
I = m L^2 / 12 + J_zz L about its centre) lies on a floor with e = 0.05, its end O_1 falling at 1 m/s and its end
O_2 rising at 0.2 m/s.  An impulse F at one end changes that end's velocity by a F and the other end's by c F,
a = 1/m + L^2 / (4 I), c = 1/m - L^2 / (4 I) < 0: the impulse at O_1 drives O_2 into the floor, the impulse at
O_2 then drives O_1 back, and so on: Newton's law in rounds.  The approach speeds of the rounds obey
u_k+1 = (1 + e) |c| / a u_k - e u_k-1, whose roots (0.39 and 0.13 here) are real, so the rounds never end by
themselves and the velocities of both ends go to 0: the exact outcome is the rod at rest on the floor, with
impulses from momentum alone, F_1 + F_2 = m 0.4 (the centre's speed, (1 - 0.2) / 2) and (F_1 - F_2) L / 2 =
I 1.2 (the rate of turn, (1 + 0.2) / L).  Both ends then rest on the floor under gravity.  Neither end lands
by the bounce rule (O_1 arrives at 1 m/s, O_2 was rising), so the runtime left O_2 at rest on the floor but
free: it sank from gap 0, where no crossing is looked for, and was caught by further zero-impulse impacts
(or, had it come out again between two event samples, not at all: a 3.9e-6 m penetration at a position
tolerance of 1.4e-8 m in a random 6-link scene).
"""
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from codegen.scene import LineLink, Scene, Wall
from runtime import simulate


SCENES = Path(__file__).parent / "scenes"
J_ZZ = 1e-3      # kg m: the rod's own inertia per unit length about the joint axis


def rod_on_floor() -> Scene:
    return Scene(name="rod_rounds", links=(LineLink(1.0, 1.0, (J_ZZ, J_ZZ, J_ZZ)),), walls=(Wall("x2_min", 0.0, 0.05),),
                 q0=(-math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0, 0.0), qd0=(0.0, 0.0, 1.2, 0.0, -1.0, 0.0))


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_an_impact_that_leaves_a_contact_at_rest_on_its_wall_holds_it_there(compiled, method):
    model = compiled(rod_on_floor(), specialise=True)
    q0, qd0 = model.layout.reduce(np.array(model.scene.q0)), model.layout.reduce(np.array(model.scene.qd0))
    vertical = model.contact_velocities(q0, qd0)[:, 1]
    assert vertical == pytest.approx([-1.0, 0.2], abs=1e-12)          # the start the docstring describes
    result = simulate(model, 0.05, method=method, t_eval=np.linspace(0.0, 0.05, 501))
    assert result.success, result.message
    assert len(result.impacts) == 1                                   # no zero-impulse impacts after it
    inertia = 1.0 / 12.0 + J_ZZ                                       # I = m L^2 / 12 + J_zz L
    a, c = 1.0 + 1.0 / (4.0 * inertia), 1.0 - 1.0 / (4.0 * inertia)
    e = 0.05
    assert ((1 + e) * abs(c) / a) ** 2 > 4 * e                        # real roots: the rounds never end
    total, difference = 0.4, 2.0 * inertia * 1.2                      # F_1 + F_2, F_1 - F_2
    impulses = {c.point: c.impulse for c in result.impacts[0].contacts}
    assert impulses[1] == pytest.approx((total + difference) / 2, abs=1e-9)
    assert impulses[2] == pytest.approx((total - difference) / 2, abs=1e-9)
    assert sorted((e.t, e.point, e.kind) for e in result.contact_events) == [(0.0, 1, "rest"), (0.0, 2, "rest")]
    assert sorted(result.resting_final) == [(1, "x2_min"), (2, "x2_min")]
    gaps = np.array([model.contact_gaps(model.layout.reduce(q)) for q in result.q])
    assert np.abs(gaps).max() < 1e-12                                 # flat on the floor throughout
    assert np.abs(result.qd_final).max() < 1e-9


def test_elastic_chain_started_at_its_wall_keeps_its_energy():
    """A start (or a restart: chart switching restarts the loop from states it produced) with a point within
    contact_tol of a wall with e = 1: a rod of 1 kg standing on its end O_1, spinning at 1000 rad/s, O_1 leaving
    the floor at 1 m/s.  The spin gives O_1 a normal acceleration of w^2 L / 2 = 5e5 m/s^2, so the bounce rule
    (v^2 <= 2 a rest_height) would call 1 m/s at rest, and holding O_1 took m v^2 / 2 = 0.5 J from the elastic
    rod at the start (3.5 % of the energy in a random five-link chain restarted at a chart switch).  On a wall
    with e = 1 a contact starts at rest only to round-off, as it lands there only if it arrives at rest."""
    scene = Scene(name="spin_start", links=(LineLink(1.0, 1.0),), walls=(Wall("x2_min", 0.0, 1.0),),
                  q0=(-math.pi / 2, 0.0, 0.0, 0.5, 0.0, 0.0), qd0=(0.0, 0.0, 1000.0, 0.0, 1.0, 0.0))
    result = simulate(scene, 1e-3, method="dop853", rtol=1e-12, atol=1e-14)
    assert result.success and not result.contact_events and not result.impacts
    assert abs(result.energy_final - result.energy_initial) < 1e-12 * result.energy_initial
    # at rest it does rest: the same rod standing still on the floor is held there from the start
    still = simulate(dataclasses.replace(scene, name="still_start", qd0=(0.0,) * 6), 0.1, method="dop853")
    assert [e.kind for e in still.contact_events][:1] == ["rest"] and still.q_final[4] == pytest.approx(0.0, abs=1e-9)


# --- the energy balance, watched by the loop ---------------------------------------------------------------------
def test_an_elastic_chain_keeps_its_energy_to_the_tolerance(compiled):
    """e = 1 on every wall, three links of very different sizes (a 12.6 m link, a 2 mm one): each step's error
    estimate was small in every component, yet T + V drifted by 1.4 % over 1.5 s at rtol 4.5e-8 (the error of
    energy, a sum of large terms, is invisible to a per-component norm).  The adaptive steps also hold the step's
    energy error, so the balance, evaluated here from the kernels' energies at the ends and the impacts' records,
    closes to 1e-3 of the energy scale; the loop's own verdict (energy_tol, default 1e4 rtol) agrees."""
    from codegen.scene import load_scene
    model = compiled(load_scene(str(SCENES / "elastic_drift.toml")), specialise=True)
    result = simulate(model, 1.5, method="dopri5", rtol=4.48e-8, atol=4.48e-10, t_eval=[])
    assert result.success, result.message
    assert len(result.impacts) > 50
    T0, V0 = model.energy(model.q0, model.qd0)
    Tf, Vf = model.energy(model.layout.reduce(result.q_final), model.layout.reduce(result.qd_final))
    lost = sum(i.energy_before - i.energy_after for i in result.impacts)
    assert abs(Tf + Vf - (T0 + V0) + lost) < 1e-3 * result.energy_scale


def test_the_loop_stops_where_its_energy_balance_leaves_the_tolerance(compiled):
    """energy_tol below what the run's integration error leaves: the loop stops with the cause at the first step
    end beyond it, and the balance evaluated independently (the kernels' energies, the impacts' records) confirms
    that it was beyond; with the watch off the same run goes on to t_end."""
    from codegen.scene import load_scene
    model = compiled(load_scene("paper-case1"))
    free = simulate(model, 1.5, rtol=1e-6, atol=1e-8, energy_tol=0.0, t_eval=[])
    assert free.success and abs(free.energy_drift) > 1e-9, free.energy_drift
    tight = simulate(model, 1.5, rtol=1e-6, atol=1e-8, energy_tol=1e-9, t_eval=[])
    assert tight.status == -1 and "energy drift" in tight.message and tight.t_final < 1.5, tight.message
    assert abs(tight.energy_drift) > 1e-9 and abs(tight.energy_drift) < 1e-6, tight.energy_drift
    with pytest.raises(ValueError, match=r"^energy_tol: must be < 1"):
        simulate(model, 1.5, energy_tol=1.0)
