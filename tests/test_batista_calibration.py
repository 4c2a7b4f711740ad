"""Batista et al. (2011), Table I: exactness, the batched form, convergence, the CRLB, the baselines."""

import numpy as np
import pytest

from accelcal import DegeneratePosesError, InputShapeError, NonFiniteError, NotConvergedError
from accelcal.batista.calibration import PARAMETERS, WindowStatistics, calibrate, calibrate_batch, stack_system
from accelcal.batista.crlb import calibration_crlb, derived_quantities, pack, window_jacobian, window_means
from accelcal.batista.model import (PAPER_B_PRIME, PAPER_F2, PAPER_F_INV, PAPER_NOISE, accelerometer_output,
                                    correct_measurement, euler_to_rotation, gravity_in_table,
                                    specific_force_at_rest)
from accelcal_repro.batista2011.montecarlo import (asymptotic_bias, calibration_bounds, calibration_design,
                                         calibration_montecarlo, calibration_summary, lls_comparison)

G = 9.81
ROLL, PITCH, YAW = np.arange(0, 360, 45), [-60, -30, 0, 30, 60], [0, 90, 180, 270]


def _design(noise=PAPER_NOISE, window_s=1.0, **kw):
    # 1 s windows (100 samples) keep the Monte Carlo tests fast; the estimator is the same.
    return calibration_design(kw.pop("roll", ROLL), kw.pop("pitch", PITCH), kw.pop("yaw", YAW), [0.3, -0.2, 0.0], G,
                              PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, noise, window_s=window_s, **kw)


def _samples(design, n_per_window, rng, noise, quadratic=True):
    mu = design.window_means(quadratic)
    a = mu[:, None, :] + noise * rng.standard_normal((len(mu), n_per_window, 3))
    return a.reshape(-1, 3), np.repeat(design.R, n_per_window, axis=0), a


@pytest.fixture
def design():
    return _design()


def test_model_inverse_in_closed_form():
    rng = np.random.default_rng(1)
    a = rng.normal(0, 9.81, (50, 3))
    am = accelerometer_output(a, PAPER_F_INV, PAPER_B_PRIME, PAPER_F2)
    np.testing.assert_allclose(correct_measurement(am, PAPER_F_INV, PAPER_B_PRIME, PAPER_F2), a, atol=1e-12)
    # at rest a = -g_B and F⁻¹ a_m + g_B - F2 g_B² - b' = 0 (eq. 5)
    R = euler_to_rotation(rng.uniform(-np.pi, np.pi, (20, 3)))
    Tg = gravity_in_table([0.01, -0.02, 0.3], G)
    gB = -specific_force_at_rest(R, Tg)
    am = accelerometer_output(-gB, PAPER_F_INV, PAPER_B_PRIME, PAPER_F2)
    np.testing.assert_allclose(am @ PAPER_F_INV.T + gB - PAPER_F2 * gB**2 - PAPER_B_PRIME, 0, atol=1e-12)


def test_exact_recovery_on_noise_free_data(design):
    a, R, _ = _samples(design, 3, np.random.default_rng(0), 0.0)
    truth = design.truth()
    r = calibrate(a, R, G, tol=1e-13)
    assert r.converged and 1 <= r.iterations <= 10
    np.testing.assert_allclose(r.vector(), truth, atol=1e-12)
    np.testing.assert_allclose(r.bias, np.linalg.solve(PAPER_F_INV, PAPER_B_PRIME), atol=1e-12)
    # the literal stacked system annihilates the true parameter vector (paper's column order)
    x = np.concatenate([PAPER_F_INV.ravel(), design.g_table, PAPER_F2, PAPER_B_PRIME])
    assert np.abs(stack_system(a, R, design.g_table) @ x).max() < 1e-12
    rb = calibrate_batch(WindowStatistics.from_samples(design.window_means()[:, None, :]), design.R, G, tol=1e-13)
    np.testing.assert_allclose(rb.vectors()[0], truth, atol=1e-10)


def test_quadratic_step_is_needed_on_noise_free_data(design):
    """Steps 1-2 alone (no F2) cannot fit data with the paper's F2: a wrong estimator is caught."""
    a, R, _ = _samples(design, 1, np.random.default_rng(0), 0.0)
    lin = calibrate(a, R, G, quadratic=False)
    assert np.abs(lin.b_prime - PAPER_B_PRIME).max() > 1e-3
    a0, R0, _ = _samples(design, 1, np.random.default_rng(0), 0.0, quadratic=False)
    np.testing.assert_allclose(calibrate(a0, R0, G, quadratic=False).vector(), design.truth(False), atol=1e-12)


def test_batched_form_equals_the_literal_svd(design):
    rng = np.random.default_rng(2)
    a, R, win = _samples(design, 100, rng, PAPER_NOISE)
    r = calibrate(a, R, G)
    rb = calibrate_batch(WindowStatistics.from_samples(win), design.R, G)
    np.testing.assert_allclose(rb.vectors()[0], r.vector(), rtol=0, atol=1e-10)
    assert rb.iterations[0] == r.iterations and rb.converged[0]


def test_non_convergence_is_reported(design):
    a, R, win = _samples(design, 20, np.random.default_rng(3), PAPER_NOISE)
    r = calibrate(a, R, G, tol=0.0, max_iter=3)
    assert not r.converged and r.iterations == 3 and r.gravity_change >= 0
    with pytest.raises(NotConvergedError, match="did not converge in 3 iterations"):
        calibrate(a, R, G, tol=0.0, max_iter=3, strict=True)
    rb = calibrate_batch(WindowStatistics.from_samples(np.stack([win, win])), design.R, G, tol=0.0, max_iter=2)
    assert not rb.converged.any() and (rb.iterations == 2).all()
    errors = calibration_montecarlo(design, np.random.default_rng(4).spawn(4), tol=0.0, max_iter=2, chunk=2)
    table = errors[errors["method"] == "batista2011"]
    assert not table["converged"].any()
    summary = calibration_summary(errors, calibration_bounds(design))
    assert (summary.loc[summary["method"] == "batista2011", "n_converged"] == 0).all()


def test_bad_input_is_rejected(design):
    a, R, _ = _samples(design, 2, np.random.default_rng(5), PAPER_NOISE)
    with pytest.raises(InputShapeError):
        calibrate(a[:, :2], R, G)
    with pytest.raises(InputShapeError):
        calibrate(a, R[:-1], G)
    bad = a.copy()
    bad[3, 1] = np.nan
    with pytest.raises(NonFiniteError):
        calibrate(bad, R, G)
    # the table turns about one axis only: the rotations do not determine F⁻¹ and ᵀg
    one_axis = _design(roll=np.arange(0, 360, 30), pitch=[0], yaw=[0])
    a1, R1, _ = _samples(one_axis, 2, np.random.default_rng(6), PAPER_NOISE)
    with pytest.raises(DegeneratePosesError, match="do not determine"):
        calibrate(a1, R1, G)
    with pytest.raises(DegeneratePosesError):
        calibration_crlb(PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, one_axis.g_table, one_axis.R, 100, PAPER_NOISE)


def test_crlb_jacobian_and_scaling(design):
    p = design.truth()
    J = window_jacobian(p, design.R)
    h = 1e-6
    for j in (0, 4, 10, 13, 16):
        e = np.zeros_like(p)
        e[j] = h
        fd = (window_means(p + e, design.R) - window_means(p - e, design.R)) / (2 * h)
        np.testing.assert_allclose(J[..., j], fd, atol=1e-7)
    b1 = calibration_crlb(PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, design.g_table, design.R, 100, PAPER_NOISE)
    b4 = calibration_crlb(PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, design.g_table, design.R, 400, PAPER_NOISE)
    np.testing.assert_allclose(b4.std, b1.std / 2, rtol=1e-6)
    # |ᵀg| is known: no variance along ᵀg; f2 known: a smaller bound on the others
    assert abs(design.g_table @ b1.cov[15:, 15:] @ design.g_table) < 1e-12 * np.abs(b1.cov).max()
    b_lin = calibration_crlb(PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, design.g_table, design.R, 100, PAPER_NOISE,
                             estimate_f2=False)
    assert np.all(b_lin.std[9:12] < b1.std[9:12]) and np.all(b_lin.std[12:15] == 0)


def test_monte_carlo_error_attains_the_crlb(design):
    """Table I is (nearly) efficient: error std ≈ CRLB for every parameter, mean ≈ 0."""
    T = 400
    errors = calibration_montecarlo(design, np.random.default_rng(7).spawn(T), chunk=200)
    s = calibration_summary(errors, calibration_bounds(design))
    s = s[(s["method"] == "batista2011") & (s["data"] == "quadratic") & s["parameter"].isin(PARAMETERS)]
    assert len(s) == 18 and (s["n_converged"] == T).all()
    # std of a std over 400 runs ≈ 3.5 %: 0.85-1.15 is > 4 sigma for each of 18 parameters
    assert s["std_over_crlb"].between(0.85, 1.15).all(), s[["parameter", "std_over_crlb"]]
    assert (s["t_mean"].abs() < 4.5).all()
    # the paper's std < 1e-7 is below the bound: no estimator reaches it on this design
    assert (s["crlb_std"] > 1e-7).sum() >= 17


def test_errors_in_variables_bias_matches_monte_carlo_at_high_noise():
    """The O(σ²) bias of Table I (noisy a_m inside X) is real: Monte Carlo finds it at 30x noise."""
    noise = 30 * PAPER_NOISE
    d = _design(noise=noise)
    ab = asymptotic_bias(d)
    T = 1500
    errors = calibration_montecarlo(d, np.random.default_rng(8).spawn(T), chunk=500)
    e = errors[(errors["method"] == "batista2011") & (errors["data"] == "quadratic")]
    s = e.groupby("parameter")["error"].agg(["mean", "std"])
    for name in ("F_inv_11", "F_inv_22", "F_inv_33"):
        i = PARAMETERS.index(name)
        se = s.loc[name, "std"] / np.sqrt(T)
        assert abs(ab[i]) > 6 * se  # the bias is resolvable here ...
        assert abs(s.loc[name, "mean"] - ab[i]) < 4 * se  # ... and the prediction matches it


def test_quadratic_term_and_known_rotations_against_full_lls(design):
    """Full LLS (no F2, unknown attitude) is biased by F2; on F2 = 0 data it is only less precise."""
    errors = calibration_montecarlo(design, np.random.default_rng(9).spawn(60))
    c = lls_comparison(errors).set_index(["data", "method", "quantity"])["rms_norm"]
    assert c[("quadratic", "full_lls", "b")] > 100 * c[("quadratic", "batista2011", "b")]
    assert c[("quadratic", "batista2011_linear", "b")] > 100 * c[("quadratic", "batista2011", "b")]
    assert c[("linear", "full_lls", "b")] < 3 * c[("linear", "batista2011", "b")]
    assert c[("linear", "full_lls", "b")] > c[("linear", "batista2011_linear", "b")]
    # derived b and M of the truth are those of the LLS parametrisation
    p = design.truth()
    F = np.linalg.inv(PAPER_F_INV)
    M = np.linalg.cholesky(F @ F.T)
    np.testing.assert_allclose(derived_quantities(p)[3:], M[[0, 1, 1, 2, 2, 2], [0, 0, 1, 0, 1, 2]])
    assert pack(PAPER_F_INV, PAPER_B_PRIME, PAPER_F2, design.g_table).shape == (18,)


def test_chunked_calibration_monte_carlo_equals_one_job(design):
    """The runs of a chunk draw from their own streams: split into jobs, the same table."""
    import pandas as pd

    from accelcal_repro.batista2011.montecarlo import run_streams

    whole = calibration_montecarlo(design, run_streams(3, "calibration", range(6)), chunk=4)
    parts = [calibration_montecarlo(design, run_streams(3, "calibration", ids), run_ids=ids, chunk=4)
             for ids in (range(0, 2), range(2, 6))]
    merged = pd.concat(parts, ignore_index=True).sort_values(["data", "method", "run"], kind="stable")
    expected = whole.sort_values(["data", "method", "run"], kind="stable")
    pd.testing.assert_frame_equal(merged.reset_index(drop=True), expected.reset_index(drop=True))
    shifted = calibration_montecarlo(design, run_streams(3, "calibration", range(1, 3)), run_ids=range(1, 3))
    assert not np.allclose(shifted["estimate"], parts[0]["estimate"])
