"""The gyro loop's null: the rests are the gyro's still samples, and a rest mean's error reaches
every motion that subtracts it.  Without either, effect-free sessions named a time offset, a
g-sensitivity or a motion bias (family-wise 0.085 on 386 sessions where alpha is 0.05)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from accelcal.calibration import calibrate_recording
from accelcal.discrepancy import gyro_loop as GL
from accelcal.gyro.fit import motion_residuals
from accelcal.gyro.recording import calibrate_recording_gyro
from accelcal.gyro.rests import STILL_WINDOWS, bias_series, fit_bias, still_intervals
from accelcal.recording import Recording
from accelcal_repro.gyro import loop_benchmark as LB

SIGMA = 0.003


def _rest_with_tails(rng, n=300, tail=12):
    """A rest of white noise whose interval also holds the last ``tail`` samples of a turn before
    it and the first ``tail`` of the next (minimum-jerk ends: the rate grows as the time squared)."""
    ramp = 0.6 * (np.arange(tail, 0, -1) / 100.0) ** 2 * 30  # rad/s, from 0.26 down to ~0.002
    g = SIGMA * rng.standard_normal((n + 2 * tail, 3))
    g[:tail, 2] += ramp
    g[-tail:, 0] -= ramp[::-1]
    return g, tail


def test_a_rest_is_shrunk_to_where_the_gyro_is_still():
    rng = np.random.default_rng(5)
    g, tail = _rest_with_tails(rng)
    (a, b), = still_intervals(g, [(0, len(g))])
    kept_turn = 0.01 * (np.clip(tail - a, 0, None) + np.clip(b - (len(g) - tail), 0, None))
    assert a >= tail - 3 and b <= len(g) - tail + 3, (a, b)
    assert kept_turn <= 0.03  # at most 3 samples of the turns' slowest ends
    assert b - a >= len(g) - 2 * (tail + STILL_WINDOWS[-1])  # at most a long window's worth of still samples goes


def test_noise_alone_loses_a_few_samples_at_most():
    rng = np.random.default_rng(6)
    iv = np.array([(i * 400, i * 400 + 300) for i in range(40)])
    g = SIGMA * rng.standard_normal((40 * 400, 3))
    kept = still_intervals(g, iv)
    lost = (iv[:, 1] - iv[:, 0]) - (kept[:, 1] - kept[:, 0])
    assert lost.max() <= 12 and lost.mean() <= 4, lost


@pytest.fixture(scope="module")
def tails_session():
    """Seed 209 of the benchmark: the accelerometer's rest 15 holds 0.18 deg of a turn."""
    sim = LB.simulate_recording(np.random.default_rng(209), **LB.DESIGN)
    rec = Recording(t=sim["t"], acc=sim["acc"], temp=None, source="s", unit="m/s^2", gyro=sim["gyro"],
                    gyro_unit="rad/s")
    acc, poses = calibrate_recording(rec, sim["g"], "full_lls", search=True, min_poses=6)
    gm = GL.gyro_motions(rec, acc, poses, calibrate_recording_gyro(rec, acc, poses, g_sensitivity=False))
    return sim, poses, gm


def test_a_turn_the_accelerometer_rests_take_in_is_not_named(tails_session):
    sim, poses, gm = tails_session
    w = np.linalg.norm(sim["rates"], axis=1)
    turn_in = [np.rad2deg(w[a:b].sum() * 0.01) for a, b in poses.intervals]
    turn_kept = [np.rad2deg(w[a:b].sum() * 0.01) for a, b in gm.rests.intervals]
    assert max(turn_in) > 0.1 and max(turn_kept) < 0.01
    res = GL.gyro_discrepancy(gm, n_boot=199, seed=209)
    assert res.named == ()
    row = res.rounds[0]["time_offset"]  # between still rests a shift of the gyro's samples moves no rotation
    assert row["status"] == "not_identifiable" and "still" in row["why"] and "turntable" in row["needs"]


def test_the_rest_means_reach_the_motions_as_a_perturbation_of_them_does(tails_session):
    """Each column of :func:`bias_error_jacobian` is the residuals' response to one rest mean
    moved on one axis (through the bias the motions subtract), by central differences."""
    _, _, gm = tails_session
    B = GL.bias_error_jacobian(gm)
    idx, small = GL.compact(gm.ms)
    p = len(gm.rests.means)
    for k, a in [(0, 0), (7, 1), (p - 1, 2)]:
        unit = replace(gm.rests, means=np.eye(p)[k][:, None] * np.eye(3)[a])
        d = -bias_series(fit_bias(unit, gm.bias_mode), unit, gm.t)[idx]
        col = (motion_residuals(GL._with_y(small, small.y + 1e-3 * d), gm.C, gm.integrator)
               - motion_residuals(GL._with_y(small, small.y - 1e-3 * d), gm.C, gm.integrator)) / 2e-3
        np.testing.assert_allclose(B[:, 3 * k + a], col, atol=1e-6 * np.abs(col).max())
