"""The magnetometer's ± under correlated noise: the noise-only s.e. (independent samples) is far too
small when the residuals are correlated; the block jackknife the fit switches to covers the error a
Monte Carlo measures, and leaves white noise's s.e. at the bound."""

from __future__ import annotations

import numpy as np
import pytest

from accelcal.mag.fit import FieldSamples, fit_ellipsoid_ml, with_residual_covariance
from accelcal.mag.noise import correlation_length, fit_ar
from accelcal_repro.mag.loop_benchmark import DESIGN, simulate


def _monte_carlo(rho, trials=16):
    err, se0, se1 = [], [], []
    for seed in range(trials):
        m, _, s = simulate(np.random.default_rng(seed), design={"rho": rho, "n_samples": 900})
        S = FieldSamples(m, noise_cov=np.eye(3) * s**2)
        f = fit_ellipsoid_ml(S)
        err.append(f.theta[:3] - np.asarray(DESIGN["hard_iron"]))
        se0.append(f.se[:3])
        se1.append(with_residual_covariance(f, S).se[:3])
    # pooled over the three axes (the same design): 3 x trials errors
    return float(np.sqrt(np.mean(np.square(err)))), float(np.mean(se0)), float(np.mean(se1))


def test_correlated_noise_gets_the_block_jackknife_and_its_se_covers_the_error():
    rms, noise_only, final = _monte_carlo(0.95)
    assert noise_only < 0.4 * rms  # independent samples: 5x too small
    assert 0.7 * rms < final < 1.5 * rms


def test_white_noise_keeps_se_near_the_bound():
    rms, noise_only, final = _monte_carlo(0.0)
    assert 0.75 * rms < noise_only < 1.3 * rms
    assert final < 1.3 * noise_only


@pytest.mark.parametrize("rho", [0.0, 0.8])
def test_the_ar_model_and_the_correlation_length_read_the_noise(rho):
    rng = np.random.default_rng(1)
    e = rng.standard_normal(20000)
    for k in range(1, e.size):
        e[k] += rho * e[k - 1]
    ar = fit_ar(e)
    assert ar.lag1 == pytest.approx(rho, abs=0.03)
    assert correlation_length(e) == (1 if rho == 0 else pytest.approx(-1 / np.log(rho), abs=1.5))
