"""Long chains: the derivation in worker processes gives the same text as a serial one, the source cut into
translation units holds every kernel once, and a long 3D chain without dense kernels (8 links told so, by default; 30,
past the links where they are left out anyway, with -m slow) agrees with the independent reference model and keeps its
energy in flight."""
from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from codegen import interface
from codegen.options import build_options
from codegen.pipeline import PARALLEL_MIN_LINKS, generate
from codegen.scene import default_scene
from conftest import chain, reference_of
from runtime import load_model, simulate
from runtime.compile import END_MARK, KERNEL_MARK, translation_units
from studies import reference


WORKERS = """
import hashlib, sys
from codegen.pipeline import generate
from codegen.scene import default_scene
model = generate(default_scene({n}), workers=2)
assert "parallel_wall" in model.timings, "not derived in workers"
print(hashlib.sha256((model.header + model.source + model.cdef).encode()).hexdigest())
"""


def test_workers_give_the_same_text():
    """In a fresh, single-threaded process the kernels are derived by two worker processes (a process that
    holds threads, like this test run after the ensemble tests, derives serially: forking it is not safe);
    the text is the one a serial derivation gives."""
    n = PARALLEL_MIN_LINKS
    done = subprocess.run([sys.executable, "-c", WORKERS.format(n=n)], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parent.parent)
    assert done.returncode == 0, done.stderr
    serial = generate(default_scene(n), workers=1)
    assert "parallel_wall" not in serial.timings
    assert done.stdout.split()[-1] == hashlib.sha256((serial.header + serial.source + serial.cdef).encode()).hexdigest()


def test_translation_units_hold_every_kernel_once():
    scene = default_scene(6)
    model = generate(scene, build_options(scene, dense=True, tangent=True))        # every kernel
    units = translation_units(model.source, 3)
    assert len(units) == 3
    kernels = [line for line in model.source.splitlines() if line.startswith(KERNEL_MARK)]
    found = [line for unit in units for line in unit.splitlines() if line.startswith(KERNEL_MARK)]
    assert sorted(found) == sorted(kernels) and len(kernels) == len(interface.KERNELS)
    assert all(unit.count(f'#include "{model.name}.h"') == 1 for unit in units)
    assert sum(END_MARK in unit for unit in units) == 1                  # the rest of the file, once
    assert translation_units(model.source, 1) == [model.source]


@pytest.fixture(scope="module", params=[8, pytest.param(30, marks=pytest.mark.slow)])
def long_chain(request):
    """A long 3D chain without dense kernels: 8 links told so (dense=False; the same code as past
    interface.DENSE_MAX_LINKS, where they are left out by default), 30 links with -m slow."""
    scene = chain(request.param, twists=True, walls=False)     # straight out: no box
    return scene, load_model(scene, specialise=False, chart_b=False, dense=False)   # (never near the gimbal lock)


def test_long_chain_against_the_reference(long_chain):
    scene, model = long_chain
    assert "_mass_matrix(" in model.generated.source and "gac_mass_matrix(&" in model.generated.source
    rng = np.random.default_rng(30)
    ref = reference_of(scene)
    q, qd = reference.random_state(scene.n, rng)
    expected = ref.forward_dynamics(q, qd)
    qdd = model.forward_dynamics(q, qd)
    assert np.max(np.abs(qdd - expected)) < 1e-9 * np.max(np.abs(expected))
    M = ref.mass_matrix(q)
    Q = rng.normal(size=model.nq)
    x = model.inertia_solve(q, Q)
    assert np.max(np.abs(M @ x - Q)) < 1e-10 * np.max(np.abs(M)) * np.max(np.abs(x))
    assert np.max(np.abs(model.generalized_momentum(q, qd) - M @ qd)) < 1e-10 * np.max(np.abs(M)) * np.max(np.abs(qd))


def test_long_chain_keeps_its_energy_in_flight(long_chain):
    scene, model = long_chain
    run = simulate(model, 0.05, method="dop853", rtol=1e-11, atol=1e-13)
    assert run.success, run.message
    E0, E1 = run.energy_initial, run.energy_final
    assert abs(E1 - E0) < 1e-8 * max(1.0, abs(E0))
