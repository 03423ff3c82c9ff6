"""Two thin capsule links crossing fast (docs/simulation.md, "Events", pass-throughs): a free three-link chain, no
gravity, folding so fast that link 3 sweeps across link 1 (0.01 m thick together) far within one unlimited step,
strikes it; the links' segments, by an independent numpy distance at dense samples, never cross."""
import numpy as np
import pytest

from codegen.scene import LineLink, Scene, coordinate_names
from runtime import load_model, simulate
from studies.fuzz import segment_distance

R = 0.005


@pytest.fixture(scope="module")
def model():
    names = coordinate_names(3)
    q0 = np.zeros(8)
    q0[names.index("theta_2")] = q0[names.index("theta_3")] = 1.8
    links = tuple(LineLink(l, mu, (1e-3, 2e-3, 3e-3), R) for l, mu in ((1.0, 1.0), (0.8, 1.5), (1.1, 0.7)))
    return load_model(Scene(name="tunnel_links", links=links, gravity=0.0, q0=tuple(q0), link_restitution=1.0))


def test_thin_links_crossing_fast_strike_each_other(model):
    names = coordinate_names(3)
    qd0 = np.zeros(8)
    qd0[names.index("theta_3")] = 40.0
    r = simulate(model, 0.3, q0=model.scene.q0, qd0=qd0, t_eval=np.linspace(0.0, 0.3, 6001), rtol=1e-6, atol=1e-8)
    assert r.status == 0, r.message
    assert r.impacts and [c.wall for c in r.impacts[0].contacts] == ["O4-L1"]     # link 3's tip strikes link 1
    distances = []
    for q in r.q:
        p = model.contact_points(model.layout.reduce(q))
        distances.append(segment_distance(p[0], p[1], p[2], p[3]) - 2 * R)
    assert min(distances) >= -1e-6
