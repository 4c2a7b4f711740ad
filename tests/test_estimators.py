"""Closed forms (eqs. 3-7), NLLS, ALS: exactness, g-independence, agreement."""

import numpy as np
import pytest

from accelcal import (
    NotConvergedError,
    bias_lls,
    bias_lls_batch,
    bias_nlls,
    full_als,
    full_lls,
    full_lls_batch,
    full_nlls,
    nlls,
)
from accelcal.simulation import classic_directions, random_directions, sample_truth, simulate_poses

from .conftest import G, make_poses


def test_full_lls_exact_from_q_plus_1_noise_free_poses(rng, truth):
    z = make_poses(rng, truth, 10, 0.0)
    r = full_lls(z, G)
    np.testing.assert_allclose(r.bias, truth["bias"], atol=1e-12)
    np.testing.assert_allclose(r.M, truth["M"], atol=1e-12)
    np.testing.assert_allclose(r.scale_factors, truth["scale_factors"], atol=1e-12)
    np.testing.assert_allclose(r.nonorthogonality, truth["nonorthogonality"], atol=1e-12)
    assert r.residual_rms < 1e-12


def test_bias_lls_exact_from_q_plus_1_noise_free_poses(rng, truth):
    tetrahedron = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
    z = simulate_poses(tetrahedron, G, np.eye(3), truth["bias"], 0.0, rng)
    np.testing.assert_allclose(bias_lls(z, G).bias, truth["bias"], atol=1e-12)


@pytest.mark.parametrize("est", [full_nlls, bias_nlls])
def test_nlls_exact_on_noise_free_poses(rng, truth, est):
    z = make_poses(rng, truth, 24, 0.0, identity=est is bias_nlls)
    r = est(z, G)
    assert r.status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    np.testing.assert_allclose(r.bias, truth["bias"], atol=1e-9)
    if est is full_nlls:
        np.testing.assert_allclose(r.M, truth["M"], atol=1e-9)


def test_lls_bias_does_not_depend_on_g(rng, truth):
    """Eqs. (4) and (7): b needs neither g nor λ; only M (through λ) does."""
    z = make_poses(rng, truth, 24, 1e-3)
    full = [full_lls(z, g) for g in (9.0, 9.8055, 10.5)]
    bias = [bias_lls(z, g) for g in (9.0, 9.8055, 10.5)]
    for r in full[1:]:
        np.testing.assert_allclose(r.bias, full[0].bias, rtol=0, atol=1e-14)
        # λ scales with g², A = M⁻¹ with g: M g is the same for every g
        np.testing.assert_allclose(r.M * r.g, full[0].M * full[0].g, atol=1e-12)
    for r in bias[1:]:
        np.testing.assert_allclose(r.bias, bias[0].bias, rtol=0, atol=1e-14)
    # the iterative bias-only estimate does depend on g: the test can tell the difference
    assert np.abs(bias_nlls(z, 9.0).bias - bias_nlls(z, 10.5).bias).max() > 1e-3


@pytest.mark.parametrize("noise", [1e-6, 1e-4])
def test_full_lls_agrees_with_full_nlls_at_low_noise(rng, truth, noise):
    z = make_poses(rng, truth, 24, noise)
    a, b = full_lls(z, G), full_nlls(z, G)
    # both are within the noise of the truth; they differ by far less than that
    assert np.abs(a.bias - b.bias).max() < 0.05 * noise
    assert np.abs(a.M - b.M).max() < 0.05 * noise / G
    assert np.abs(a.bias - truth["bias"]).max() < 5 * noise


def test_batched_equals_single(rng):
    tr = sample_truth(rng, 20)
    Z = simulate_poses(random_directions(rng, 24, 20), G, tr["M"], tr["bias"], 1e-4, rng)
    fb, bb = full_lls_batch(Z, G), bias_lls_batch(Z, G)
    assert fb.valid.all() and bb.valid.all()
    for i in range(20):
        np.testing.assert_allclose(fb.bias[i], full_lls(Z[i], G).bias, atol=1e-13)
        np.testing.assert_allclose(fb.M[i], full_lls(Z[i], G).M, atol=1e-13)
        np.testing.assert_allclose(bb.bias[i], bias_lls(Z[i], G).bias, atol=1e-12)


def test_batch_marks_invalid_trials_instead_of_returning_numbers(rng, truth):
    Z = np.stack([make_poses(rng, truth, 12, 1e-4), make_poses(rng, truth, 12, 1e-4)])
    Z[1] = _hyperboloid_points(rng, 12)
    r = full_lls_batch(Z, G)
    assert r.valid.tolist() == [True, False]
    assert np.isnan(r.bias[1]).all() and np.isfinite(r.bias[0]).all()


def _hyperboloid_points(rng, n):
    # x² + y² - z² = 25: a quadric that is no ellipsoid, so Ŝ is indefinite
    a, h = rng.uniform(0, 2 * np.pi, n), rng.uniform(-3, 3, n)
    r = np.sqrt(25 + h**2)
    return np.column_stack([r * np.cos(a), r * np.sin(a), h])


def test_raw_counts_with_g_in_ms2(rng, truth):
    """z in counts, g in m/s²: M carries the sensitivity (counts per m/s²)."""
    sens = np.array([415.0, 413.0, 415.0])
    Mc = sens[:, None] * truth["M"]
    bc = np.array([32768.0, 32700.0, 32800.0])
    u = random_directions(rng, 30)
    z = simulate_poses(u, G, Mc, bc, 0.5, rng)
    for est in (full_lls, full_nlls, full_als):
        r = est(z, G)
        np.testing.assert_allclose(np.diag(r.M), np.diag(Mc), rtol=2e-3)
        np.testing.assert_allclose(r.bias, bc, atol=2.0)


def test_classic_24_position_design_determines_full_model(rng, truth):
    z = simulate_poses(classic_directions(24), G, truth["M"], truth["bias"], 0.0, rng)
    np.testing.assert_allclose(full_lls(z, G).M, truth["M"], atol=1e-12)


def test_nlls_reports_non_convergence(rng, truth, monkeypatch):
    """IPOPT stopped early must raise, never hand back its last iterate."""
    monkeypatch.setitem(nlls.IPOPT_OPTIONS, "ipopt.max_iter", 1)
    nlls._solver.cache_clear()
    try:
        with pytest.raises(NotConvergedError, match="Maximum_Iterations"):
            full_nlls(make_poses(rng, truth, 24, 1e-3), G)
        out = nlls.nlls_batch(make_poses(rng, truth, 24, 1e-3)[None], G, "full")
        assert not out["valid"][0] and np.isnan(out["bias"][0]).all()
    finally:
        nlls._solver.cache_clear()


def test_als_equals_lls_at_low_noise(rng, truth):
    z = make_poses(rng, truth, 24, 1e-5)
    a, b = full_lls(z, G), full_als(z, G)
    assert np.abs(a.bias - b.bias).max() < 1e-3 * 1e-5
    assert np.abs(a.M - b.M).max() < 1e-8


def test_als_removes_the_noise_bias_of_the_algebraic_fit():
    """At large noise the full LLS scale factors are biased by ~2σ²/g²; ALS is not."""
    rng = np.random.default_rng(7)
    tr = sample_truth(rng, 1)
    sigma, n, trials = 0.3, 1500, 16
    err_lls, err_als = [], []
    for _ in range(trials):
        z = simulate_poses(random_directions(rng, n), G, tr["M"][0], tr["bias"][0], sigma, rng)
        err_lls.append(full_lls(z, G).scale_factors - tr["scale_factors"][0])
        err_als.append(full_als(z, G).scale_factors - tr["scale_factors"][0])
    err_lls, err_als = np.array(err_lls).ravel(), np.array(err_als).ravel()
    se = err_lls.std() / np.sqrt(err_lls.size)
    predicted = 2 * sigma**2 / G**2
    assert abs(err_lls.mean() - predicted) < 4 * se  # the algebraic bias is there...
    assert err_lls.mean() > 6 * se
    assert abs(err_als.mean()) < 4 * se  # ...and ALS removes it


def test_als_noise_estimate_is_consistent(rng, truth):
    z = make_poses(rng, truth, 3000, 0.2)
    r = full_als(z, G)
    assert abs(np.sqrt(r.noise_var) / 0.2 - 1) < 0.1
