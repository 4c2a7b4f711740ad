"""The magnetometer's noise standard errors on AR(1) sessions simulated by the reproductions' magnetometer benchmark (accelcal_repro.mag.loop_benchmark).

Moved from tests/test_mag_noise.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

from __future__ import annotations

import numpy as np
from accelcal.mag.fit import FieldSamples, fit_ellipsoid_ml, with_residual_covariance
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
