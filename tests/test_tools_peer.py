"""The studies of long chains: the peer benchmark's URDF of the chain (its joint order, twists and inertias,
checked against our own frames and the reference model's inertia), the side-by-side run when the peer is
installed, and the exponent fit of the simulation-cost study."""
from __future__ import annotations

import math
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from codegen.scene import default_scene
from conftest import random_scene
from studies import peer, simcost


def _chain_of(urdf: str):
    """The URDF's movable joints in tree order, with their origin transform, and the links' inertials."""
    root = ET.fromstring(urdf)
    joints = [j for j in root.findall("joint") if j.get("type") != "fixed"]
    links = {link.get("name"): link.find("inertial") for link in root.findall("link")}
    return joints, links


def test_urdf_maps_the_chain_exactly():
    """Pinocchio's joint order is X1, X2, X3, theta_-1 .. theta_n; the revolute joints' fixed rotations are the
    scene's twists and their offsets the previous link's length; each real link's inertia about its centre of
    mass is the one the model's moments of Eq. 4-7 give."""
    scene = random_scene(4, seed=11, random_twists=True)
    joints, links = _chain_of(peer.urdf(scene))
    names = [j.get("name") for j in joints]
    assert names == ["X1", "X2", "X3"] + [f"theta_{k}".replace("-", "m") for k in range(-1, 5)]
    assert [j.get("type") for j in joints] == ["prismatic"] * 3 + ["revolute"] * 6
    assert peer.pin_order(4) == [6, 7, 8, 0, 1, 2, 3, 4, 5]
    for k, joint in zip(range(-1, 5), joints[3:]):
        origin = joint.find("origin")
        roll, pitch, yaw = map(float, origin.get("rpy").split())
        c, s = np.cos([roll, pitch, yaw]), np.sin([roll, pitch, yaw])
        R = (np.array([[c[2], -s[2], 0], [s[2], c[2], 0], [0, 0, 1]])
             @ np.array([[c[1], 0, s[1]], [0, 1, 0], [-s[1], 0, c[1]]])
             @ np.array([[1, 0, 0], [0, c[0], -s[0]], [0, s[0], c[0]]]))
        assert np.max(np.abs(R - np.array(scene.all_twists[k + 1]))) < 1e-12
        offset = float(origin.get("xyz").split()[0])
        assert offset == (scene.links[k - 2].length if k >= 2 else 0.0)
    for i, link in enumerate(scene.links, start=1):
        inertial = links[f"link{i}"]
        m = float(inertial.find("mass").get("value"))
        l, mu, J = link.length, link.mu, link.J
        assert m == pytest.approx(mu * l, rel=1e-15)
        inertia = inertial.find("inertia")
        assert float(inertia.get("ixx")) == pytest.approx(l * J[0], rel=1e-15)
        # about O_i the model has K_yy = mu l^3 / 3 + l Jyy (Eq. 6-7); the parallel-axis theorem gives the centre
        assert float(inertia.get("iyy")) + m * (l / 2) ** 2 == pytest.approx(mu * l ** 3 / 3 + l * J[1], rel=1e-14)


def test_side_by_side_against_the_peer():
    """With the peer installed: both forward dynamics agree to 1e-12 on the same random states."""
    problem = peer.peer_available(sys.executable)
    if problem:
        pytest.skip(f"peer extra not installed here ({problem.split(':')[0]}); "
                    "python -m studies peer --peer-python names an interpreter that has it")
    rows = peer.measure(3, ["-O1"], batches=1, peer_python=sys.executable, progress=lambda m: None)
    assert rows[0]["agree"] < 1e-12


def test_exponent_fit_recovers_a_power_law():
    ns = [8, 16, 32, 64]
    assert simcost.fit_exponent(ns, [3.0 * n ** 1.3 for n in ns]) == pytest.approx(1.3, abs=1e-12)


def test_default_scene_urdf_has_gravity_along_minus_x2():
    """The fixed world -> reference rotation maps the reference frame's X2 onto the world's z (Pinocchio's
    gravity is -z)."""
    root = ET.fromstring(peer.urdf(default_scene(2)))
    fixed = [j for j in root.findall("joint") if j.get("type") == "fixed"]
    assert len(fixed) == 1
    roll, pitch, yaw = map(float, fixed[0].find("origin").get("rpy").split())
    R = np.array([[1, 0, 0], [0, math.cos(roll), -math.sin(roll)], [0, math.sin(roll), math.cos(roll)]])
    assert (pitch, yaw) == (0.0, 0.0) and np.allclose(R @ [0, 1, 0], [0, 0, 1], atol=1e-15)


def test_simulation_cost_needs_two_links_or_more():
    from studies.cli import parse_links
    assert parse_links("2-4,8", low=2) == [2, 3, 4, 8]
    with pytest.raises(ValueError, match="--links: every n must be in 2.."):
        parse_links("1,4", low=2)
