"""accelcal.evaluation on simulated poses, where the truth and the noise are known."""

from __future__ import annotations

import numpy as np
import pytest

from accelcal import bias_lls, full_lls
from accelcal import evaluation as ev
from accelcal.model import m_from_params
from accelcal.simulation import random_directions, simulate_poses

G = 9.81
# an Xsens-like unit: raw counts, ~414 counts per m/s², offset ~33000 counts
M_COUNTS = 414.0 * m_from_params([0.0, -0.005, 0.002], np.deg2rad([0.2, 0.5, 1.2]))
B_COUNTS = np.array([33120.0, 33275.0, 32364.0])
SIGMA = 0.15  # counts, per axis, of a pose mean


def poses(rng, n, sigma=SIGMA):
    return simulate_poses(random_directions(rng, n), G, M_COUNTS, B_COUNTS, sigma, rng)


def test_chi2_of_a_correct_model_is_about_its_dof_in_raw_counts():
    """Residuals are in m/s², pose noise in counts: σ_r must carry M⁻¹ (reduced χ² ≈ 1)."""
    rng = np.random.default_rng(1)
    z = poses(rng, 400)
    r = full_lls(z, G)
    s = ev.residual_sigma(z, np.full(z.shape, SIGMA), r.M, r.bias)
    assert np.allclose(s, SIGMA / 414.0, rtol=0.02)
    c = ev.chi2_test(r.residuals, s, 9)
    assert c.dof == 391 and 0.85 < c.reduced < 1.15 and 0.92 < c.excess < 1.08
    assert 0.01 < c.p_value < 0.99
    # noise underestimated by 3x: the excess says so
    c3 = ev.chi2_test(r.residuals, s / 3, 9)
    assert 2.7 < c3.excess < 3.3 and c3.p_value < 1e-10


def test_noise_standard_errors_match_the_scatter_of_repeated_fits():
    rng = np.random.default_rng(2)
    u = random_directions(rng, 30)
    fits = [full_lls(simulate_poses(u, G, M_COUNTS, B_COUNTS, SIGMA, rng), G) for _ in range(300)]
    b = np.array([f.bias for f in fits])
    z = simulate_poses(u, G, M_COUNTS, B_COUNTS, SIGMA, rng)
    r = full_lls(z, G)
    se = ev.noise_standard_errors(z, np.full(z.shape, SIGMA), r.M, r.bias, "full")
    assert se.shape == (9,)
    assert np.allclose(se[:3], b.std(axis=0), rtol=0.2)


def test_lopo_on_noise_only_data_is_slightly_worse_than_the_fit():
    rng = np.random.default_rng(3)
    z = poses(rng, 40)
    r = full_lls(z, G)
    err, note = ev.lopo(lambda zz: full_lls(zz, G), z, G, 10)
    assert note == "" and np.isfinite(err).all()
    rms = np.sqrt(np.mean(err**2))
    # for noise alone the leave-one-out inflation is about sqrt(n/(n-q)) = 1.18 on average
    assert 1.0 < rms / r.residual_rms < 1.6


def test_lopo_reports_why_it_is_impossible():
    rng = np.random.default_rng(4)
    z = poses(rng, 10)
    err, note = ev.lopo(lambda zz: full_lls(zz, G), z, G, 10)
    assert np.isnan(err).all() and note == "not possible: 9 remaining poses < 10 needed"


def test_bootstrap_valid_fractions_and_interval():
    rng = np.random.default_rng(5)
    z = poses(rng, 40)
    fit = lambda zz: full_lls(zz, G)  # noqa: E731
    par = lambda r: r.bias  # noqa: E731
    idx = ev.bootstrap_indices(40, 200, np.random.default_rng(0))
    samples, valid = ev.bootstrap(fit, par, z, idx, 10, 3)
    assert valid.all() and samples.shape == (200, 3)
    lo, hi = ev.percentile_ci(samples, 0.95)
    est = fit(z).bias
    assert np.all(lo < est) and np.all(est < hi)
    # the interval width is of the order of the linearised one
    se = fit(z).standard_errors["bias"]
    assert np.all((hi - lo) / (2 * 1.96 * se) > 0.5) and np.all((hi - lo) / (2 * 1.96 * se) < 2.0)
    # 10 poses for 9 parameters: virtually no resample has 10 distinct poses
    z10 = z[:10]
    s10, v10 = ev.bootstrap(fit, par, z10, ev.bootstrap_indices(10, 200, np.random.default_rng(0)), 10, 3)
    assert v10.mean() < 0.02 and np.isnan(s10[~v10]).all()


def test_bootstrap_marks_failed_fits_invalid():
    rng = np.random.default_rng(6)
    u = random_directions(rng, 8)
    u[:, 2] = 0.0  # coplanar: degenerate for the bias-only model
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    z = simulate_poses(u, G, np.eye(3), np.zeros(3), 1e-3, rng)
    s, v = ev.bootstrap(lambda zz: bias_lls(zz, G), lambda r: r.bias, z,
                        ev.bootstrap_indices(8, 20, np.random.default_rng(0)), 4, 3)
    assert not v.any() and np.isnan(s).all()


def test_noise_interval_inflates_only_when_residuals_exceed_the_noise():
    v, se = np.array([1.0, 2.0]), np.array([0.1, 0.2])
    lo, hi = ev.noise_interval(v, se, ev.Chi2(chi2=0.5, dof=10, p_value=1.0), 0.95)
    assert np.allclose(hi - v, 1.959964 * se)
    lo, hi = ev.noise_interval(v, se, ev.Chi2(chi2=90.0, dof=10, p_value=0.0), 0.95)
    assert np.allclose(hi - v, 3 * 1.959964 * se) and np.allclose(v - lo, hi - v)


@pytest.mark.parametrize("dof", [0, -1])
def test_chi2_without_degrees_of_freedom(dof):
    c = ev.chi2_test(np.zeros(3), np.ones(3), 3 - dof)
    assert c.dof == dof and np.isnan(c.p_value) and np.isnan(c.reduced)
