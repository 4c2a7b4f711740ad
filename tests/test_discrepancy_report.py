"""The join of the two layers: what a noise model means for the pose residuals."""

from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.discrepancy.allan_check import allan_check
from accelcal.discrepancy.detect import discrepancy
from accelcal.discrepancy.fit import forward, pose_data
from accelcal.discrepancy.noise_implication import noise_implication, rests_implication
from accelcal.discrepancy.rules import Rules
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
    imp = rests_implication(det, _stoch({"white": N}, {"white": 2 * N}), starts, durations, 0.05)
    # (σ_i is projected at the closed-form fit, w at the final one: equal to ~1e-7)
    assert imp["expected_excess_short_term"] == pytest.approx(2.0, rel=1e-5)
    assert 1.9 < imp["expected_excess"] < 2.0
    # residuals that follow the white-only model are 2x smaller than this model says: flagged
    assert imp["verdict"] == "it over-predicts" and not imp["explains_excess"]
    # nothing named: nothing added
    same = rests_implication(det, _stoch({"white": N}, {"white": N}), starts, durations, 0.05)
    assert same["expected_excess"] == pytest.approx(1.0) and same["extra_residual_std"] == [0.0] * 30


def test_a_random_walk_adds_scatter_growing_with_distance_in_time():
    rng = np.random.default_rng(1)
    durations = np.full(30, 8.0)
    starts = np.cumsum(durations + 2.0) - durations
    det = _result(rng, 0.3, durations)
    imp = rests_implication(det, _stoch({"white": 0.3}, {"white": 0.3, "random_walk": 0.05}), starts, durations,
                            0.05)
    extra = np.asarray(imp["extra_residual_std"])
    assert imp["expected_excess"] > imp["expected_excess_short_term"] > 1
    # the first and last poses are farthest from the session's mean time: most extra scatter
    # (up to the projection w of each pose's gravity direction)
    assert max(extra[0], extra[-1]) > np.median(extra)


# --------------------------------------------------------------------------- the joint model


def _allan_stoch(n_white, extra_avar, fs=100.0, lengths=(5200,) + (800,) * 30):
    """A stochastic-layer stand-in whose rests measured white noise + ``extra_avar(τ)``."""
    from accelcal.noise import octave_m

    m = octave_m(list(lengths))
    taus = m / fs
    adev = np.sqrt(n_white ** 2 / taus + extra_avar(taus))
    axes = [SimpleNamespace(axis=a, taus=taus, adev_measured=adev, fit_before={"white": {"value": n_white}})
            for a in "xyz"]
    return SimpleNamespace(axes=tuple(axes), fs=fs, segment_lengths=tuple(lengths))


def test_allan_check_compares_the_wander_with_the_rests():
    """A Gauss-Markov wander (K = 0.06, τ = 120 s) whose Allan variance the rests show is
    consistent; rests with white noise only contradict a wander large enough to show at
    their longest τ; a tiny wander is not visible in the rests."""
    from accelcal.noise import TERMS

    N, K, tau = 0.35, 0.06, 120.0
    nm = {"term": "bias_wander", "tau_s": tau, "random_walk_K": K, "random_walk_K_ci": [0.8 * K, 1.25 * K]}
    gm = lambda taus, k=K: k ** 2 * tau / 2 * TERMS["gauss_markov"].basis(taus, 100.0, tau)  # noqa: E731
    assert allan_check(nm, _allan_stoch(N, gm))["verdict"] == "consistent"
    big = {**nm, "random_walk_K": 0.3, "random_walk_K_ci": [0.25, 0.35]}
    out = allan_check(big, _allan_stoch(N, lambda t: 0 * t))
    assert out["verdict"] == "rests show less" and out["axes"]["x"]["less_at"]
    tiny = {**nm, "random_walk_K": 1e-4, "random_walk_K_ci": [0.0, 2e-4]}
    assert allan_check(tiny, _allan_stoch(N, lambda t: 0 * t))["verdict"] == "not visible in the rests"
    # rests showing more (other short-term noise) is no contradiction, and is reported
    out = allan_check(nm, _allan_stoch(N, lambda t: gm(t) + 0.2 * np.exp(-((np.log(t) - 1) ** 2))))
    assert out["verdict"] == "consistent" and out["axes"]["x"]["more_at"]


def test_allan_check_reads_a_flicker_wander_as_its_floor():
    """A flicker wander (B = 0.5: Allan floor 0.33) is checked against its flat floor: rests
    that show it are consistent, white-only rests contradict it (before: 'no wander named')."""
    floor = lambda taus, b=0.5: 2 * np.log(2) / np.pi * b ** 2 + 0 * taus  # noqa: E731
    nm = {"term": "bias_wander", "process": "flicker", "tau_s": float("nan"), "random_walk_K": float("nan"),
          "size": 0.5, "size_ci": [0.45, 0.55]}
    assert allan_check(nm, _allan_stoch(0.35, floor))["verdict"] == "consistent"
    assert allan_check(nm, _allan_stoch(0.35, lambda t: 0 * t))["verdict"] == "rests show less"


def test_joint_noise_model_explains_the_excess_of_a_wandering_session():
    """Pose means with white noise and a Gauss-Markov wander twice the pose noise: the white
    reading of the rests leaves a residual excess it cannot explain, the joint model predicts
    it (verdict consistent, observed excess inside the predicted interval)."""
    from accelcal.discrepancy.wander import simulate_interval_means

    rng = np.random.default_rng(3)
    n = 36
    durations = np.full(n, 8.0)
    starts = np.cumsum(durations + 3.0) - durations
    u = random_directions(rng, n)
    M = m_from_params(np.full(3, 414.0), np.deg2rad([0.3, -0.5, 0.8]))
    b = np.array([32768.0, 32500.0, 33000.0])
    N = 0.35
    ms = np.repeat((N / np.sqrt(durations))[:, None], 3, axis=1)
    z = forward(G * u, M, b, {}) + ms * rng.standard_normal((n, 3))
    z = z + simulate_interval_means(rng, {"gauss_markov": (2 * N / np.sqrt(8.0), 60.0)}, starts, durations)
    t = starts + durations / 2
    det = discrepancy(pose_data(z, G, ms, t, t_start=starts, t_end=starts + durations), Rules())
    stoch = _allan_stoch(N, lambda taus: 0 * taus)
    stoch = SimpleNamespace(**{**stoch.__dict__, "axes": tuple(SimpleNamespace(**{**a.__dict__, "named": (),
                                                                                  "model_after": {"white": N}})
                                                                for a in stoch.axes)})
    imp = noise_implication(det, stoch, starts, durations, 0.05)
    assert det.noise_model["term"] == "bias_wander"
    assert imp["rests_only"]["verdict"] == "residuals exceed it"
    assert imp["verdict"] == "consistent" and imp["explains_excess"]
    lo, hi = imp["expected_excess_interval"]
    assert lo <= imp["observed_excess"] <= hi and imp["observed_excess"] > 1.5
