"""The shooting study (`python -m studies shoot`): Newton's method with the exact Jacobian of the tip's position by
the initial velocity, through three impacts, reaches the target to 1e-10 m with the quadratic convergence of an
exact Jacobian, every iterate meeting the same impacts; the Jacobian agrees with central differences."""
import numpy as np
import pytest

from studies import shoot_target as study


@pytest.fixture(scope="module")
def model():
    from runtime import load_model
    return load_model(study.chain_scene(), tangent=True)


def test_newton_reaches_the_target_quadratically(model):
    target = study.tip(model, 1.2, study.TRUE)[0]
    v, history = study.shoot(model, 1.2, target)
    sizes = [size for size, _ in history]
    assert sizes[-1] <= 1e-10 and len(history) <= 8
    assert len({impacts for _, impacts in [(s, tuple(i)) for s, i in history]}) == 1
    assert len(history[0][1]) == 3
    for before, after in zip(sizes, sizes[1:]):           # quadratic: e_k+1 <= C e_k^2 (C about 12 here)
        if 1e-8 <= before <= 1e-2:
            assert after <= 50 * before ** 2, sizes
    assert np.linalg.norm(study.tip(model, 1.2, v)[0] - target) <= 1e-10


def test_the_tip_jacobian_matches_central_differences(model):
    v = np.array(study.START)
    _, jac, _ = study.tip(model, 1.2, v, sensitivities=True)
    h = 1e-6
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        fd = (study.tip(model, 1.2, v + step)[0] - study.tip(model, 1.2, v - step)[0]) / (2 * h)
        assert np.abs(fd - jac[:, j]).max() <= 1e-6 * max(1.0, np.abs(fd).max())


def test_the_study_prints_its_iterations():
    assert study.main(["--t", "1.2"]) == 0
