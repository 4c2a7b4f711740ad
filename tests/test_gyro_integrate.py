"""Integrators: exactness where they must be exact, their order, and the exact Jacobian."""

import numpy as np
import pytest

from accelcal.gyro.integrate import (METHODS, expm_so3, integrate_intervals, integrate_sequential, log_so3,
                                     suffix_products, total_products)
from accelcal.gyro.simulate import Motion, rotation_error_deg


def _coning_motion():
    axes = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    return Motion(axes, np.deg2rad([120.0, -80.0, 60.0]), np.array([1.2, 1.0, 0.9]), np.array([0.0, 0.3, 0.5]))


def _errors(fs, methods=METHODS):
    mo = _coning_motion()
    n = int(np.ceil(mo.duration * fs)) + 1
    w = mo.rates(np.arange(n) / fs)
    out = {}
    for m in methods:
        R = integrate_sequential(w, 1.0 / fs, [0], [n - 1], m)
        out[m] = float(rotation_error_deg(R, mo.rotation()[None])[0])
    return out


def test_constant_axis_rotation():
    # one fixed axis: no coning; the rate is a smooth bump that starts and ends at rest, so
    # every quadrature of the rate is nearly exact (Euler-Maclaurin)...
    mo = Motion(np.array([[0.6, 0.0, 0.8]]), np.array([2.0]), np.array([1.0]), np.array([0.0]))
    w = mo.rates(np.arange(201) / 200.0)
    err = {m: rotation_error_deg(integrate_sequential(w, 1 / 200.0, [0], [200], m), mo.rotation()[None])[0]
           for m in METHODS}
    for m in ("euler_sum", "rk4", "coning", "magnus4"):
        assert err[m] < 1e-4, m
    # ...except the normalised first-order quaternion step, which turns by 2 atan(h ω / 2) instead of h ω
    assert 1e-4 < err["euler"] < 1e-2


def test_orders_of_the_integrators():
    coarse, fine = _errors(100.0), _errors(200.0)
    ratio = {m: coarse[m] / fine[m] for m in METHODS}
    # the plain sum ignores the non-commutativity: its error does not shrink with the step
    assert coarse["euler_sum"] > 1.0 and ratio["euler_sum"] < 1.2
    # second order: the left-point quaternion step too, because a rest-to-rest motion cancels
    # its first-order term (h/2 (ω_end - ω_start) = 0); RK4 and the coning form interpolate linearly
    for m in ("euler", "rk4", "coning"):
        assert 3.5 < ratio[m] < 4.5, m
    # the cubic interpolation: close to fourth order (the minimum-jerk profiles' jerk jumps limit it)
    assert ratio["magnus4"] > 7.0
    assert fine["magnus4"] < 0.01 * fine["coning"]


def test_products_and_scan():
    rng = np.random.default_rng(0)
    E = expm_so3(0.4 * rng.standard_normal((3, 53, 3)))
    mask = np.ones((3, 53), bool)
    mask[2, 17:] = False
    P = suffix_products(E, mask)
    for i, L in ((0, 53), (2, 17)):
        for k in (0, 5, L - 1):
            ref = np.eye(3)
            for j in range(k, L):
                ref = ref @ E[i, j]
            np.testing.assert_allclose(P[i, k], ref, atol=1e-13)
    np.testing.assert_allclose(total_products(E, mask), P[:, 0], atol=1e-13)


def test_log_exp_round_trip_including_near_pi():
    rng = np.random.default_rng(1)
    v = rng.standard_normal((20, 3))
    v *= (rng.uniform(0, np.pi - 1e-6, 20) / np.linalg.norm(v, axis=1))[:, None]
    np.testing.assert_allclose(log_so3(expm_so3(v)), v, atol=1e-6)


@pytest.mark.parametrize("method", ["coning", "magnus4"])
def test_jacobian_matches_central_differences(method):
    rng = np.random.default_rng(2)
    t = np.arange(300) * 0.01
    y = np.column_stack([2 * np.sin(2 * t), 1.5 * np.cos(3 * t), 0.5 * np.sin(5 * t + 1)])
    C = np.eye(3) + 0.02 * rng.standard_normal((3, 3))
    starts, stops = np.array([3, 40]), np.array([250, 298])
    it = integrate_intervals(y @ C.T, 0.01, starts, stops, method, raw=y)
    eps = 1e-6
    for a in range(9):
        dC = np.zeros(9)
        dC[a] = eps
        Rp = integrate_intervals(y @ (C + dC.reshape(3, 3)).T, 0.01, starts, stops, method).R
        Rm = integrate_intervals(y @ (C - dC.reshape(3, 3)).T, 0.01, starts, stops, method).R
        fd = (log_so3(np.swapaxes(it.R, -1, -2) @ Rp) - log_so3(np.swapaxes(it.R, -1, -2) @ Rm)) / (2 * eps)
        np.testing.assert_allclose(it.dphi_dC[:, :, a], fd, atol=2e-8)
    # a common rate offset δω rotates by G δω
    dw = np.array([1e-6, -2e-6, 0.5e-6])
    R2 = integrate_intervals(y @ C.T + dw, 0.01, starts, stops, method).R
    np.testing.assert_allclose(log_so3(np.swapaxes(it.R, -1, -2) @ R2), it.G @ dw, atol=1e-11)


def test_rotation_noise_matches_monte_carlo():
    # Q predicts the scatter of the integrated rotation under white rate noise
    rng = np.random.default_rng(3)
    t = np.arange(400) * 0.01
    w = np.column_stack([np.sin(t), np.cos(2 * t), 0.3 * t])
    sig = np.array([0.01, 0.02, 0.015])
    it = integrate_intervals(w, 0.01, [0], [399], "coning", rate_cov=np.diag(sig ** 2))
    errs = []
    for _ in range(400):
        R = integrate_intervals(w + sig * rng.standard_normal(w.shape), 0.01, [0], [399], "coning").R
        errs.append(log_so3(np.swapaxes(it.R, -1, -2) @ R)[0])
    emp = np.cov(np.array(errs).T)
    np.testing.assert_allclose(np.diag(emp), np.diag(it.Q[0]), rtol=0.2)


def test_grouping_by_length_changes_nothing():
    from accelcal.gyro import integrate as I

    rng = np.random.default_rng(4)
    y = np.cumsum(0.05 * rng.standard_normal((3000, 3)), axis=0)
    starts = np.sort(rng.choice(2500, 30, replace=False))
    stops = starts + rng.integers(5, 400, 30)
    stops = np.minimum(stops, 2999)
    grouped = I.integrate_intervals(y, 0.01, starts, stops, "magnus4", raw=y, rate_cov=np.eye(3) * 1e-4)
    whole = I._integrate(y, 0.01, starts, stops, "magnus4", y, np.eye(3) * 1e-4)
    assert len(starts) > 2 * I.GROUP
    for name in ("R", "dphi_dC", "G", "Q"):
        np.testing.assert_allclose(getattr(grouped, name), getattr(whole, name), atol=1e-12)
