"""The Cramér–Rao bound, and Monte Carlo errors against it at low noise."""

import numpy as np
import pytest

from accelcal import bias_lls_batch, crlb, full_lls_batch, full_nlls, nlls_batch
from accelcal.simulation import classic_directions, random_directions, sample_truth, simulate_poses
from accelcal.uncertainty import crlb_mean

from .conftest import G, make_poses


def test_bias_only_bound_in_closed_form(rng):
    """With M = I the normal of pose i is u_i: F = Σ u uᵀ / σ²."""
    u = random_directions(rng, 24)
    np.testing.assert_allclose(crlb(u, G, 1e-3, model="bias").cov, 1e-6 * np.linalg.inv(u.T @ u), rtol=1e-12)


def test_bound_scales_with_noise_and_pose_count():
    u = classic_directions(24)
    a, b = crlb(u, G, 1e-3), crlb(u, G, 2e-3)
    tol = 1e-12 * np.abs(a.cov).max()
    np.testing.assert_allclose(b.cov, 4 * a.cov, rtol=1e-10, atol=4 * tol)
    c = crlb(np.vstack([u, u]), G, 1e-3)
    np.testing.assert_allclose(c.cov, a.cov / 2, rtol=1e-10, atol=tol)


def test_full_bound_exceeds_bias_only_bound(rng):
    """Estimating M as well can only cost bias accuracy."""
    u = random_directions(rng, 24)
    assert crlb(u, G, 1e-3).bias_rms > crlb(u, G, 1e-3, model="bias").bias_rms


def test_linearised_standard_errors_match_the_bound(rng, truth):
    """The standard errors an estimate reports are the CRLB evaluated at the estimate."""
    u = random_directions(rng, 200)
    z = simulate_poses(u, G, truth["M"], truth["bias"], 1e-3, rng)
    r = full_nlls(z, G)
    bound = crlb(u, G, 1e-3, truth["M"]).std
    got = np.concatenate([r.standard_errors["bias"], r.standard_errors["scale_factors"],
                          np.deg2rad(r.standard_errors["nonorthogonality_deg"])])
    np.testing.assert_allclose(got, bound, rtol=0.15)


@pytest.mark.parametrize("noise", [1e-6, 1e-4])
def test_monte_carlo_error_attains_the_bound_at_low_noise(noise):
    rng = np.random.default_rng(11)
    T = 400
    tr = sample_truth(rng, T)
    U = random_directions(rng, 24, T)
    Zf = simulate_poses(U, G, tr["M"], tr["bias"], noise, rng)
    Zb = simulate_poses(U, G, np.eye(3), tr["bias"], noise, rng)
    full = crlb_mean(U, G, noise, tr["M"]).bias_rms
    bias = crlb_mean(U, G, noise, model="bias").bias_rms

    def rms(est):
        return np.sqrt(np.mean(np.sum((est - tr["bias"]) ** 2, axis=1)))

    # RMS over 400 trials has ~3.5% sampling error (χ² with 1200 dof): 15% is > 4 sigma
    assert rms(full_lls_batch(Zf, G).bias) / full == pytest.approx(1, abs=0.15)
    assert rms(bias_lls_batch(Zb, G).bias) / bias == pytest.approx(1, abs=0.15)
    nl = nlls_batch(Zf[:100], G, "full")
    assert nl["valid"].all()
    ratio = np.sqrt(np.mean(np.sum((nl["bias"] - tr["bias"][:100]) ** 2, axis=1))) / crlb_mean(
        U[:100], G, noise, tr["M"][:100]).bias_rms
    assert ratio == pytest.approx(1, abs=0.3)


def test_single_problem_closed_forms_attain_the_bound_at_the_lowest_paper_noise():
    """At 1e-7 m/s² (the bottom of the Burkhard noise range) the single-problem LLS,
    whatever route it computes by, is noise-limited: its RMS bias error over 300 trials
    is the CRLB's, so no rounding of its own shows at this level."""
    from accelcal import bias_lls, full_lls

    rng = np.random.default_rng(12)
    noise, T = 1e-7, 300
    tr = sample_truth(rng, T)
    U = random_directions(rng, 24, T)
    Zf = simulate_poses(U, G, tr["M"], tr["bias"], noise, rng)
    Zb = simulate_poses(U, G, np.eye(3), tr["bias"], noise, rng)
    err_full = np.array([full_lls(z, G).bias for z in Zf]) - tr["bias"]
    err_bias = np.array([bias_lls(z, G).bias for z in Zb]) - tr["bias"]
    rms = lambda e: np.sqrt(np.mean(np.sum(e**2, axis=1)))  # noqa: E731
    # 300 trials: ~4% sampling error on the RMS; 15% is > 3.5 sigma
    assert rms(err_full) / crlb_mean(U, G, noise, tr["M"]).bias_rms == pytest.approx(1, abs=0.15)
    assert rms(err_bias) / crlb_mean(U, G, noise, model="bias").bias_rms == pytest.approx(1, abs=0.15)
