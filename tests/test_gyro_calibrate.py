"""A whole session, simulated as a time series: the gyro calibrated through its own still rests
(the accelerometer's, trimmed), its uncertainty and warnings, and every kind of bad input
refused in one line."""

import dataclasses

import numpy as np
import pytest

from accelcal.calibration import calibrate_poses
from accelcal.gyro.calibrate import calibrate_gyro, prepare_session
from accelcal.gyro.errors import GyroInputError, NoMotionError, SaturatedGyroError, TooFewMotionsError
from accelcal.gyro.rests import gyro_rests
from accelcal.gyro.result import GyroCalibration
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording
from accelcal.static import detect_static


class _Identity:
    """An accelerometer that needs no calibration (for sessions the accelerometer cannot fit)."""

    @staticmethod
    def apply(z):
        return np.asarray(z, float)


def _recording(seed=5, **kw):
    rng = np.random.default_rng(seed)
    args = dict(C=random_gyro_matrix(rng), gyro_bias=[0.01, -0.02, 0.005], M=np.diag([1.01, 0.99, 1.0]),
                acc_bias=[0.1, -0.05, 0.2])
    args.update(kw)
    return simulate_recording(rng, **args)


def _calibrate(r, **kw):
    poses = detect_static(r["t"], r["acc"])
    cal = calibrate_poses(poses, r["g"], "full_lls", unit="m/s^2")
    return calibrate_gyro(r["t"], r["gyro"], poses, cal, acc=r["acc"], **kw), poses, cal


def test_session_recovers_the_truth_within_its_standard_errors():
    G = np.array([[1e-4, 0, -2e-4], [0, 3e-4, 0], [2e-4, 0, 0]])
    r = _recording(g_sensitivity=G)
    g, _, _ = _calibrate(r)
    z = (g.model.C - r["C"]) / g.standard_errors["C"]
    assert np.abs(z).max() < 4
    assert g.settings["g_sensitivity"]  # the F test found it
    assert np.abs((g.model.g_sensitivity - G) / g.standard_errors["g_sensitivity"]).max() < 4
    assert 0.5 < g.quality.chi2 / g.quality.dof < 1.6
    assert not g.quality.warnings
    back = GyroCalibration.from_dict(g.to_dict())
    assert back.model == g.model and back.quality.warnings == g.quality.warnings
    assert "scale factors [ppm]" in g.summary() and "warning" not in g.summary()


def test_rests_cut_into_the_turns_are_trimmed_to_where_the_gyro_is_still():
    """The accelerometer counts the slow ends of a turn as rest (gravity hardly moves there):
    here every rest is widened by 0.25 s into the motions around it.  The calibration takes the
    gyro's own still rests (gyro_rests, the loop's too), so C stays within its standard errors;
    on the accelerometer's rests it was 8.8 standard errors off (and failed to converge at 0.5 s)."""
    r = _recording(seed=5)
    poses = detect_static(r["t"], r["acc"])
    cal = calibrate_poses(poses, r["g"], "full_lls", unit="m/s^2")
    iv = poses.intervals.copy()
    iv[:, 0] = np.maximum(iv[:, 0] - 25, np.r_[0, iv[:-1, 1]])
    iv[:, 1] = np.minimum(iv[:, 1] + 25, np.r_[iv[1:, 0], len(r["t"])])
    wide = dataclasses.replace(poses, intervals=iv)
    g = calibrate_gyro(r["t"], r["gyro"], wide, cal, acc=r["acc"])
    assert np.abs((g.model.C - r["C"]) / g.standard_errors["C"]).max() < 4
    assert 0.5 < g.quality.excess < 1.3
    still = gyro_rests(r["t"], r["gyro"], wide, cal, r["acc"]).intervals
    assert np.all(still[:, 0] >= iv[:, 0]) and np.all(still[:, 1] <= iv[:, 1]) and np.any(still != iv)
    assert g.motions["t_start"] == r["t"][still[:-1, 1] - 1].tolist()  # the motions run between the still rests
    assert g.motions["t_end"] == r["t"][still[1:, 0]].tolist()


def test_no_g_sensitivity_when_there_is_none():
    g, _, _ = _calibrate(_recording(seed=6))
    assert not g.settings["g_sensitivity"] and g.model.g_sensitivity is None


def test_one_step_and_coning_integrator_agree_with_the_iterative_estimate():
    r = _recording(seed=7)
    it, poses, cal = _calibrate(r)
    one = calibrate_gyro(r["t"], r["gyro"], poses, cal, acc=r["acc"], estimator="gyro_one_step")
    con = calibrate_gyro(r["t"], r["gyro"], poses, cal, acc=r["acc"], integrator="coning")
    se = it.standard_errors["C"]
    assert np.abs((one.model.C - it.model.C) / se).max() < 1.0
    assert np.abs((con.model.C - it.model.C) / se).max() < 0.5


def test_jittery_host_times_use_the_sample_index_and_say_so():
    r = _recording(seed=8)
    t = r["t"] + np.random.default_rng(0).uniform(-0.003, 0.003, len(r["t"]))  # receive times
    t[0] = r["t"][0]
    r = {**r, "t": np.maximum.accumulate(t + np.arange(len(t)) * 1e-9)}
    g, _, _ = _calibrate(r)
    assert g.settings["time_base"]["used"] == "index"
    assert any("sample index" in w for w in g.quality.warnings)


def test_saturated_motions_are_left_out_or_refused():
    r = _recording(seed=9)
    lim = 0.9 * np.abs(r["gyro"]).max()
    clipped = {**r, "gyro": np.clip(r["gyro"], -lim, lim)}
    g, _, _ = _calibrate(clipped, gyro_range=(-lim, lim))
    assert "saturated" in g.quality.flags and g.quality.n_motions < 24
    assert "near_range" in g.quality.flags  # the motions kept still come within 10 % of the range
    clean, _, _ = _calibrate(r, gyro_range=(-5 * lim, 5 * lim))
    assert "near_range" not in clean.quality.flags
    hard = {**r, "gyro": np.clip(r["gyro"], -0.3, 0.3)}
    with pytest.raises(SaturatedGyroError, match="saturated"):
        _calibrate(hard, gyro_range=(-0.3, 0.3))


def test_a_gyro_that_does_not_see_the_motions():
    r = _recording(seed=10)
    flat = {**r, "gyro": 0.003 * np.random.default_rng(1).standard_normal(r["gyro"].shape)}
    with pytest.raises(NoMotionError, match="gyro columns"):
        _calibrate(flat)


def test_a_sensor_that_does_not_turn():
    r = _recording(seed=11, n_motions=8)
    rng = np.random.default_rng(2)
    acc = np.tile([0.0, 0.0, 9.81], (len(r["t"]), 1)) + 0.01 * rng.standard_normal(r["acc"].shape)
    moving = np.linalg.norm(r["rates"], axis=1) > 0
    acc[moving] += 2.0 * rng.standard_normal((moving.sum(), 3))  # shaken, not turned
    gyro = 0.003 * rng.standard_normal(r["gyro"].shape)
    poses = detect_static(r["t"], acc)
    with pytest.raises(NoMotionError, match="does not turn"):
        calibrate_gyro(r["t"], gyro, poses, _Identity())


def test_time_bases_that_do_not_match():
    r = _recording(seed=12)
    poses = detect_static(r["t"], r["acc"])
    cal = calibrate_poses(poses, r["g"], "full_lls", unit="m/s^2")
    with pytest.raises(GyroInputError, match="time bases do not match"):
        calibrate_gyro(r["t"], r["gyro"], poses, cal, t_gyro=r["t"] + 0.5)
    with pytest.raises(GyroInputError, match="samples"):
        calibrate_gyro(r["t"], r["gyro"][:-10], poses, cal)


def test_too_few_motions_and_an_axis_that_never_turns():
    short = _recording(seed=13, n_motions=3)
    poses = detect_static(short["t"], short["acc"])
    with pytest.raises(TooFewMotionsError, match="at least 5"):
        calibrate_gyro(short["t"], short["gyro"], poses, _Identity())
    about_x = _recording(seed=14, axis=[1.0, 0.0, 0.0], C=np.eye(3), n_motions=12)
    poses = detect_static(about_x["t"], about_x["acc"])
    with pytest.raises(TooFewMotionsError, match="about its y axis"):
        calibrate_gyro(about_x["t"], about_x["gyro"], poses, _Identity())


def test_a_prepared_session_fits_each_noise_model_as_a_separate_call_does():
    """The rests and motions found once (prepare_session; the coverage Monte Carlo fits
    each trial both ways): each fit is the one a separate calibrate_gyro call gives, bit for
    bit, and fitting leaves the session as it was (a second fit gives the same)."""
    r = _recording(seed=11)
    poses = detect_static(r["t"], r["acc"])
    cal = calibrate_poses(poses, r["g"], "full_lls", unit="m/s^2")
    session = prepare_session(r["t"], r["gyro"], poses, cal, acc=r["acc"])

    def without_times(g):  # wall times differ from run to run
        d = g.to_dict()
        d["settings"] = {k: v for k, v in d["settings"].items() if k not in ("seconds", "fit_seconds")}
        return d

    fitted = {model: session.fit(noise_model=model) for model in (True, False)}
    for model, g in fitted.items():
        one = calibrate_gyro(r["t"], r["gyro"], poses, cal, acc=r["acc"], noise_model=model)
        assert type(g) is type(one)
        assert without_times(g) == without_times(one)
        assert np.array_equal(g.standard_errors["C"], one.standard_errors["C"])
        assert without_times(session.fit(noise_model=model)) == without_times(g)
    assert fitted[True].settings["noise_model"] is not None and fitted[False].settings["noise_model"] is None
    assert not np.array_equal(fitted[True].standard_errors["C"], fitted[False].standard_errors["C"])


@pytest.mark.parametrize("value", [(True, False), None])
def test_noise_model_is_a_bool_and_a_tuple_says_how_to_fit_several(value):
    r = _recording(seed=11)
    poses = detect_static(r["t"], r["acc"])
    with pytest.raises(GyroInputError, match="noise_model must be True or False.*prepare the session once"):
        calibrate_gyro(r["t"], r["gyro"], poses, _Identity(), noise_model=value)
