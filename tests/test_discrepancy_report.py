"""The join of the two layers: what a noise model means for the pose residuals."""

from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.discrepancy.detect import Rules, discrepancy
from accelcal.discrepancy.fit import forward, pose_data
from accelcal.discrepancy.report import noise_implication
from accelcal.model import m_from_params
from accelcal.simulation import random_directions

G = 9.80665


def _result(rng, N, durations):
    n = len(durations)
    u = random_directions(rng, n)
    M = m_from_params(np.full(3, 414.0), np.deg2rad([0.3, -0.5, 0.8]))
    b = np.array([32768.0, 32500.0, 33000.0])
    ms = np.repeat((N / np.sqrt(durations))[:, None], 3, axis=1)  # white noise: Var(mean over T) = N²/T
    z = forward(G * u, M, b, {}) + ms * rng.standard_normal((n, 3))
    t = np.cumsum(durations + 2.0) - durations / 2
    return discrepancy(pose_data(z, G, ms, t), Rules())


def _stoch(before: dict, after: dict, fs=100.0):
    axes = [SimpleNamespace(axis=a, named=tuple(k for k in after if k != "white"),
                            fit_before={k: {"value": v} for k, v in before.items()}, model_after=after)
            for a in "xyz"]
    return SimpleNamespace(axes=tuple(axes), fs=fs)


def test_more_white_noise_means_that_much_more_residual_scatter():
    """A simulator whose white noise doubles predicts residuals twice as large: the short-term
    expected excess is exactly 2 (each pose mean: 4 N²/T instead of N²/T); centring on the
    common mean makes the session-wide one slightly smaller."""
    rng = np.random.default_rng(0)
    durations = rng.uniform(5, 10, 30)
    starts = np.cumsum(durations + 2.0) - durations
    N = 0.3
    det = _result(rng, N, durations)
    imp = noise_implication(det, _stoch({"white": N}, {"white": 2 * N}), starts, durations, 0.05)
    # (σ_i is projected at the closed-form fit, w at the final one: equal to ~1e-7)
    assert imp["expected_excess_short_term"] == pytest.approx(2.0, rel=1e-5)
    assert 1.9 < imp["expected_excess"] < 2.0
    # residuals that follow the white-only model are 2x smaller than this model says: flagged
    assert imp["verdict"] == "it over-predicts" and not imp["explains_excess"]
    # nothing named: nothing added
    same = noise_implication(det, _stoch({"white": N}, {"white": N}), starts, durations, 0.05)
    assert same["expected_excess"] == pytest.approx(1.0) and same["extra_residual_std"] == [0.0] * 30


def test_a_random_walk_adds_scatter_growing_with_distance_in_time():
    rng = np.random.default_rng(1)
    durations = np.full(30, 8.0)
    starts = np.cumsum(durations + 2.0) - durations
    det = _result(rng, 0.3, durations)
    imp = noise_implication(det, _stoch({"white": 0.3}, {"white": 0.3, "random_walk": 0.05}), starts, durations,
                            0.05)
    extra = np.asarray(imp["extra_residual_std"])
    assert imp["expected_excess"] > imp["expected_excess_short_term"] > 1
    # the first and last poses are farthest from the session's mean time: most extra scatter
    # (up to the projection w of each pose's gravity direction)
    assert max(extra[0], extra[-1]) > np.median(extra)
