"""The identification study (`python -m studies identify`): restitution and gravity fitted to noisy impact times of
a bouncing rod with the exact Jacobian of the impact times (simulate(sensitivities=...), impact.dt_dp) converge to
the true values within the noise, and to the same point as the fit with finite-difference Jacobians; the Jacobian
itself agrees with central differences of the impact times."""
import numpy as np
import pytest

from studies import identify_restitution as study


@pytest.fixture(scope="module")
def result():
    return study.identify(impacts=8, noise=1e-4, seed=1)


def test_the_fit_finds_the_true_parameters_within_the_noise(result):
    model, measured, truth, fits = result
    exact, differences = fits["exact"], fits["differences"]
    assert exact["status"] > 0 and differences["status"] > 0
    assert exact["x"] == pytest.approx([study.TRUE[n] for n in study.NAMES], abs=0.0, rel=2e-3)
    assert exact["rms"] <= 2e-4                                 # the residual is the noise (1e-4 s), no more
    assert np.allclose(exact["x"], differences["x"], rtol=1e-5)
    assert exact["njev"] >= 1 and exact["runs"] < differences["runs"]


def test_the_exact_jacobian_matches_central_differences(result):
    model = result[0]
    f = study.ImpactTimes(model, 8)
    x = np.array([0.75, 9.5])
    jac = f.jacobian(x)
    for j, h in enumerate((1e-6, 1e-5)):
        step = np.zeros(2)
        step[j] = h
        fd = (f.times(x + step) - f.times(x - step)) / (2 * h)
        assert np.abs(fd - jac[:, j]).max() <= 1e-5 * max(1.0, np.abs(fd).max())


def test_the_study_prints_both_fits_and_draws_the_plot(tmp_path):
    png = tmp_path / "identify.png"
    assert study.main(["--impacts", "6", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10000
