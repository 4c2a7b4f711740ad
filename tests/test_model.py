"""Parametrisation of M, its derivatives, the reversed Cholesky and the pose designs."""

import numpy as np
import pytest

from accelcal.errors import InputShapeError, NotPositiveDefiniteError
from accelcal.model import dM_dparams, lower_from_gram, m_from_params, params_from_m
from accelcal.simulation import classic_directions


def test_round_trip_params_m(rng):
    s = rng.uniform(-0.05, 0.05, (50, 3))
    th = rng.uniform(-0.1, 0.1, (50, 3))
    s2, th2 = params_from_m(m_from_params(s, th))
    np.testing.assert_allclose(s2, s, atol=1e-14)
    np.testing.assert_allclose(th2, th, atol=1e-14)


def test_round_trip_m_params(rng):
    L = np.tril(rng.uniform(-0.02, 0.02, (3, 3))) + np.diag(rng.uniform(0.9, 1.1, 3))
    np.testing.assert_allclose(m_from_params(*params_from_m(L)), L, atol=1e-15)


def test_rows_follow_the_documented_parametrisation():
    th = np.deg2rad([0.03, 0.02, 0.04])
    M = m_from_params([1e-3, 2e-3, 3e-3], th)
    assert M[0, 1] == M[0, 2] == M[1, 2] == 0
    np.testing.assert_allclose(np.linalg.norm(M, axis=1), 1 + np.array([1e-3, 2e-3, 3e-3]))
    np.testing.assert_allclose(M[1, 0] / np.linalg.norm(M[1]), np.sin(th[0]))
    np.testing.assert_allclose(M[2, :2] / np.linalg.norm(M[2]), np.sin(th[1:]))


def test_derivatives_match_finite_differences(rng):
    s, th = rng.uniform(-0.01, 0.01, 3), rng.uniform(-0.05, 0.05, 3)
    p = np.concatenate([s, th])
    h = 1e-6
    for k in range(6):
        dp = np.zeros(6)
        dp[k] = h
        fd = (m_from_params(*np.split(p + dp, 2)) - m_from_params(*np.split(p - dp, 2))) / (2 * h)
        np.testing.assert_allclose(dM_dparams(s, th)[k], fd, atol=1e-9)


def test_reversed_cholesky(rng):
    A = np.tril(rng.normal(0, 0.05, (3, 3))) + np.eye(3)
    np.testing.assert_allclose(lower_from_gram(A.T @ A), A, atol=1e-14)
    with pytest.raises(NotPositiveDefiniteError):
        lower_from_gram(-np.eye(3))


def test_params_from_m_rejects_bad_m():
    with pytest.raises(NotPositiveDefiniteError):
        params_from_m(np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(InputShapeError):
        params_from_m(np.ones((3, 3)))
    with pytest.raises(InputShapeError):
        params_from_m(np.eye(2))


@pytest.mark.parametrize("n", [6, 12, 24])
def test_classic_designs(n):
    u = classic_directions(n)
    assert u.shape == (n, 3)
    np.testing.assert_allclose(np.linalg.norm(u, axis=1), 1)
    assert len({tuple(np.round(v, 12)) for v in u}) == n
    # symmetric designs: every axis seen equally, mean direction zero
    np.testing.assert_allclose(u.mean(axis=0), 0, atol=1e-15)
    np.testing.assert_allclose(u.T @ u, n / 3 * np.eye(3), atol=1e-12)
    with pytest.raises(InputShapeError):
        classic_directions(7)


def test_scalar_m_from_params_equals_the_array_version(rng):
    from accelcal.model import m_from_params_single

    for _ in range(50):
        s, th = rng.uniform(-1e-2, 1e-2, 3), rng.uniform(-0.3, 0.3, 3)
        np.testing.assert_allclose(m_from_params_single(s, th), m_from_params(s, th), rtol=1e-15, atol=1e-16)
    with pytest.raises(InputShapeError, match="too large"):
        m_from_params_single(np.zeros(3), [0.0, 1.2, 1.2])
