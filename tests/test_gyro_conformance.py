"""Every registered gyroscope estimator meets the same contracts, as the accelerometer's do
(``tests/test_estimator_conformance.py``): each check is a function of a registry entry,
run on every entry of ``estimators('gyroscope')``, whatever it fits (motions between
rests, rotations of known angle: :attr:`accelcal.registry.Estimator.data`).

* the entry: its function, conditioning and calibration class load; the class's
  ``CAL_TYPE`` is the name and it is found by it; a baseline is of the same sensor and
  model; the result says its method; the conditioning is finite and positive;
* minimum data: one motion (rotation) fewer than ``min_poses`` is refused
  (``TooFewPosesError``, naming the minimum); ``min_poses`` noise-free ones determine the
  truth exactly;
* compiled = reference: forcing either kernel backend changes nothing (no gyro estimator
  has a compiled kernel yet; one that declares it is compared to rounding);
* JSON round trip: a session calibrated by it saves, inside an accelerometer calibration
  file of format 2, loads (its class found by ``cal_type``) and compares equal;
* ``apply`` inverts the fitted model, through the file's ``apply_gyro``;
* noise: the estimate does not depend on the overall noise level, its covariance scales
  with its square (the noise weights, it does not bias);
* g: no gyro estimate takes the gravity magnitude (``needs_g`` is honest).
"""

from __future__ import annotations

import inspect
from dataclasses import replace

import numpy as np
import pytest

from accelcal import kernels
from accelcal.calibration import calibrate_poses, calibration_class, load_calibration
from accelcal.errors import TooFewPosesError
from accelcal.gyro.calibrate import calibrate_gyro
from accelcal.gyro.ferraris import REST_SECTIONS, ROTATION_SECTIONS, calibrate_ferraris_session
from accelcal.gyro.result import GyroCalibration
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording, simulate_session
from accelcal.registry import ESTIMATORS, Estimator, MotionEstimator, RotationEstimator, estimators
from accelcal.static import detect_static

H = 0.01


# ----------------------------------------------------------------------------- problems
def _rotation_segments(rng, C, n: int, noise: float, angle_deg: float = 360.0):
    """``n`` rotations of ``angle_deg`` about tilted axes at a constant rate, raw ``y = C⁻¹ ω``."""
    axes = np.eye(3)[np.arange(n) % 3] + 0.05 * rng.standard_normal((n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    k = 300
    rate = np.deg2rad(angle_deg) / (k * H)
    segs = [np.tile(rate * a @ np.linalg.inv(C).T, (k, 1)) + noise * rng.standard_normal((k, 3)) for a in axes]
    return segs, axes


def problem(e: Estimator, rng, n: int, noise: float, scale: float = 1.0, fs: float = 100.0):
    """The arguments of ``e``'s function for ``n`` motions (rotations) and the true ``C``.

    ``scale`` multiplies every noise level the data state (not the noise drawn); ``fs``
    the sample rate of the motions (1 kHz: Magnus-4 integrates them to 1e-10)."""
    C = random_gyro_matrix(rng)
    if e.data == "motions":
        s = simulate_session(rng, n_motions=n, C=C, gyro_noise=noise, direction_noise=0.5 * noise, rest_s=0.5,
                             fs=fs)
        ms = replace(s.data, y_var=s.data.y_var * scale ** 2, u_cov=s.data.u_cov * scale ** 2)
        return (ms,), C
    segs, axes = _rotation_segments(rng, C, n, noise)
    return (segs, H, np.full(n, 360.0), axes), C


def fit(e: Estimator, args, C0=None, scale: float = 1.0):
    """Run ``e`` through its kind's ``fit``: (C, covariance, method name)."""
    if e.data == "motions":
        r = e.fit(args[0], np.eye(3) if C0 is None else C0)
        return r.C, r.cov, r.method
    segs, h, angles, axes = args
    yv = np.full(3, (1e-3 * scale) ** 2)
    r = e.fit(segs, h, angles[:len(segs)], axes=axes[:len(segs)], y_var=yv, bias_var=yv / 100)
    return r.C, r.cov, r.estimator


def conditioning(e: Estimator, args, C):
    f = e.load_conditioning()
    return f(args[0], C) if e.data == "motions" else f(args[0], args[1])


def session(e: Estimator, rng) -> tuple[GyroCalibration, object]:
    """A whole session calibrated by ``e`` (its session-level route) and the accelerometer's calibration."""
    if e.data == "motions":
        r = simulate_recording(rng, C=random_gyro_matrix(rng), gyro_bias=[0.01, -0.02, 0.005], n_motions=14)
        poses = detect_static(r["t"], r["acc"])
        acc = calibrate_poses(poses, r["g"], "full_lls", unit="m/s^2")
        return calibrate_gyro(r["t"], r["gyro"], poses, acc, acc=r["acc"], estimator=e.name), acc
    C, bias = random_gyro_matrix(rng), np.array([0.01, -0.02, 0.005])
    segs, _ = _rotation_segments(rng, C, 3, 0.0)
    rest = [bias + 1e-3 * rng.standard_normal((200, 3)) for _ in REST_SECTIONS]
    parts, sections, pos = [], {}, 0
    for name, chunk in [*zip(REST_SECTIONS, rest), *zip(ROTATION_SECTIONS, (s + bias for s in segs))]:
        sections[name] = (pos, pos + len(chunk))
        parts.append(chunk)
        pos += len(chunk)
    gyro = np.concatenate(parts)
    cal = calibrate_ferraris_session(np.arange(len(gyro)) * H, gyro, sections, raw_unit="rad/s")
    rng2 = np.random.default_rng(0)
    z = rng2.standard_normal((12, 3))
    z = 9.81 * z / np.linalg.norm(z, axis=1, keepdims=True)
    acc = calibrate_poses(_Poses(z), 9.81, "full_lls", unit="m/s^2")
    return cal, acc


class _Poses:
    def __init__(self, z):
        n = len(z)
        self.means, self.mean_std = z, np.full((n, 3), 1e-3)
        self.t_start, self.t_end = np.arange(n) * 10.0, np.arange(n) * 10.0 + 5
        self.n_samples, self.temp, self.labels = np.full(n, 500), None, None


# ----------------------------------------------------------------------------- checks
def check_entry(e: Estimator, rng):
    assert e.sensor == "gyroscope" and callable(e.load()) and callable(e.load_conditioning())
    assert isinstance(e, {"motions": MotionEstimator, "rotations": RotationEstimator}[e.data])
    assert not hasattr(e, "fit_batch") and not hasattr(e, "needs_g")  # pose-mean fields mean nothing here
    cls = e.load_calibration()
    assert issubclass(cls, GyroCalibration) and cls.__dict__.get("CAL_TYPE") == e.name
    assert calibration_class(e.name, root=GyroCalibration) is cls
    if e.baseline is not None:
        o = ESTIMATORS[e.baseline]
        assert (o.sensor, o.model, o.data) == (e.sensor, e.model, e.data), (e.name, e.baseline)
    args, C = problem(e, rng, 3 * e.min_poses, 1e-3)
    C_hat, cov, method = fit(e, args)
    assert method == e.name and C_hat.shape == (3, 3) and cov.shape == (9, 9) and e.n_parameters == 9
    sv = conditioning(e, args, C_hat)
    assert np.all(np.isfinite(sv)) and sv.min() > 0


def check_min_data(e: Estimator, rng):
    args, C = problem(e, rng, e.min_poses, 0.0, fs=1000.0)
    short = (args[0].subset(np.arange(e.min_poses - 1)),) if e.data == "motions" else \
        (args[0][:-1], *args[1:])
    with pytest.raises(TooFewPosesError, match=str(e.min_poses)):
        fit(e, short)
    # noise-free: exact from a start near the truth (a one-step estimate too, to second order),
    # up to the integration of the sampled rates (about 1e-8 at 1 kHz; 1e-5 at 100 Hz)
    tol = 1e-7 if e.data == "motions" else 1e-12
    C_hat, _, _ = fit(e, args, C0=C + 1e-6 * rng.standard_normal((3, 3)))
    np.testing.assert_allclose(C_hat, C, rtol=0, atol=tol)
    if e.family == "iterative":  # and from the nominal model
        np.testing.assert_allclose(fit(e, args)[0], C, rtol=0, atol=tol)


def check_compiled_equals_reference(e: Estimator, rng):
    args, _ = problem(e, rng, 3 * e.min_poses, 1e-3)
    previous, out = kernels.choice(), {}
    try:
        for be in ("numba", "numpy") if kernels._resolve("auto") == "numba" else ("numpy",):
            kernels.set_backend(be)
            out[be] = fit(e, args)[0]
    finally:
        kernels.set_backend(previous)
    if len(out) == 2:
        np.testing.assert_allclose(out["numba"], out["numpy"], rtol=0, atol=0.0)  # no compiled gyro estimator


def check_json_round_trip(e: Estimator, rng, tmp_path):
    cal, acc = session(e, rng)
    assert type(cal) is e.load_calibration() and cal.method == e.name and cal.settings["estimator"] == e.name
    back = GyroCalibration.from_dict(cal.to_dict())
    assert type(back) is type(cal) and back == cal
    both = replace(acc, gyro=cal)
    both.save(tmp_path / "both.json")
    again = load_calibration(tmp_path / "both.json")
    assert type(again.gyro) is type(cal) and again.gyro == cal and again == both


def check_apply_inverts(e: Estimator, rng, tmp_path):
    cal, acc = session(e, rng)
    replace(acc, gyro=cal).save(tmp_path / "both.json")
    loaded = load_calibration(tmp_path / "both.json")
    w = rng.normal(size=(50, 3))
    f = 9.81 * np.tile([0.0, 0.0, 1.0], (50, 1))
    raw_acc = f @ acc.M.T + acc.bias
    raw = cal.model.measure(w, f)
    np.testing.assert_allclose(loaded.apply_gyro(raw, raw_acc), w, rtol=0, atol=1e-12)


def check_noise_weights_only(e: Estimator, rng):
    """The stated noise scaled by 10: the same estimate, a covariance 100 times larger."""
    args, _ = problem(e, np.random.default_rng(7), 4 * e.min_poses, 1e-3)
    big, _ = problem(e, np.random.default_rng(7), 4 * e.min_poses, 1e-3, scale=10.0)
    C1, cov1, _ = fit(e, args)
    C2, cov2, _ = fit(e, big, scale=10.0)
    np.testing.assert_allclose(C2, C1, rtol=0, atol=1e-7)
    np.testing.assert_allclose(cov2, 100.0 * cov1, rtol=1e-5, atol=0)


def check_takes_no_g(e: Estimator, rng):
    assert "g" not in inspect.signature(e.load()).parameters and "g" not in inspect.signature(e.fit).parameters


#: The checks of each sensor's estimators that this module covers.
GYRO_CHECKS = {"gyroscope": (check_entry, check_min_data, check_compiled_equals_reference, check_json_round_trip,
                             check_apply_inverts, check_noise_weights_only, check_takes_no_g)}
CHECKS = GYRO_CHECKS["gyroscope"]


def run_check(check, e: Estimator, tmp_path):
    rng = np.random.default_rng([20240624, CHECKS.index(check)])
    if "tmp_path" in inspect.signature(check).parameters:
        return check(e, rng, tmp_path)
    return check(e, rng)


@pytest.mark.parametrize("name", [e.name for e in estimators("gyroscope")])
@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_conformance(check, name, tmp_path):
    run_check(check, ESTIMATORS[name], tmp_path)


def test_the_checks_can_fail(tmp_path):
    """Entries that lie (a minimum of another data kind, another estimator's class, a baseline of
    another sensor, a one-step estimate declared iterative) fail their checks."""
    it = ESTIMATORS["gyro_iterative"]
    lies = [(check_min_data, replace(it, min_poses=it.min_poses + 1)),
            (check_entry, replace(it, calibration="accelcal.gyro.result:GyroOneStepCalibration")),
            (check_entry, replace(ESTIMATORS["gyro_one_step"], baseline="full_nlls")),
            (check_min_data, replace(ESTIMATORS["gyro_one_step"], family="iterative")),
            (check_min_data, replace(ESTIMATORS["gyro_ferraris"], min_poses=4))]
    for check, e in lies:
        with pytest.raises((AssertionError, pytest.fail.Exception)):
            run_check(check, e, tmp_path)
