"""The multi-position gyro fit: exactness, efficiency against its own bound, the bound itself."""

import dataclasses

import numpy as np
import pytest

from accelcal.gyro.fit import crlb, evaluate, fit_iterative, fit_one_step, initial_scale, tangent_basis
from accelcal.gyro.simulate import random_gyro_matrix, simulate_session


def _session(seed, **kw):
    rng = np.random.default_rng(seed)
    C = random_gyro_matrix(rng, kw.pop("scale_std", 0.02), kw.pop("misalignment_deg", 1.0))
    args = dict(n_motions=15, angle_deg=100.0, peak_rate_dps=150.0, fs=100.0, C=C, gyro_noise=0.005,
                direction_noise=2e-4, rest_s=0.5)
    args.update(kw)
    return simulate_session(rng, **args)


def test_noise_free_data_give_the_truth():
    s = _session(1, gyro_noise=0.0, direction_noise=0.0)
    f = fit_iterative(s.clean, np.eye(3))
    # what is left is the integrator's own error at 150 deg/s and 100 Hz
    assert np.abs(f.C - s.C).max() < 2e-5
    assert f.evaluation.angles_deg.max() < 1e-3


def test_residual_jacobian_matches_finite_differences():
    s = _session(2)
    C = s.C + 0.01
    ev = evaluate(s.data, C)
    for a in (0, 4, 7):
        d = np.zeros(9)
        d[a] = 1e-7
        rp = evaluate(s.data, C + d.reshape(3, 3)).r
        rm = evaluate(s.data, C - d.reshape(3, 3)).r
        np.testing.assert_allclose(ev.J[:, :, a], (rp - rm) / 2e-7, atol=1e-6)


def _nuisance_crlb(ms, C):
    """The bound with the pose directions as explicit nuisance parameters (2 per rest):
    observations are the accelerometer directions and, per motion, the gravity constraint
    with the integrated gyro's rotation noise."""
    ev = evaluate(ms, C)
    from accelcal.gyro.integrate import integrate_intervals, skew

    it = integrate_intervals(ms.y @ C.T, ms.h, ms.starts, ms.stops, "magnus4", raw=ms.y,
                             rate_cov=C @ np.diag(ms.y_var) @ C.T)
    p, m = len(ms.u), ms.n_motions
    T = tangent_basis(ms.u)  # coordinates of each rest direction
    q = 9 + 2 * p
    F = np.zeros((q, q))
    for j in range(p):  # accelerometer: a_j = v_j + noise
        S = T[j].T @ ms.u_cov[j] @ T[j]
        Jj = np.zeros((2, q))
        Jj[:, 9 + 2 * j:11 + 2 * j] = np.eye(2)
        F += Jj.T @ np.linalg.inv(S) @ Jj
    for i in range(m):  # gyro: 0 = E_bᵀ Rᵀ v_a - E_bᵀ v_b + E_bᵀ [w]× η
        a, b = ms.rest_before[i], ms.rest_after[i]
        R = it.R[i]
        w = R.T @ ms.u[a]
        Eb = tangent_basis(ms.u[b:b + 1])[0]
        EW = Eb.T @ skew(w)
        Ji = np.zeros((2, q))
        Ji[:, :9] = EW @ it.dphi_dC[i]
        Ji[:, 9 + 2 * a:11 + 2 * a] += Eb.T @ R.T @ T[a]
        Ji[:, 9 + 2 * b:11 + 2 * b] -= Eb.T @ T[b]
        GC = it.G[i] @ C
        S = EW @ (it.Q[i] + GC @ np.diag(ms.bias_var[i]) @ GC.T) @ EW.T
        F += Ji.T @ np.linalg.inv(S) @ Ji
    return np.linalg.inv(F)[:9, :9]


def test_crlb_equals_the_explicit_nuisance_bound():
    s = _session(3, bias_var=1e-7)
    np.testing.assert_allclose(crlb(s.clean, s.C), _nuisance_crlb(s.clean, s.C), rtol=1e-6)


def test_iterative_is_efficient_and_its_chi2_fits_the_noise():
    z2, chi = [], []
    for seed in range(10, 40):
        s = _session(seed)
        f = fit_iterative(s.data, np.eye(3))
        z2.append(((f.C - s.C).reshape(9) / np.sqrt(np.diag(crlb(s.clean, s.C)))) ** 2)
        chi.append(f.chi2 / f.dof)
    assert 0.7 < np.mean(z2) < 1.4  # RMS error / CRLB ≈ 1 (270 squared standardised errors)
    assert 0.8 < np.mean(chi) < 1.2  # the predicted residual covariance is the right one


def test_one_step_is_exact_at_the_nominal_model_and_biased_far_from_it():
    near = _session(4, scale_std=0.0, misalignment_deg=0.0, gyro_noise=0.0, direction_noise=0.0)
    assert np.abs(fit_one_step(near.clean, np.eye(3)).C - np.eye(3)).max() < 2e-5
    far = _session(5, scale_std=0.08, misalignment_deg=3.0, gyro_noise=0.0, direction_noise=0.0)
    one = np.abs(fit_one_step(far.clean, np.eye(3)).C - far.C).max()
    it = np.abs(fit_iterative(far.clean, np.eye(3)).C - far.C).max()
    assert one > 1e-3 > 100 * it  # the second-order remainder of an 8 % scale error


def test_initial_scale_of_raw_counts():
    s = _session(6)
    counts = dataclasses.replace(s.data, y=s.data.y * 4778.0)
    assert initial_scale(counts) == pytest.approx(1 / 4778.0, rel=0.03)
    f = fit_iterative(counts, initial_scale(counts) * np.eye(3))
    np.testing.assert_allclose(f.C * 4778.0, s.C, atol=5e-3)
