"""`accelcal apply` on a log's IMU topic: the table (time as recorded, calibrated accelerometer,
gyroscope passed through), and nothing written when it fails."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import accelcal
from accelcal import cli
from accelcal.calibration import FullLLSCalibration
from accelcal.formats import px4, ros
from .ros_synthetic import write_imu_bag

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
BAG = DATA / "imutk_fork_sessions" / "data1" / "rosbag2_2023_08_11-21_37_35"
ULOG = DATA / "px4_ulog" / "sample_log_small.ulg"
STATIC = {"window": 0.5, "min_duration": 0.5, "trim": 0.1}


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    if not BAG.is_dir():
        pytest.skip("shared data not present")
    cal, _ = accelcal.calibrate_recording(ros.read(BAG), 9.80665, "full_lls", static=STATIC)
    path = tmp_path_factory.mktemp("cal") / "cal.json"
    cal.save(path)
    return path


def test_the_real_bag_calibrated_with_its_own_calibration(tmp_path, calibration):
    out = tmp_path / "calibrated.csv"
    code, err = _cli("apply", calibration, BAG, "--out", out)
    assert code == 0, err
    assert "gx_raw, gy_raw, gz_raw as recorded" in err and "gyro not corrected: the calibration has no gyroscope" in err
    table = pd.read_csv(out)
    rec = ros.read(BAG)
    assert len(table) == rec.n
    assert list(table.columns) == ["header_stamp_ns", "ax", "ay", "az", "gx_raw", "gy_raw", "gz_raw"]
    assert np.array_equal(table["header_stamp_ns"].to_numpy(), rec.time_column[1])
    expected = accelcal.load_calibration(calibration).apply(rec.acc)
    assert np.array_equal(table[["ax", "ay", "az"]].to_numpy(), expected)  # round-trip float repr
    assert np.array_equal(table[["gx_raw", "gy_raw", "gz_raw"]].to_numpy(), rec.gyro)
    # the calibration moves the static norm towards g
    norm = np.linalg.norm(expected, axis=1)
    assert abs(np.median(norm) - 9.80665) < abs(np.median(np.linalg.norm(rec.acc, axis=1)) - 9.80665)
    # the log's clock on request: its record times as the time column
    code, err = _cli("apply", calibration, BAG, "--out", tmp_path / "log.csv", "--time-source", "log")
    assert code == 0 and pd.read_csv(tmp_path / "log.csv").columns[0] == "log_time_ns"


def test_a_px4_log_is_applied_with_its_time_column(tmp_path, calibration):
    """sensor_combined is calibrated by the autopilot already: refused in one line, nothing written,
    unless --already-calibrated says the calibration was fitted to such values."""
    if not ULOG.is_file():
        pytest.skip("shared data not present")
    out = tmp_path / "px4.csv"
    code, err = _cli("apply", calibration, ULOG, "--out", out)
    assert code == 2 and len(err.splitlines()) == 1 and "sensor_combined" in err and "second time" in err, err
    assert not out.exists()
    code, err = _cli("apply", calibration, ULOG, "--out", out, "--already-calibrated")
    assert code == 0, err
    table = pd.read_csv(out)
    assert len(table) == px4.read(ULOG).n and table.columns[0] == "timestamp_us"
    assert list(table.columns[1:]) == ["ax", "ay", "az", "gx_raw", "gy_raw", "gz_raw"]
    assert np.all(np.diff(table["timestamp_us"]) > 0)


def test_a_failing_read_writes_nothing(tmp_path, calibration):
    bad = tmp_path / "bad.bag"
    bad.write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 50)
    out = tmp_path / "out.csv"
    code, err = _cli("apply", calibration, bad, "--out", out)
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith(f"accelcal: error: {bad}: cannot open")
    assert not out.exists()


def test_a_counts_calibration_on_a_log_in_m_s2_is_refused(tmp_path):
    rng = np.random.default_rng(2)
    cal = FullLLSCalibration(bias=np.zeros(3), M=400 * np.eye(3), g=9.80665, unit="counts", input_unit="counts")
    cal.save(tmp_path / "c.json")
    p = write_imu_bag(tmp_path / "b", 1.7e9 + np.arange(50) / 100, np.tile([0, 0, 9.8], (50, 1)) +
                      rng.normal(size=(50, 3)) * 0.01, np.zeros((50, 3)))
    code, err = _cli("apply", tmp_path / "c.json", p, "--out", tmp_path / "o.csv")
    assert code == 2 and "is read as m/s^2 but" in err and "was made from counts" in err
    assert not (tmp_path / "o.csv").exists()


def test_the_real_bag_with_an_imu_calibration_gives_calibrated_gyro(tmp_path):
    """calibrate on the bag (accelerometer and gyroscope), then apply on the same bag: the
    table carries the calibrated gx, gy, gz, the calibration's own correction of the recorded rates."""
    if not BAG.is_dir():
        pytest.skip("shared data not present")
    cal_path, out = tmp_path / "imu.json", tmp_path / "imu.csv"
    code, err = _cli("calibrate", BAG, "--out", cal_path)
    assert code == 0, err
    cal = accelcal.load_calibration(cal_path)
    assert cal.gyro is not None, err
    code, err = _cli("apply", cal_path, BAG, "--out", out)
    assert code == 0 and "gx, gy, gz in rad/s" in err, err
    table = pd.read_csv(out)
    rec = ros.read(BAG)
    assert list(table.columns) == ["header_stamp_ns", "ax", "ay", "az", "gx", "gy", "gz"]
    w = table[["gx", "gy", "gz"]].to_numpy()
    np.testing.assert_array_equal(w, cal.apply_gyro(rec.gyro, rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit))
    assert not np.allclose(w, rec.gyro)  # corrected, not passed through
    # the calibrated bag carries the same rates in angular_velocity
    code, err = _cli("apply", cal_path, BAG, "--out", tmp_path / "imu_bag")
    assert code == 0 and "linear_acceleration and angular_velocity replaced" in err, err
    back = ros.read(tmp_path / "imu_bag")
    np.testing.assert_array_equal(back.gyro, w)
    np.testing.assert_array_equal(back.acc, table[["ax", "ay", "az"]].to_numpy())


def test_calibrate_on_a_px4_flight_log_says_it_read_sensor_combined(tmp_path):
    """The one line names what was read (calibrated by the autopilot) and what to log instead; a
    bias-only method is never told to use a bias-only method."""
    if not ULOG.is_file():
        pytest.skip("shared data not present")
    for method in ("full-lls", "bias-lls"):
        code, err = _cli("calibrate", ULOG, "--out", tmp_path / "c.json", "--method", method)
        assert code == 2 and len(err.splitlines()) == 1, err
        assert "PX4 sensor_combined (already calibrated by the autopilot" in err and "raw sensor_accel" in err
        assert "bias-only method" not in err  # 1 orientation: no method fits, and bias-lls is bias-only
    assert not (tmp_path / "c.json").exists()
