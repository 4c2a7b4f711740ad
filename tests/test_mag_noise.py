"""The magnetometer's ± under correlated noise: the noise-only s.e. (independent samples) is far too
small when the residuals are correlated; the block jackknife the fit switches to covers the error a
Monte Carlo measures, and leaves white noise's s.e. at the bound (that Monte Carlo, on the
reproductions' simulated sessions: tests/test_repro_mag_noise.py)."""

from __future__ import annotations

import numpy as np
import pytest

from accelcal.mag.noise import correlation_length, fit_ar


@pytest.mark.parametrize("rho", [0.0, 0.8])
def test_the_ar_model_and_the_correlation_length_read_the_noise(rho):
    rng = np.random.default_rng(1)
    e = rng.standard_normal(20000)
    for k in range(1, e.size):
        e[k] += rho * e[k - 1]
    ar = fit_ar(e)
    assert ar.lag1 == pytest.approx(rho, abs=0.03)
    assert correlation_length(e) == (1 if rho == 0 else pytest.approx(-1 / np.log(rho), abs=1.5))
