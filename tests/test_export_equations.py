"""Each export, read back and applied as its consumer's own source applies it, equals ``accelcal apply``.

Every test below implements the consumer's correction exactly as its source does (repository,
file and line cited beside it) on a calibration with every term of accelcal's model
non-zero (``M`` full lower triangular, ``b``, the gyroscope's nine ``C``, ``b``, ``G``), and
checks raw data corrected that way against :meth:`Calibration.apply` / ``apply_gyro`` to
1e-9 relative.  Where a consumer's model cannot hold a term (PX4, ArduPilot, KF-GINS: no
misalignment; IMU-TK: no g-sensitivity), it equals apply on a calibration of the terms it
holds, and on the full calibration the error it leaves is within the cost the summary
states (and close to it: the cost is the worst orientation's).  The noise-only consumers
(VINS, ORB-SLAM3) are checked by their own covariance propagation.
"""

from __future__ import annotations

import json
import math
import re

import cv2
import numpy as np
import pytest

from accelcal.export.api import ExportInputs, export
from .export_fixtures import full_calibration, noise_report

yaml = pytest.importorskip("yaml")

REL = 1e-9
G = 9.81


def _data(cal, n=400, seed=11):
    """Raw samples of the calibration's own model: specific forces of |f| ~ g in every direction, rates to 3 rad/s."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 3))
    f = G * u / np.linalg.norm(u, axis=1, keepdims=True) * rng.uniform(0.5, 1.5, (n, 1))
    w = rng.uniform(-3, 3, (n, 3))
    raw_a = f @ cal.M.T + cal.bias
    raw_g = cal.gyro.model.measure(w, f) if cal.gyro is not None else None
    return raw_a, raw_g


def _apply(cal, raw_a, raw_g):
    return cal.apply(raw_a), (None if raw_g is None else cal.apply_gyro(raw_g, raw_a))


def _rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


def _one(name, cal, **options):
    return export(name, ExportInputs(cal, noise_report(), {"source": "cal.json", **options}))


def _vec_comment(text, label):
    m = re.search(re.escape(label) + r"[^:\n]*: \[([^\]]*)\]", text)
    return np.array([float(v) for v in m.group(1).split(",")])


def _cost(result, words):
    line = next(x.cost for x in result.left_out if words in x.term)
    return float(re.search(r"up to ([0-9.eE+-]+)", line).group(1))


# --------------------------------------------------------------------------- Kalibr


def test_kalibr_scale_misalignment_model_equals_apply():
    cal = full_calibration()
    r = _one("kalibr", cal)
    text = r.files[""]
    y = yaml.safe_load(text)
    assert y["model"] == "scale-misalignment" and y["update_rate"] == 200.0
    Ma = np.array(y["accelerometers"]["M"])
    Mg, A, Cgi = (np.array(y["gyroscopes"][k]) for k in ("M", "A", "C_gyro_i"))
    ba, bg = _vec_comment(text, "bias b_a"), _vec_comment(text, "bias b_g")
    raw_a, raw_g = _data(cal)
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    # ethz-asl/kalibr aslam_offline_calibration/kalibr/python/kalibr_imu_camera_calibration/IccSensors.py
    # l. 999-1002: alpha = M (C_i_b a_b) + b_i  (C_i_b = I: the IMU frame is accelcal's)
    f = np.linalg.solve(Ma, (raw_a - ba).T).T
    # l. 1045-1051: omega = M (C_gyro_i C_i_b w_b) + Ma (C_gyro_i C_i_b a_b) + b_i
    w = np.linalg.solve(Mg @ Cgi, (raw_g - bg - f @ (A @ Cgi).T).T).T
    assert _rel(f, f_ref) < REL and _rel(w, w_ref) < REL
    assert np.allclose(np.triu(Ma, 1), 0) and np.allclose(np.triu(Mg, 1), 0)  # Kalibr's lower-triangular M
    assert np.allclose(Cgi @ Cgi.T, np.eye(3), atol=1e-12) and np.linalg.det(Cgi) > 0


# --------------------------------------------------------------------------- OpenVINS


def _filestorage_node(text, tmp_path):
    """The file as OpenVINS opens it: ``cv::FileStorage(path, READ)``, node ``imu0``.

    rpng/open_vins ov_core/src/utils/opencv_yaml_parse.h l. 590-600 (parse_external_yaml opens the
    external file with cv::FileStorage) and l. 448-468 (a Matrix3d is read element by element,
    ``(double)file_node[node_name][r][c]``); scalars by ``file_node[node_name] >> value`` (l. 372).
    """
    path = tmp_path / "kalibr_imu_chain.yaml"
    path.write_text(text)
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    assert fs.isOpened(), "OpenCV's FileStorage cannot open the export"
    return fs, fs.getNode("imu0")


def _openvins_read(text, tmp_path):
    """ov_msckf/src/core/VioManagerOptions.h l. 306-351 and ov_msckf/src/state/State.h l. 91-116."""
    assert text.startswith("%YAML:1.0\n")  # OpenCV FileStorage's header, which OpenVINS's parser needs
    fs, node = _filestorage_node(text, tmp_path)
    y = yaml.safe_load(text.split("\n", 1)[1])["imu0"]

    def mat3(name):
        n = node.getNode(name)
        assert n.isSeq() and n.size() == 3, name
        return np.array([[n.at(r).at(c).real() for c in range(3)] for r in range(3)])

    Tw, Ta, R_ia, R_ig, Tg = (mat3(k) for k in ("Tw", "Ta", "R_IMUtoACC", "R_IMUtoGYRO", "Tg"))
    # OpenCV reads every number PyYAML reads (a key OpenCV misparsed would be silently wrong there)
    for key, value in y.items():
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            assert node.getNode(key).real() == pytest.approx(value, rel=1e-15, abs=0), key
    assert node.getNode("model").string() == y["model"]
    for k, m in zip(("Tw", "Ta", "R_IMUtoACC", "R_IMUtoGYRO", "Tg"), (Tw, Ta, R_ia, R_ig, Tg)):
        assert np.array_equal(m, np.array(y[k], float)), k
    fs.release()
    Dw, Da = np.linalg.inv(Tw), np.linalg.inv(Ta)                           # l. 319-320
    R_ACCtoIMU, R_GYROtoIMU = R_ia.T, R_ig.T                                 # l. 321-322
    if y["model"] == "kalibr":                                               # l. 342-344, State::Dm l. 95-96
        vec_dw = [Dw[0, 0], Dw[1, 0], Dw[2, 0], Dw[1, 1], Dw[2, 1], Dw[2, 2]]
        vec_da = [Da[0, 0], Da[1, 0], Da[2, 0], Da[1, 1], Da[2, 1], Da[2, 2]]

        def Dm(v):
            return np.array([[v[0], 0, 0], [v[1], v[3], 0], [v[2], v[4], v[5]]])
    else:                                                                    # l. 346-347, State::Dm l. 97-98
        vec_dw = [Dw[0, 0], Dw[0, 1], Dw[1, 1], Dw[0, 2], Dw[1, 2], Dw[2, 2]]
        vec_da = [Da[0, 0], Da[0, 1], Da[1, 1], Da[0, 2], Da[1, 2], Da[2, 2]]

        def Dm(v):
            return np.array([[v[0], v[1], v[3]], [0, v[2], v[4]], [0, 0, v[5]]])
    vec_tg = np.concatenate([Tg[:, 0], Tg[:, 1], Tg[:, 2]])                  # l. 349
    Tg = np.array([[vec_tg[0], vec_tg[3], vec_tg[6]], [vec_tg[1], vec_tg[4], vec_tg[7]],
                   [vec_tg[2], vec_tg[5], vec_tg[8]]])                         # State::Tg l. 110-115
    return y, Dm(vec_dw), Dm(vec_da), R_ACCtoIMU, R_GYROtoIMU, Tg


@pytest.mark.parametrize("model", ["kalibr", "rpng"])
def test_openvins_intrinsics_in_both_models_equal_apply(model, tmp_path):
    cal = full_calibration(seed=5)
    text = _one("openvins", cal, model=model).files[""]
    y, Dw, Da, R_ACCtoIMU, R_GYROtoIMU, Tg = _openvins_read(text, tmp_path)
    ba = _vec_comment(text, "accelerometer bias b_a")
    bg = _vec_comment(text, "gyroscope bias b_g")
    raw_a, raw_g = _data(cal)
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    # rpng/open_vins ov_msckf/src/state/Propagator.cpp l. 184-190
    a_hat = (R_ACCtoIMU @ Da @ (raw_a - ba).T).T
    w_hat = (R_GYROtoIMU @ Dw @ (raw_g - bg - a_hat @ Tg.T).T).T
    P = np.eye(3)
    if model == "rpng":  # the IMU frame is the gyroscope's: the file states P (w_IMU = P w_accelcal)
        rows = re.search(r"P = \[([^\]]*)\]", text).group(1).split(";")
        P = np.array([[float(v) for v in row.split(",")] for row in rows])
        assert np.allclose(np.array(y["R_IMUtoGYRO"]), np.eye(3))
    assert _rel(a_hat @ P, f_ref) < REL and _rel(w_hat @ P, w_ref) < REL


# --------------------------------------------------------------------------- IMU-TK and imucal


def _calib(text):
    rows = [[float(v) for v in line.split()] for line in text.splitlines() if line.strip()]
    return np.array(rows[0:3]), np.array(rows[3:6]), np.array([r[0] for r in rows[6:9]])


def test_imutk_files_equal_apply_and_the_left_out_g_sensitivity_costs_what_the_summary_says():
    cal = full_calibration(seed=8, g_sensitivity=False)
    r = _one("imutk", cal)
    raw_a, raw_g = _data(cal)
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    # Kyle-ak/imu_tk include/imu_tk/calibration.h l. 163-165: unbiasNormalize = ms_mat_ (raw - bias_vec_),
    # l. 433: ms_mat_ = mis_mat_ * scale_mat_; the .calib layout is T, K, b (CalibratedTriad_::save)
    T, K, b = _calib(r.files["_acc.calib"])
    Tg, Kg, bg = _calib(r.files["_gyro.calib"])
    assert _rel((T @ K @ (raw_a - b).T).T, f_ref) < REL
    assert _rel((Tg @ Kg @ (raw_g - bg).T).T, w_ref) < REL
    assert not r.left_out
    full = full_calibration(seed=8)
    r = _one("imutk", full)
    raw_a, raw_g = _data(full, n=20000)
    Tg, Kg, bg = _calib(r.files["_gyro.calib"])
    err = np.degrees(np.linalg.norm((Tg @ Kg @ (raw_g - bg).T).T - _apply(full, raw_a, raw_g)[1], axis=1))
    cost = _cost(r, "g-sensitivity")  # deg/s at |f| = g; the data's |f| goes to 1.5 g
    sel = np.abs(np.linalg.norm(_apply(full, raw_a, raw_g)[0], axis=1) - G) < 0.02 * G
    assert err[sel].max() <= 1.02 * cost * 1.001 and err[sel].max() > 0.8 * cost


def test_imucal_reads_the_export_and_calibrates_as_apply():
    imucal = pytest.importorskip("imucal")
    cal = full_calibration(seed=9)
    text = _one("imucal", cal).files[""]
    info = imucal.CalibrationInfo.from_json(text)  # mad-lab-fau/imucal: its own reader and calibrate()
    raw_a, raw_g = _data(cal)
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    acc, gyr = info.calibrate(raw_a, raw_g, "m/s^2", "rad/s")
    assert _rel(acc, f_ref) < REL and _rel(np.radians(gyr), w_ref) < REL
    assert json.loads(text)["cal_type"] == "Ferraris"


# --------------------------------------------------------------------------- PX4 and ArduPilot


def _px4_read(text):
    params = {}
    for line in text.splitlines():
        if line and not line.startswith("#"):
            vehicle, component, name, value, kind = line.split("\t")
            params[name] = float(value) if kind == "9" else int(value)
    return params


def _ardupilot_read(text):
    return {n: float(v) for n, v in (line.split() for line in text.splitlines() if line and not line.startswith("#"))}


def _px4_correct(p, raw_a, raw_g, n=0):
    # PX4/PX4-Autopilot src/lib/sensor_calibration/Accelerometer.hpp l. 82-85:
    #   Correct(data) = _rotation * (data - _thermal_offset - _offset).emult(_scale)   (rotation: identity here)
    off = np.array([p[f"CAL_ACC{n}_{a}OFF"] for a in "XYZ"])
    scale = np.array([p[f"CAL_ACC{n}_{a}SCALE"] for a in "XYZ"])
    # Gyroscope.hpp l. 75-78: Correct(data) = _rotation * (data - _thermal_offset - _offset)
    goff = np.array([p[f"CAL_GYRO{n}_{a}OFF"] for a in "XYZ"])
    return (raw_a - off) * scale, raw_g - goff


def _ardupilot_correct(p, raw_a, raw_g):
    # ArduPilot/ardupilot libraries/AP_InertialSensor/AP_InertialSensor_Backend.cpp
    # _rotate_and_correct_accel: l. 123 accel -= _accel_offset; l. 127-130 accel.x *= accel_scale.x ...
    accel = raw_a - np.array([p[f"INS_ACCOFFS_{a}"] for a in "XYZ"])
    accel = accel * np.array([p[f"INS_ACCSCAL_{a}"] for a in "XYZ"])
    # _rotate_and_correct_gyro: l. 156 gyro -= _gyro_offset
    return accel, raw_g - np.array([p[f"INS_GYROFFS_{a}"] for a in "XYZ"])


@pytest.mark.parametrize("name,read,correct", [("px4", _px4_read, _px4_correct),
                                               ("ardupilot", _ardupilot_read, _ardupilot_correct)])
def test_autopilot_parameters_equal_apply_on_the_terms_they_hold(name, read, correct):
    cal = full_calibration(seed=4, diagonal=True, gyro_scale=False)
    r = _one(name, cal)
    raw_a, raw_g = _data(cal)
    f, w = correct(read(r.files[""]), raw_a, raw_g)
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    assert _rel(f, f_ref) < 1e-8 and _rel(w, w_ref) < 1e-8  # the files hold 9 significant digits (float32 params)
    assert not [x for x in r.left_out if "non-orthogonality" in x.term or "scale" in x.term]


@pytest.mark.parametrize("name,read,correct", [("px4", _px4_read, _px4_correct),
                                               ("ardupilot", _ardupilot_read, _ardupilot_correct)])
def test_autopilot_parameters_leave_out_what_the_summary_says_it_costs(name, read, correct):
    cal = full_calibration(seed=4)
    r = _one(name, cal)
    rng = np.random.default_rng(2)
    u = rng.standard_normal((40000, 3))
    f_true = G * u / np.linalg.norm(u, axis=1, keepdims=True)        # every orientation, |f| = g, at rest
    raw_a = f_true @ cal.M.T + cal.bias
    raw_g = cal.gyro.model.measure(np.zeros_like(f_true), f_true)
    f, w = correct(read(r.files[""]), raw_a, raw_g)
    acc_mg = 1e3 * np.linalg.norm(f - cal.apply(raw_a), axis=1).max() / 9.80665
    cost = _cost(r, "non-orthogonality")
    assert 0.95 * cost < acc_mg <= 1.005 * cost, (acc_mg, cost)
    g_dps = np.degrees(np.linalg.norm(w - cal.apply_gyro(raw_g, raw_a), axis=1)).max()
    cost = _cost(r, "g-sensitivity")
    assert 0.95 * cost < g_dps <= 1.005 * cost, (g_dps, cost)
    # at 100 deg/s without gravity's term: the scale and misalignment's cost
    spin = np.radians(100.0) * u / np.linalg.norm(u, axis=1, keepdims=True)
    raw_g = np.linalg.solve(cal.gyro.model.C, spin.T).T + cal.gyro.model.bias
    _, w = correct(read(r.files[""]), raw_a, raw_g)
    cost = _cost(r, "scale and misalignment")
    dps = np.degrees(np.linalg.norm(w - spin, axis=1)).max()
    assert 0.95 * cost < dps <= 1.005 * cost, (dps, cost)


# --------------------------------------------------------------------------- KF-GINS


def test_kfgins_initial_errors_and_noise_follow_its_source():
    cal = full_calibration(seed=6, diagonal=True, gyro_scale=True)
    r = _one("kfgins", cal, corr_time_h=2.0)
    y = yaml.safe_load(r.files[""])
    D2R = math.pi / 180.0
    # i2Nav-WHU/KF-GINS src/kf_gins.cpp l. 259-263: the initial IMU errors' units
    gyrbias = np.array(y["initgyrbias"]) * D2R / 3600.0
    accbias = np.array(y["initaccbias"]) * 1e-5
    gyrscale, accscale = np.array(y["initgyrscale"]) * 1e-6, np.array(y["initaccscale"]) * 1e-6
    raw_a, raw_g = _data(cal)
    dt = 1.0 / 200.0
    dtheta, dvel = raw_g * dt, raw_a * dt
    # src/kf-gins/gi_engine.cpp l. 157-171 (imuCompensate)
    dtheta = dtheta - gyrbias * dt
    dvel = dvel - accbias * dt
    dtheta = dtheta * (1.0 / (1.0 + gyrscale))
    dvel = dvel * (1.0 / (1.0 + accscale))
    f_ref, w_ref = _apply(cal, raw_a, raw_g)
    assert _rel(dvel / dt, f_ref) < 1e-8 and _rel(dtheta / dt, w_ref) < 1e-8  # 6 significant digits x ppm
    # kf_gins.cpp l. 342-348: the noise's units; gi_engine.cpp l. 46-52: Qc = arw^2, 2 sigma^2 / T for the biases
    n = y["imunoise"]
    noise = noise_report()
    N_g = [noise["sensors"]["gyroscope"]["axes"][a]["noise_density"]["value"] for a in "xyz"]
    K_a = [noise["sensors"]["accelerometer"]["axes"][a]["random_walk"]["value"] for a in "xyz"]
    assert np.allclose(np.array(n["arw"]) * D2R / 60.0, N_g, rtol=1e-5)
    T = n["corrtime"] * 3600.0
    q_ba = 2.0 / T * (np.array(n["abstd"]) * 1e-5) ** 2
    assert np.allclose(q_ba, np.square(K_a), rtol=1e-5)  # the GM's driving noise is the measured random walk


# --------------------------------------------------------------------------- VINS and ORB-SLAM3


def _worst(sensor, what):
    return max(noise_report()["sensors"][sensor]["axes"][a][what]["value"] for a in "xyz")


def test_vins_noise_is_what_its_propagation_needs():
    y = yaml.safe_load(_one("vins", full_calibration()).files[""].split("\n", 1)[1])
    fs = 200.0
    dt = 1.0 / fs
    # HKUST-Aerial-Robotics/VINS-Fusion vins_estimator/src/factor/integration_base.h:
    # l. 31-36 noise = diag(ACC_N^2, GYR_N^2, ACC_N^2, GYR_N^2, ACC_W^2, GYR_W^2);
    # l. 123, 125 V(6,0) = V(6,6) = 0.5 R dt (R = I here); l. 127 V(9,12) = I dt; l. 134 P += V noise V^T
    var_v = (0.5 * dt) ** 2 * y["acc_n"] ** 2 * 2
    var_ba = dt ** 2 * y["acc_w"] ** 2
    # the truth: samples of white noise of density N at fs have variance N^2 fs; the mid-point
    # increment dt (a0 + a1) / 2 has dt^2 N^2 fs / 2; a random walk K grows by K^2 dt per step
    N, K = _worst("accelerometer", "noise_density"), _worst("accelerometer", "random_walk")
    assert var_v == pytest.approx(dt ** 2 * N ** 2 * fs / 2, rel=1e-6)
    assert var_ba == pytest.approx(K ** 2 * dt, rel=1e-6)
    assert y["gyr_n"] == pytest.approx(_worst("gyroscope", "noise_density") * math.sqrt(fs), rel=1e-6)
    assert y["g_norm"] == pytest.approx(9.81)


def test_orbslam3_noise_is_what_its_preintegration_needs():
    r = _one("orbslam3", full_calibration())
    y = yaml.safe_load(r.files[""].split("\n", 1)[1])
    freq = y["IMU.Frequency"]
    dt = 1.0 / freq
    # UZ-SLAMLab/ORB_SLAM3 src/Tracking.cc (Tracking::newParameterLoader): sf = sqrt(mImuFreq);
    # mpImuCalib = new IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf); src/ImuTypes.cc (commit c85e0ea)
    # Calib::Set: Cov = diag(ng^2 x3, na^2 x3), CovWalk = diag(ngw^2 x3, naw^2 x3);
    # Preintegrated::IntegrateNewMeasurement: B.rowRange(3,6).colRange(3,6) = dR*dt,
    # C(0:9) = A C A^T + B Nga B^T, C(9:15) += NgaWalk (once per sample)
    sf = math.sqrt(freq)
    var_v = dt ** 2 * (y["IMU.NoiseAcc"] * sf) ** 2
    var_bg = (y["IMU.GyroWalk"] / sf) ** 2
    N, K = _worst("accelerometer", "noise_density"), _worst("gyroscope", "random_walk")
    assert var_v == pytest.approx(N ** 2 * dt, rel=1e-6)   # white noise of density N over dt
    assert var_bg == pytest.approx(K ** 2 * dt, rel=1e-6)  # a random walk of density K over dt
    assert [x for x in r.left_out if "scale and non-orthogonality" in x.term]
