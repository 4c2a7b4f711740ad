"""Every registered estimator of pose means meets the same contracts (in the spirit of
scikit-learn's ``parametrize_with_checks``): each check is a function of a registry entry,
run here on every accelerometer entry of :data:`accelcal.registry.ESTIMATORS`, and by
``tests/test_add_estimator.py`` on an estimator a test registers, so a new estimator is
checked without a new test.  The gyroscope's entries have their own checks
(``tests/test_gyro_conformance.py``); a test below sees that every entry is covered by one.

* the entry: its function, batch form and calibration class load; the class's
  ``CAL_TYPE`` is the name; baseline and corrected estimator are registered, of the same
  sensor and model; the result says its method and model;
* minimum poses: one pose fewer than ``min_poses`` is refused (``TooFewPosesError``),
  ``min_poses`` noise-free poses are fitted exactly;
* batch = single: the batched form gives every trial's single-problem estimate, and
  fails (``valid=False``, same error name) where the single-problem form raises;
* compiled = reference: with a compiled kernel, numba and numpy agree to rounding;
  without one, forcing either backend changes nothing;
* JSON round trip: a calibration by it saves, loads (its class found by ``cal_type``)
  and compares equal;
* ``apply`` inverts the fitted model ``z = M x + b``;
* noise level: ``noise_use`` is declared iff the function takes ``noise_std``; an
  estimator without it ignores the level; a correction with zero noise is the estimator
  it corrects; a stopping rule changes the estimate by less than the noise;
* g: ``needs_g`` is honest (the estimate moves with g iff it says so).
"""

from __future__ import annotations

import inspect
import json
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal import kernels
from accelcal.calibration import Calibration, calibrate_poses, calibration_class, load_calibration
from accelcal.errors import AccelcalError, TooFewPosesError
from accelcal.registry import ESTIMATORS, PoseEstimator, estimators
from accelcal.simulation import random_directions, sample_truth, simulate_poses

G = 9.8055
HAVE_NUMBA = kernels._resolve("auto") == "numba"


def problem(e: PoseEstimator, rng, n: int, noise: float):
    """Poses of the estimator's model (``M = I`` for a bias-only one) and the truth."""
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    M = np.eye(3) if e.model == "bias" else tr["M"]
    return simulate_poses(random_directions(rng, n), G, M, tr["bias"], noise, rng), M, tr["bias"]


def no_ellipsoid(rng, n: int) -> np.ndarray:
    """Points on a hyperboloid x² + y² - z² = 25: no ellipsoid fits them."""
    a, h = rng.uniform(0, 2 * np.pi, n), rng.uniform(-3, 3, n)
    r = np.sqrt(25 + h**2)
    return np.column_stack([r * np.cos(a), r * np.sin(a), h])


def outcome(e: PoseEstimator, z, g=G, **kw):
    """The result, or the name of the AccelcalError it raised."""
    try:
        return e.fit(z, g, **kw)
    except AccelcalError as err:
        return type(err).__name__


# ----------------------------------------------------------------------------- checks
def check_entry(e: PoseEstimator, rng):
    assert callable(e.load()) and callable(e.load_conditioning())
    assert e.batch is None or callable(e.load_batch())
    cls = e.load_calibration()
    assert issubclass(cls, Calibration) and cls.__dict__.get("CAL_TYPE") == e.name
    assert calibration_class(e.name) is cls
    for other in (e.baseline, e.corrects):
        if other is not None:
            o = ESTIMATORS[other]
            assert (o.sensor, o.model) == (e.sensor, e.model), (e.name, other)
    z, _, _ = problem(e, rng, 24, 1e-3)
    r = e.fit(z, G)
    assert r.method == e.name and r.model == e.model and r.n_parameters == e.n_parameters
    if e.model == "bias":
        np.testing.assert_array_equal(r.M, np.eye(3))
    sv = r.singular_values if hasattr(r, "singular_values") else e.load_conditioning()(e.model, z)
    assert np.all(np.isfinite(sv))


def check_min_poses(e: PoseEstimator, rng):
    z, M, b = problem(e, rng, e.min_poses, 0.0)
    with pytest.raises(TooFewPosesError, match=str(e.min_poses)):
        e.fit(z[:-1], G)
    r = e.fit(z, G, noise_std=0.0)  # noise-free: an iterative estimator stops at its tightest
    scale = e.n_parameters  # an exact fit of q + 1 poses leaves no residual
    assert np.sqrt(np.mean(np.square(r.residuals))) < 1e-9 * G * scale, r.residuals
    np.testing.assert_allclose(r.bias, b, atol=1e-7 * G)
    np.testing.assert_allclose(r.M, M, atol=1e-7)


def check_batch_equals_single(e: PoseEstimator, rng):
    trials = [problem(e, rng, n, noise)[0] for n, noise in ((24, 1e-3), (24, 1e-2), (24, 1e-5))]
    trials.append(no_ellipsoid(rng, 24))
    Z = np.stack(trials)
    br = e.fit_batch(Z, G, noise_std=1e-3)
    assert br.method == e.name and br.bias.shape == (4, 3) and br.M.shape == (4, 3, 3)
    assert br.status is not None and len(br.status) == 4
    for t, z in enumerate(Z):
        single = outcome(e, z, noise_std=1e-3)
        if isinstance(single, str):
            assert not br.valid[t] and np.isnan(br.bias[t]).all(), (t, single)
            assert br.status[t] == single or br.status[t] not in _ERROR_NAMES, (t, br.status[t], single)
            continue
        assert br.valid[t], (t, br.status[t])
        np.testing.assert_allclose(br.bias[t], single.bias, rtol=0, atol=1e-10 * G)
        np.testing.assert_allclose(br.M[t], single.M, rtol=0, atol=1e-10)


_ERROR_NAMES = {c.__name__ for c in (AccelcalError, *AccelcalError.__subclasses__())}


def check_compiled_equals_reference(e: PoseEstimator, rng):
    singles = [problem(e, rng, n, noise)[0] for n, noise in ((e.min_poses + 2, 1e-3), (24, 1e-2), (100, 1e-5))]
    Z = np.stack([problem(e, rng, 24, 1e-3)[0] for _ in range(3)])
    previous = kernels.choice()
    out = {}
    try:
        for be in ("numba", "numpy") if HAVE_NUMBA else ("numpy",):
            kernels.set_backend(be)
            out[be] = ([e.fit(z, G, noise_std=1e-3) for z in singles], e.fit_batch(Z, G, noise_std=1e-3))
    finally:
        kernels.set_backend(previous)
    if not HAVE_NUMBA:
        pytest.skip("numba (the fast extra) is not installed: only the numpy path runs")
    (s1, b1), (s2, b2) = out["numba"], out["numpy"]
    tol = 1e-10 if e.compiled else 0.0  # no kernel: the very same computation
    for a, b in zip(s1, s2):
        np.testing.assert_allclose(a.bias, b.bias, rtol=0, atol=tol * G)
        np.testing.assert_allclose(a.M, b.M, rtol=0, atol=tol)
    np.testing.assert_array_equal(b1.valid, b2.valid)
    np.testing.assert_allclose(b1.bias, b2.bias, rtol=0, atol=tol * G)


def _poses(z, noise):
    n = len(z)
    return SimpleNamespace(means=z, mean_std=np.full((n, 3), noise), t_start=np.arange(n) * 10.0,
                           t_end=np.arange(n) * 10.0 + 5.0, n_samples=np.full(n, 500), temp=None, labels=None)


def check_json_round_trip(e: PoseEstimator, rng, tmp_path):
    z, _, _ = problem(e, rng, 24, 1e-3)
    cal = calibrate_poses(_poses(z, 1e-3), G, e.name, unit="m/s^2")
    assert type(cal) is e.load_calibration() and cal.method == e.name and cal.model == e.model
    back = Calibration.from_json(cal.to_json())
    assert type(back) is type(cal) and back == cal
    cal.save(tmp_path / f"{e.name}.json")
    again = load_calibration(tmp_path / f"{e.name}.json")
    assert again == cal
    d = json.loads((tmp_path / f"{e.name}.json").read_text())
    assert d["cal_type"] == e.name and d["method"] == e.cli_name
    # the class's own fields are in the file, under their names
    for name in type(cal)._method_field_names():
        assert name in d, name


def check_apply_inverts(e: PoseEstimator, rng):
    z, _, _ = problem(e, rng, 24, 1e-3)
    cal = calibrate_poses(_poses(z, 1e-3), G, e.name, unit="m/s^2")
    x = rng.normal(size=(50, 3)) * G
    raw = x @ cal.M.T + cal.bias  # the fitted model z = M x + b
    np.testing.assert_allclose(cal.apply(raw), x, rtol=0, atol=1e-12 * G)
    # and the pose means come back on the sphere of radius g, up to the fit's residuals
    np.testing.assert_allclose(np.linalg.norm(cal.apply(z), axis=1) - G, cal.residuals, rtol=0, atol=1e-12 * G)


def check_noise_level(e: PoseEstimator, rng):
    takes_noise = "noise_std" in inspect.signature(e.load()).parameters
    assert takes_noise == e.needs_noise, (e.name, e.noise_use)
    z, _, _ = problem(e, rng, 24, 1e-2)
    plain = e.fit(z, G)
    if not e.needs_noise:  # the level is ignored
        told = e.fit(z, G, noise_std=1e-2)
        np.testing.assert_array_equal(told.bias, plain.bias)
        np.testing.assert_array_equal(told.M, plain.M)
        return
    told = e.fit(z, G, noise_std=1e-2)
    if e.noise_use == "correction":
        # corrected for nothing, it is the estimator it corrects; for the noise, it moves
        zero = e.fit(z, G, noise_std=0.0)
        base = ESTIMATORS[e.corrects].fit(z, G)
        np.testing.assert_allclose(zero.bias, base.bias, rtol=0, atol=1e-9 * G)
        np.testing.assert_allclose(zero.M, base.M, rtol=0, atol=1e-9)
        assert np.abs(told.M - zero.M).max() > 1e-9
    else:  # a stopping rule: stopped at the noise's accuracy, it moves by far less than the noise
        assert np.abs(told.bias - plain.bias).max() < 1e-2


def check_needs_g(e: PoseEstimator, rng):
    z, _, _ = problem(e, rng, 24, 1e-3)
    a, b = e.fit(z, G), e.fit(z, 1.1 * G)
    moved = max(np.abs(a.bias - b.bias).max() / G, np.abs(a.M - b.M).max())
    if e.needs_g:
        assert moved > 1e-3, moved
    else:
        assert moved < 1e-12, moved


CHECKS = (check_entry, check_min_poses, check_batch_equals_single, check_compiled_equals_reference,
          check_json_round_trip, check_apply_inverts, check_noise_level, check_needs_g)


def run_check(check, e: PoseEstimator, tmp_path):
    """Run ``check`` on ``e`` with its own random stream (and a folder if it needs one)."""
    rng = np.random.default_rng([20240601, CHECKS.index(check)])
    if "tmp_path" in inspect.signature(check).parameters:
        return check(e, rng, tmp_path)
    return check(e, rng)


@pytest.mark.parametrize("name", [e.name for e in estimators("accelerometer")])
@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_conformance(check, name, tmp_path):
    run_check(check, ESTIMATORS[name], tmp_path)


def test_every_registered_estimator_has_a_conformance_suite():
    """The accelerometer's here, the gyroscope's in test_gyro_conformance: no entry unchecked."""
    from .test_gyro_conformance import GYRO_CHECKS

    assert {e.sensor for e in ESTIMATORS.values()} <= {"accelerometer", *GYRO_CHECKS}
    assert all(isinstance(e, PoseEstimator) and e.data == "poses" for e in estimators("accelerometer"))


def test_the_checks_can_fail(tmp_path):
    """A registry entry that lies (bias_lls declared as depending on g, full_lls as taking
    a noise level, the batch form or calibration class of another estimator, a minimum
    of poses the estimator does not enforce, a compiled estimator declared as not compiled) fails its check."""
    from dataclasses import replace

    lies = [(check_needs_g, replace(ESTIMATORS["bias_lls"], needs_g=True)),
            (check_noise_level, replace(ESTIMATORS["full_lls"], noise_use="correction", corrects="full_lls")),
            (check_batch_equals_single, replace(ESTIMATORS["full_lls"], batch="accelcal.als:full_als_batch")),
            (check_min_poses, replace(ESTIMATORS["full_lls"], min_poses=11)),
            (check_entry, replace(ESTIMATORS["full_lls"], calibration="accelcal.calibration:FullALSCalibration"))]
    if HAVE_NUMBA:
        lies.append((check_compiled_equals_reference, replace(ESTIMATORS["full_lls"], compiled=False)))
    for check, e in lies:
        with pytest.raises((AssertionError, pytest.fail.Exception)):  # fail: a refusal that did not come
            run_check(check, e, tmp_path)


@pytest.mark.parametrize("name", [e.name for e in estimators("accelerometer")])
def test_batch_refuses_degenerate_poses_as_the_single_form_does(name):
    e = ESTIMATORS[name]
    rng = np.random.default_rng(3)
    z, _, _ = problem(e, rng, 24, 1e-3)
    flat = np.column_stack([z[:, :2], np.zeros(len(z))])  # coplanar poses
    assert outcome(e, flat) == "DegeneratePosesError"
    br = e.fit_batch(np.stack([z, flat]), G)
    assert not br.valid[1] and br.status[1] == "DegeneratePosesError"
