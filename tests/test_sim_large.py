"""Large chains (slow: run with `python -m pytest -m slow`)."""
import subprocess

import numpy as np
import pytest

from studies import reference
from codegen.scene import default_scene
from conftest import reference_of
from runtime.compile import LIBRARY_DIR

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("n", [16, 32])
def test_large_chain_matches_reference_and_compiles_strictly(tmp_path, compiled, n):
    scene = default_scene(n)
    model = compiled(scene)
    source = tmp_path / f"{model.name}.c"
    source.write_text(model.generated.source)
    (tmp_path / f"{model.name}.h").write_text(model.generated.header)
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O0", "-I", str(LIBRARY_DIR),
                    "-c", str(source), "-o", str(tmp_path / "m.o")], check=True)
    ref = reference_of(scene)
    q, qd = reference.random_state(n, np.random.default_rng(n))
    M, R = model.mass_matrix(q), model.bias(q, qd)
    assert np.abs(M - ref.mass_matrix(q)).max() < 1e-10 * np.abs(M).max()
    assert np.abs(R - ref.bias(q, qd)).max() < 1e-10 * np.abs(R).max()
    assert np.linalg.eigvalsh(M).min() > 0
