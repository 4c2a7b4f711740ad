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
    r = est(z, G, noise_std=0.0)  # noise-free: the tightest stopping tolerance (default 1e-8 stops at ~1e-9)
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


@pytest.mark.parametrize("noise", [1e-7, 1e-6, 1e-4])
def test_full_lls_agrees_with_full_nlls_at_low_noise(rng, truth, noise):
    z = make_poses(rng, truth, 24, noise)
    a, b = full_lls(z, G), full_nlls(z, G, noise_std=noise)  # NLLS told the noise: stops at a tenth of it
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


# --- the fast single-problem routes against the reference implementations -----------------
@pytest.fixture(params=["numba", "numpy"])
def backend(request, monkeypatch):
    """Run a test with the compiled kernels and with the numpy routes (tests/test_kernels.py
    compares the two directly)."""
    from accelcal import kernels

    if request.param == "numba" and kernels._resolve("auto") != "numba":
        pytest.skip("numba (the optional fast extra) is not installed: only the numpy path runs")
    monkeypatch.setattr(kernels, "_choice", request.param)
    monkeypatch.setattr(kernels, "_backend", request.param)
    return request.param


def _spy(monkeypatch, name):
    """Count calls of the reference implementation ``lls.<name>`` (still running it)."""
    from accelcal import lls

    calls = []
    ref = getattr(lls, name)
    monkeypatch.setattr(lls, name, lambda z, g: calls.append(1) or ref(z, g))
    return calls, ref


@pytest.mark.parametrize("noise", [0.0, 1e-7, 1e-5, 1e-3])
@pytest.mark.parametrize("design", ["random24", "classic24", "random200"])
def test_full_lls_fast_route_equals_the_svd(backend, monkeypatch, rng, truth, design, noise):
    """The Cholesky/inverse-iteration route gives the SVD's estimate to rounding, on the
    Burkhard problems it is meant for (and it is the route taken there)."""
    u = {"random24": lambda: random_directions(rng, 24), "classic24": lambda: classic_directions(24),
         "random200": lambda: random_directions(rng, 200)}[design]()
    calls, svd = _spy(monkeypatch, "_full_lls_svd")
    for _ in range(20):
        z = simulate_poses(u, G, truth["M"], truth["bias"], noise, rng)
        fast, ref = full_lls(z, G), svd(z, G)
        np.testing.assert_allclose(fast.bias, ref.bias, rtol=0, atol=1e-12)  # m/s²; noise >= 1e-7 in the paper
        np.testing.assert_allclose(fast.M, ref.M, rtol=0, atol=1e-13)
        assert fast.lam == pytest.approx(ref.lam, rel=1e-11)
    assert not calls


def test_full_lls_hands_ill_conditioned_problems_to_the_svd(backend, monkeypatch, rng, truth):
    """Raw counts with an offset 8x the gravity radius: forming XᵀX would square a
    condition number of ~2000, so the fast route declines and the SVD computes."""
    Mc = np.array([415.0, 413.0, 415.0])[:, None] * truth["M"]
    z = simulate_poses(random_directions(rng, 30), G, Mc, np.array([32768.0, 32700.0, 32800.0]), 0.05, rng)
    calls, svd = _spy(monkeypatch, "_full_lls_svd")
    r = full_lls(z, G)
    assert calls == [1]
    np.testing.assert_array_equal(r.bias, svd(z, G).bias)


def test_full_lls_fast_route_needs_its_safeguards(backend, monkeypatch, rng, truth):
    """With the gap requirement and the error bound switched off, the same raw-count
    problem goes through XᵀX and loses accuracy the SVD keeps: the safeguards (and the
    tolerance of the test above) are not decoration."""
    from accelcal import lls

    Mc = np.array([415.0, 413.0, 415.0])[:, None] * truth["M"]
    bc = np.array([32768.0, 32700.0, 32800.0])
    z = simulate_poses(random_directions(rng, 30), G, Mc, bc, 0.0, rng)
    exact = lls._full_lls_svd(z, G)
    np.testing.assert_allclose(exact.bias, bc, rtol=0, atol=1e-8)
    monkeypatch.setattr(lls, "MIN_GAP", 1e-12)
    monkeypatch.setattr(lls, "EIGVEC_TOL", 1.0)
    monkeypatch.setattr(lls, "_full_lls_svd", None)  # must not be needed now
    unsafe = full_lls(z, G)
    assert np.abs(unsafe.bias - bc).max() > 100 * np.abs(exact.bias - bc).max()


def test_null_vector_certifies_only_a_clear_one_dimensional_null_space(rng, truth):
    from accelcal.lls import _null_vector, design_matrix

    def normal_matrix(z):
        X = design_matrix(z / np.sqrt(np.mean(np.sum(z**2, axis=1))))
        return X.T @ X

    z = make_poses(rng, truth, 24, 1e-4)
    N = normal_matrix(z)
    w, V = np.linalg.eigh(N)
    x, norm = _null_vector(N.copy())
    assert norm == pytest.approx(np.linalg.norm(x), rel=1e-14)
    theta = x / norm * np.sign(x @ V[:, 0])
    np.testing.assert_allclose(theta, V[:, 0], atol=1e-12)
    # two great circles: a two-dimensional null space (the SVD test rejects it too)
    a = rng.uniform(0, 2 * np.pi, 12)
    two_planes = G * np.vstack([np.column_stack([np.cos(a), np.sin(a), 0 * a]),
                                np.column_stack([np.cos(a), 0 * a, np.sin(a)])]) + truth["bias"]
    assert _null_vector(normal_matrix(two_planes)) is None


@pytest.mark.parametrize("offset", [0.0, 1e4])
def test_bias_lls_fast_route_equals_lstsq(backend, monkeypatch, rng, truth, offset):
    """Eq. (7) by the centred 3x3 normal equations equals ``lstsq`` of the scaled system,
    also when the data sit far from the origin (raw counts)."""
    tetrahedron = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
    calls, lstsq = _spy(monkeypatch, "_bias_lls_lstsq")
    for n, noise in [(4, 0.0), (24, 1e-7), (24, 1e-3), (200, 1e-3)]:
        for _ in range(10):
            u = tetrahedron if n == 4 else random_directions(rng, n)
            z = simulate_poses(u, G, np.eye(3), truth["bias"], noise, rng) + offset
            fast, ref = bias_lls(z, G), lstsq(z, G)
            np.testing.assert_allclose(fast.bias, ref.bias, rtol=0, atol=1e-12 * (1 + offset))
            assert fast.c == pytest.approx(ref.c, rel=1e-12, abs=1e-9 * (1 + offset) ** 2)
    assert not calls


@pytest.mark.parametrize("est", [full_lls, bias_lls, full_als, full_nlls, bias_nlls])
def test_result_attributes_are_lazy_and_equal_the_direct_computation(rng, truth, est):
    """An estimate pays only for its parameters; what it derives on first access equals
    the direct (eager) computation, and every dataclass field is set."""
    from dataclasses import fields

    from accelcal.lls import design_singular_values
    from accelcal.model import params_from_m
    from accelcal.uncertainty import pose_residuals, standard_errors

    z = make_poses(rng, truth, 24, 1e-4, identity=est in (bias_lls, bias_nlls))
    r = est(z, G)
    for f in fields(r):
        getattr(r, f.name)
    lazy = ("residuals", "standard_errors", "_params")
    assert not set(lazy) & set(vars(r))
    np.testing.assert_array_equal(r.residuals, pose_residuals(z, G, r.M, r.bias))
    se = standard_errors(z, G, r.M, r.bias, r.model)
    assert r.standard_errors.keys() == se.keys()
    for key in se:
        np.testing.assert_array_equal(r.standard_errors[key], se[key])
    s, th = params_from_m(r.M)
    np.testing.assert_array_equal(r.scale_factors, s)
    np.testing.assert_array_equal(r.nonorthogonality, th)
    if est in (full_lls, bias_lls):
        np.testing.assert_array_equal(r.singular_values, design_singular_values(r.model, z))
    d = r.to_dict()
    assert {"bias", "M", "residuals", "standard_errors", "scale_factors", "nonorthogonality_deg"} <= d.keys()
    if est in (full_lls, bias_lls, full_als):
        assert list(d)[-4:] == ["singular_values", "lam", "c", "noise_var"]
        assert len(d["singular_values"]) == (4 if est is bias_lls else 10)


def test_fast_and_reference_results_serialise_alike(rng, truth):
    from accelcal import lls

    z = make_poses(rng, truth, 24, 1e-4)
    for fast, ref in ((lls.full_lls(z, G), lls._full_lls_svd(z, G)), (lls.bias_lls(z, G), lls._bias_lls_lstsq(z, G))):
        a, b = fast.to_dict(), ref.to_dict()
        assert list(a) == list(b)
        np.testing.assert_allclose(a["singular_values"], b["singular_values"], rtol=1e-12)
        np.testing.assert_allclose(a["residuals"], b["residuals"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("var", [0.0, 1e-6, 0.05])
def test_als_matrix_from_the_lls_normal_matrix_equals_its_definition(rng, var):
    """Ψ(σ²) = N + σ² Ψ1 + σ⁴ Ψ2 from XᵀX equals the monomial-by-monomial corrected moments
    (and differs from XᵀX as soon as σ² > 0: the test can tell)."""
    from accelcal.als import corrected_matrix_terms, corrected_moments
    from accelcal.lls import normal_matrix

    z = rng.normal(size=(30, 3)) + [0.2, -0.1, 0.3]
    N = normal_matrix(z, 1.0)
    P1, P2 = corrected_matrix_terms(N)
    ref = corrected_moments(z, var)
    np.testing.assert_allclose(N + var * P1 + var**2 * P2, ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    if var:
        assert np.abs(N - ref).max() > 1e3 * 1e-13 * np.abs(ref).max()
