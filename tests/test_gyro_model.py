"""The gyro model and its exact conversions to and from IMU-TK's, imucal's and Kalibr's."""

import numpy as np
import pytest

from accelcal.errors import InputShapeError
from accelcal.gyro.model import GyroModel, frame_rotation, lq


def _random_model(seed=0, g_sens=True, raw_unit="rad/s"):
    rng = np.random.default_rng(seed)
    C = np.eye(3) + np.diag(0.03 * rng.standard_normal(3)) + 0.02 * rng.standard_normal((3, 3))
    G = 1e-3 * rng.standard_normal((3, 3)) if g_sens else None
    return GyroModel(C, 0.01 * rng.standard_normal(3), G, raw_unit)


def test_correct_inverts_measure():
    m = _random_model()
    rng = np.random.default_rng(1)
    w, f = rng.standard_normal((50, 3)), 9.8 * rng.standard_normal((50, 3))
    np.testing.assert_allclose(m.correct(m.measure(w, f), f), w, atol=1e-12)


def test_imutk_round_trip_and_layout():
    m = _random_model(g_sens=False)
    d = m.to_imutk()
    T = d["T"]
    np.testing.assert_allclose(np.diag(T), 1.0)
    # IMU-TK's CalibratedTriad_: T = [[1, -yz, zy], [xz, 1, -zx], [-xy, yx, 1]]
    built = np.array([[1, -d["mis_yz"], d["mis_zy"]], [d["mis_xz"], 1, -d["mis_zx"]], [-d["mis_xy"], d["mis_yx"], 1]])
    np.testing.assert_allclose(built, T, atol=1e-15)
    back = GyroModel.from_imutk(d["T"], d["K"], d["b"])
    np.testing.assert_allclose(back.C, m.C, atol=1e-15)
    raw = np.random.default_rng(2).standard_normal((10, 3))
    np.testing.assert_allclose(m.correct(raw), (T @ d["K"] @ (raw - d["b"]).T).T, atol=1e-14)


def test_imucal_round_trip_matches_imucal_itself():
    imucal = pytest.importorskip("imucal")
    m = _random_model(raw_unit="deg/s")
    d = m.to_imucal("deg/s")
    np.testing.assert_allclose(np.linalg.norm(d["R_g"], axis=1), 1.0)  # rows: unit sensing axes
    back = GyroModel.from_imucal(d["K_g"], d["R_g"], d["b_g"], d["K_ga"], out_unit="deg/s", raw_unit="deg/s")
    np.testing.assert_allclose(back.C, m.C, atol=1e-13)
    np.testing.assert_allclose(back.g_sensitivity, m.g_sensitivity)
    info = imucal.FerrarisCalibrationInfo(K_a=np.eye(3), R_a=np.eye(3), b_a=np.zeros(3), from_acc_unit="m/s^2",
                                          from_gyr_unit="deg/s", **d)
    rng = np.random.default_rng(3)
    raw, acc = 50 * rng.standard_normal((20, 3)), 9.8 * rng.standard_normal((20, 3))
    _, gyr = info.calibrate(acc, raw, "m/s^2", "deg/s")  # imucal's own apply, output deg/s
    np.testing.assert_allclose(np.deg2rad(gyr), m.correct(raw, acc), atol=1e-12)


def test_kalibr_round_trip():
    m = _random_model()
    d = m.to_kalibr()
    M, Q = d["M"], d["C_gyro_i"]
    np.testing.assert_allclose(np.triu(M, 1), 0.0, atol=1e-15)
    assert np.all(np.diag(M) > 0)
    np.testing.assert_allclose(Q @ Q.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(Q) == pytest.approx(1.0)
    w, f = np.random.default_rng(4).standard_normal((5, 3)), np.random.default_rng(5).standard_normal((5, 3))
    # Kalibr's sensor model (IccSensors.py l. 1049): y = M C_gyro_i w + A C_gyro_i a + b
    y = (M @ Q @ w.T).T + f @ (d["A"] @ Q).T + d["b"]
    np.testing.assert_allclose(m.measure(w, f), y, atol=1e-13)
    back = GyroModel.from_kalibr(M, Q, d["b"], d["A"])
    np.testing.assert_allclose(back.C, m.C, atol=1e-13)
    np.testing.assert_allclose(back.g_sensitivity, m.g_sensitivity, atol=1e-15)


def test_lq_and_frame_rotation():
    rng = np.random.default_rng(6)
    A = np.eye(3) + 0.05 * rng.standard_normal((3, 3))
    L, Q = lq(A)
    np.testing.assert_allclose(L @ Q, A, atol=1e-14)
    np.testing.assert_allclose(np.triu(L, 1), 0.0, atol=1e-14)
    # an upper-triangular sensing matrix (IMU-TK's accelerometer frame) becomes lower triangular in ours
    U = np.triu(np.eye(3) + 0.02 * rng.standard_normal((3, 3)))
    Qf = frame_rotation(U)
    np.testing.assert_allclose(np.triu(U @ Qf.T, 1), 0.0, atol=1e-14)


def test_dict_round_trip_and_bad_input():
    m = _random_model()
    assert GyroModel.from_dict(m.to_dict()) == m
    with pytest.raises(InputShapeError):
        GyroModel(np.zeros((3, 3)), np.zeros(3))
    with pytest.raises(InputShapeError):
        GyroModel(np.eye(3), np.zeros(3), raw_unit="rpm")
    with pytest.raises(InputShapeError):
        _random_model(g_sens=True).correct(np.zeros((2, 3)))  # g-sensitivity needs the specific force


def _without_g(m):
    return GyroModel(m.C, m.bias, None, m.raw_unit)


def test_exports_are_read_by_the_peers_as_the_same_calibration(tmp_path):
    from accelcal.export.imucal import imucal_json
    from accelcal.export.imutk import imutk_files

    rng = np.random.default_rng(7)
    M = np.tril(np.eye(3) + 0.02 * rng.standard_normal((3, 3)))  # accelcal's lower-triangular accelerometer
    ab = 0.1 * rng.standard_normal(3)
    g = _random_model(g_sens=False)
    raw_a, raw_g = 9.8 * rng.standard_normal((6, 3)), rng.standard_normal((6, 3))
    f = np.linalg.solve(M, (raw_a - ab).T).T
    files = imutk_files(M, ab, g)
    rows = [[float(v) for v in line.split()] for line in files["gyro"].splitlines() if line.strip()]
    T, K, b = np.array(rows[0:3]), np.array(rows[3:6]), np.array([r[0] for r in rows[6:9]])
    np.testing.assert_allclose((T @ K @ (raw_g - b).T).T, g.correct(raw_g), atol=1e-10)
    rows = [[float(v) for v in line.split()] for line in files["acc"].splitlines() if line.strip()]
    Ta, Ka, ba = np.array(rows[0:3]), np.array(rows[3:6]), np.array([r[0] for r in rows[6:9]])
    np.testing.assert_allclose((Ta @ Ka @ (raw_a - ba).T).T, f, atol=1e-10)
    imucal = pytest.importorskip("imucal")
    gs = _random_model(g_sens=True, raw_unit="deg/s")
    info = imucal.CalibrationInfo.from_json(imucal_json(M, ab, gs))
    acc_out, gyr_out = info.calibrate(raw_a, raw_g, "m/s^2", "deg/s")
    np.testing.assert_allclose(acc_out, f, atol=1e-10)
    np.testing.assert_allclose(np.deg2rad(gyr_out), gs.correct(raw_g, f), atol=1e-10)
    # IMU-TK has no g-sensitivity: its file holds the rest (the export says what G costs)
    assert imutk_files(M, ab, gs)["gyro"] == imutk_files(M, ab, _without_g(gs))["gyro"]
