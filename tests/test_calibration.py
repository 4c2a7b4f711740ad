"""Calibration objects: one class per method, versioned JSON round trip, apply (with the
discrepancy effects), loading older and foreign files, and the quality they carry."""

from __future__ import annotations

import json

import numpy as np
import pytest

from accelcal.calibration import (FORMAT_VERSION, Calibration, CalibrationFileError, EffectTerm, ExtendedCalibration,
                                  FullLLSCalibration, calibrate_recording, calibration_class, load_calibration)
from accelcal.errors import AccelcalError
from accelcal.model import m_from_params
from accelcal.recording import Recording
from accelcal.registry import ESTIMATORS, estimators
from accelcal.simulation import random_directions, sample_truth, simulate_recording

G = 9.80665


@pytest.fixture(scope="module")
def rec():
    rng = np.random.default_rng(21)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 29)])
    sim = simulate_recording(rng, u, G, tr["M"], tr["bias"], noise_std=0.01, temperature=(20.0, 24.0))
    return Recording(sim["t"], sim["acc"], sim["temp"], "sim", unit="m/s^2"), tr


class _StaleToyCalibration(Calibration):
    """A class of a type tag that a later registry entry names another class for (a script's
    class defined again, an estimator of that name registered before)."""

    CAL_TYPE = "toy_tagged"


class ToyTaggedCalibration(Calibration):
    CAL_TYPE = "toy_tagged"


def test_the_registrys_class_comes_before_another_of_the_same_tag():
    from accelcal.registry import PoseEstimator, register, unregister

    register(PoseEstimator(name="toy_tagged", model="bias", algorithm="lls", label="toy", family="closed_form",
                       function="accelcal.lls:bias_lls", calibration=f"{__name__}:ToyTaggedCalibration",
                       conditioning="accelcal.lls:design_singular_values", min_poses=4, description="a test's toy"))
    try:
        assert calibration_class("toy_tagged") is ToyTaggedCalibration
    finally:
        unregister("toy_tagged")
    assert calibration_class("toy_tagged") is _StaleToyCalibration  # unregistered: the first subclass found


@pytest.mark.parametrize("method", [e.name for e in estimators("accelerometer")])
def test_one_class_per_method_and_exact_round_trip(rec, method, tmp_path):
    r, tr = rec
    cal, poses = calibrate_recording(r, G, method)
    assert type(cal) is calibration_class(method) is ESTIMATORS[method].load_calibration() and cal.CAL_TYPE == method
    back = Calibration.from_json(cal.to_json())
    assert type(back) is type(cal) and back == cal
    cal.save(tmp_path / "c.json")
    again = load_calibration(tmp_path / "c.json")
    assert again == cal
    d = json.loads((tmp_path / "c.json").read_text())
    assert d["format"] == "accelcal-calibration" and d["format_version"] == FORMAT_VERSION
    assert d["units"]["bias"] == "m/s^2" and d["units"]["M"] == "1" and d["unit"] == "m/s^2"
    # applied to the recording, the poses have |x| = g up to the residuals of the fit
    x = again.apply(r.acc, t=r.t, temp=r.temp)
    for (a, b), res in zip(poses.intervals, cal.residuals):
        assert np.linalg.norm(x[a:b].mean(axis=0)) - G == pytest.approx(res, abs=1e-9)
    if ESTIMATORS[method].model == "full":
        np.testing.assert_allclose(cal.bias, tr["bias"], atol=3e-3)


def test_quality_of_a_clean_fit_has_no_warning(rec):
    cal, _ = calibrate_recording(rec[0], G, "full_lls")
    q = cal.quality
    assert q.trustworthy and q.warnings == ()
    assert q.dof == 30 - 9 and 0.5 < q.excess < 1.6 and q.p_value > 1e-3
    assert q.distinct_orientations >= 25 and q.coverage > 0.6  # random directions: a few within 10°
    # the ± come from the pose noise, not from the residuals
    assert set(cal.standard_errors_noise) >= {"bias", "scale_factors", "nonorthogonality_deg"}


def test_ten_poses_warn_about_the_single_degree_of_freedom():
    rng = np.random.default_rng(2)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    sim = simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, 9)]), G, tr["M"], tr["bias"], 0.01)
    cal, _ = calibrate_recording(Recording(sim["t"], sim["acc"], None, "s", unit="m/s^2"), G, "full_lls")
    assert cal.quality.dof == 1
    assert any("1 degree(s) of freedom" in w for w in cal.quality.warnings)


def test_newer_format_missing_keys_and_unknown_type_are_refused(rec, tmp_path):
    cal, _ = calibrate_recording(rec[0], G, "full_lls")
    d = cal.to_dict()
    for change, words in (({"format_version": FORMAT_VERSION + 1}, "newer"), ({"cal_type": "magic"}, "unknown"),
                          ({"M": [[1, 0], [0, 1]]}, "M")):
        p = tmp_path / "bad.json"
        p.write_text(json.dumps({**d, **change}))
        with pytest.raises(CalibrationFileError, match=words) as e:
            load_calibration(p)
        assert "\n" not in str(e.value) and str(p) in str(e.value)
    p.write_text(json.dumps({k: v for k, v in d.items() if k != "bias"}))
    with pytest.raises(CalibrationFileError, match="'bias' missing"):
        load_calibration(p)
    p.write_text("{not json")
    with pytest.raises(CalibrationFileError, match="invalid JSON"):
        load_calibration(p)


def test_format_1_files_load_without_a_gyroscope(rec, tmp_path):
    """Format 2 adds the ``gyroscope`` object; a format-1 file (the accelerometer alone) loads as before."""
    cal, _ = calibrate_recording(rec[0], G, "full_lls")
    d = cal.to_dict()
    assert d["format_version"] == 2 and d["gyroscope"] is None
    v1 = {k: v for k, v in d.items() if k != "gyroscope"} | {"format_version": 1}
    p = tmp_path / "v1.json"
    p.write_text(json.dumps(v1))
    old = load_calibration(p)
    assert old.gyro is None and old == cal
    np.testing.assert_array_equal(old.apply(rec[0].acc), cal.apply(rec[0].acc))
    with pytest.raises(CalibrationFileError, match="no gyroscope"):
        old.apply_gyro(np.zeros((3, 3)))


def test_format_0_files_of_the_older_cli_load(tmp_path):
    old = {"method": "full-lls", "g": G, "n_poses": 12, "bias": [0.1, -0.2, 0.05], "M": np.eye(3).tolist(),
           "scale_factors": [0, 0, 0], "nonorthogonality_deg": [0, 0, 0], "residual_rms": 0.001,
           "standard_errors": {"bias": [1e-3] * 3}, "accelcal_version": "0.1.0", "recording": "x.csv"}
    p = tmp_path / "old.json"
    p.write_text(json.dumps(old))
    cal = load_calibration(p)
    assert isinstance(cal, FullLLSCalibration) and cal.unit is None
    np.testing.assert_allclose(cal.apply([[0.1, -0.2, 9.85665]]), [[0, 0, 9.80665]])


def _forward(x, M, b, terms, dt, dT):
    """The extended model z = M P(x) + b + β Δt + γ ΔT written out independently of the code."""
    P = x.copy()
    add = np.zeros_like(x)
    for eid, v in terms.items():
        if eid == "quadratic":
            P = P + v * x ** 2
        elif eid == "cubic":
            P = P + v * x ** 3
        elif eid == "temperature_scale":
            P = P + v * x * dT[:, None]
        elif eid == "bias_drift":
            add = add + v * dt[:, None]
        elif eid == "temperature":
            add = add + v * dT[:, None]
    return P @ M.T + b + add


@pytest.mark.parametrize("effects", [("quadratic",), ("cubic",), ("bias_drift",), ("temperature",),
                                     ("temperature_scale",), ("quadratic", "temperature"),
                                     ("cubic", "bias_drift", "temperature_scale")])
def test_apply_inverts_every_effect(effects):
    rng = np.random.default_rng(7)
    M = m_from_params([0.01, -0.02, 0.005], [0.002, -0.001, 0.003])
    b = np.array([0.1, -0.05, 0.2])
    size = {"quadratic": 1e-3, "cubic": 1e-5, "bias_drift": 2e-4, "temperature": 3e-3, "temperature_scale": 2e-4}
    terms = {e: size[e] * rng.uniform(0.5, 1.5, 3) * rng.choice([-1, 1], 3) for e in effects}
    n = 500
    x = G * random_directions(rng, n) * rng.uniform(0.5, 1.5, (n, 1))
    t = np.linspace(0, 600, n)
    temp = np.linspace(18, 30, n)
    t_ref, temp_ref = 310.0, 23.5
    z = _forward(x, M, b, terms, t - t_ref, temp - temp_ref)
    cal = ExtendedCalibration(bias=b, M=M, g=G, unit="m/s^2", input_unit="m/s^2",
                              effects=tuple(EffectTerm(e, v, {"bias_drift": t_ref}.get(e, temp_ref)
                                                       if e not in ("quadratic", "cubic") else None)
                                            for e, v in terms.items()))
    np.testing.assert_allclose(cal.apply(z, t=t, temp=temp), x, atol=1e-10)
    back = Calibration.from_json(cal.to_json())
    np.testing.assert_allclose(back.apply(z, t=t, temp=temp), x, atol=1e-10)
    base = cal.apply(z, t=t, temp=temp, effects=False)
    assert np.max(np.abs(base - x)) > 1e-4  # the effects matter at these sizes


def test_apply_needs_the_covariates_and_the_unit():
    cal = ExtendedCalibration(bias=np.zeros(3), M=np.eye(3), g=G, unit="m/s^2", input_unit="m/s^2",
                              effects=(EffectTerm("temperature", np.array([1e-3, 0, 0]), 25.0),))
    with pytest.raises(CalibrationFileError, match="temperature term needs the temp"):
        cal.apply(np.ones((4, 3)))
    plain = ExtendedCalibration(bias=np.zeros(3), M=np.eye(3), g=G, unit="m/s^2", input_unit="m/s^2")
    np.testing.assert_allclose(plain.apply([[0, 0, 1.0]], unit="g"), [[0, 0, G]])
    with pytest.raises(CalibrationFileError, match="fitted to m/s\\^2"):
        plain.apply([[0, 0, 16384.0]], unit="counts")
    with pytest.raises(CalibrationFileError, match="shape"):
        plain.apply(np.ones(3))


def test_discrepancy_report_loads_as_an_extended_calibration(tmp_path):
    """A report of the shape `accelcal discrepancy` writes (model_after: base model + named
    effects, parameters with value/se, the poses' times and temperatures)."""
    names = {"b_x": 0.1, "b_y": -0.05, "b_z": 0.2, "s_x": 0.01, "s_y": -0.02, "s_z": 0.005, "theta_xy": 0.002,
             "theta_zx": -0.001, "theta_zy": 0.003, "gamma_x": 1e-3, "gamma_y": -2e-3, "gamma_z": 5e-4}
    report = {"effect": "temperature", "effects": ["temperature"], "g": G, "unit": "m/s^2",
              "model_after": {"effects": ["temperature"],
                              "parameters": {k: {"value": v, "se": 1e-5, "se_noise": 1e-5} for k, v in names.items()}},
              "poses": {"t": [10.0, 20.0, 30.0], "temp": [20.0, 22.0, 27.0]}}
    p = tmp_path / "d.json"
    p.write_text(json.dumps(report))
    cal = load_calibration(p)
    assert isinstance(cal, ExtendedCalibration) and [e.id for e in cal.effects] == ["temperature"]
    assert cal.effects[0].reference == pytest.approx(23.0)
    np.testing.assert_allclose(cal.M, m_from_params([0.01, -0.02, 0.005], [0.002, -0.001, 0.003]))
    x = G * random_directions(np.random.default_rng(1), 5)
    temp = np.array([19.0, 21, 23, 25, 27])
    z = _forward(x, cal.M, cal.bias, {"temperature": np.array([1e-3, -2e-3, 5e-4])}, None, temp - 23.0)
    np.testing.assert_allclose(cal.apply(z, temp=temp), x, atol=1e-12)


def test_bias_only_on_counts_is_refused_with_the_fix(rec):
    r = Recording(rec[0].t, 16384 * rec[0].acc / G, None, "c", unit="counts")
    with pytest.raises(AccelcalError, match="raw counts.*full-lls"):
        calibrate_recording(r, G, "bias_lls")
