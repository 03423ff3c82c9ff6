"""Shared helpers: random scenes, their reference model, and compiled models (cached per session)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))      # for `from conftest import ...`

from codegen.scene import LineLink, RigidLink, Scene, Wall, WALL_NAMES  # noqa: E402
from studies import reference  # noqa: E402
from studies.reference import reference_of, with_parameters  # noqa: E402,F401

FAR = 50.0   # walls far away: every (point, wall) pair exists but no state is outside


def random_link(rng, kind: str):
    if kind == "line":
        return LineLink(rng.uniform(0.2, 2.0), rng.uniform(0.1, 3.0), tuple(rng.uniform(0.0, 1e-2, size=3)))
    l, m, h, K = reference.random_link(rng)
    com = h / m
    inertia = K - m * (com @ com * np.eye(3) - np.outer(com, com))   # back to the centre of mass
    inertia = (inertia + inertia.T) / 2
    return RigidLink(l, m, tuple(com), tuple(map(tuple, inertia)))


def random_scene(n: int, seed: int, random_twists: bool = False, kinds=("line",), name=None,
                 walls=True) -> Scene:
    """A scene with random links (kinds cycled along the chain), random twists T_2..T_n if asked,
    random gravity, and all six walls far away."""
    rng = np.random.default_rng(seed)
    links = tuple(random_link(rng, kinds[i % len(kinds)]) for i in range(n))
    twists = tuple(map(lambda T: tuple(map(tuple, T)), (reference.random_rotation(rng) for _ in range(n - 1)))) \
        if random_twists else ()
    wall_list = tuple(Wall(w, -FAR if w.endswith("min") else FAR, rng.uniform(0, 1)) for w in WALL_NAMES) \
        if walls else ()
    q0 = (0.0,) * (n + 5)
    return Scene(name=name or f"rand{n}_{seed}", links=links, twists=twists, gravity=rng.uniform(0, 12),
                 walls=wall_list, q0=q0)


def random_parameters(scene: Scene, seed: int) -> np.ndarray:
    """A new random parameter vector with the layout of ``scene`` (same link kinds)."""
    rng = np.random.default_rng(seed)
    other = random_scene(scene.n, seed, kinds=tuple(link.kind for link in scene.links), walls=False)
    p = scene.parameter_vector().copy()
    q = other.parameter_vector()
    p[:len(q)] = q
    p[0] = rng.uniform(0, 12)
    return p


_MODELS = {}


@pytest.fixture(scope="session")
def compiled():
    """compiled(scene, bake_params=False, specialise=False) -> runtime.CompiledModel, built once per
    session.  Tests get the general model unless they ask for the specialised one."""
    from runtime import load_model

    def get(scene: Scene, bake_params: bool = False, specialise: bool = False):
        key = (scene, bake_params, specialise)
        if key not in _MODELS:
            _MODELS[key] = load_model(scene, bake_params=bake_params, specialise=specialise)
        return _MODELS[key]
    return get
