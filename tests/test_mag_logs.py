"""A log's magnetometer beside its IMU: ROS ``sensor_msgs/MagneticField`` (ROS 1, ROS 2 sqlite3
and MCAP), PX4 ``sensor_mag``, ArduPilot ``MAG``.  Synthetic sessions with a known hard and soft
iron and a known rotation to the accelerometer go through the readers and ``accelcal mag`` /
``calibrate``, which must recover them; each unit is the one its consumer's source states."""

import json

import numpy as np
import pytest

from accelcal.cli import main
from accelcal.formats import read
from accelcal.formats.mag_logs import MAG_WARNING, place
from tests.mag_sessions import A_INV, B, DIP, R_TRUE, simulate_session

T0 = 1_700_000_000.0  # header stamps: Unix time
EVERY = 4  # magnetometer at 25 Hz beside a 100 Hz IMU


def _check_model(d):
    """The model maps raw µT onto the unit field in the accelerometer's axes: M A_INV = R_TRUE."""
    model = d["model"]
    M = model["strength"] * np.array(model["R"]) @ np.array(model["A"])
    assert np.allclose(model["b"], B, atol=0.3)
    assert np.abs(M @ A_INV - R_TRUE).max() < 0.01
    assert abs(d["alignment"]["dip_deg"] - DIP) < 0.3


def test_place_holds_each_sample_on_its_nearest_row_once():
    imu = np.arange(0, 10, 0.01)
    ms = np.arange(0.003, 10.5, 0.04)
    out, note = place(imu, ms, np.c_[ms, ms, ms], "m")
    k = np.isfinite(out[:, 0])
    assert k.sum() == 250 and np.abs(out[k, 0] - imu[k]).max() <= 0.0031
    assert "13 outside" in note
    fast = np.arange(0, 10, 0.004)  # faster than the IMU: the nearest of each row's samples, once
    out, note = place(imu, fast, np.c_[fast, fast, fast], "m")
    k = np.isfinite(out[:, 0])
    assert k.sum() == 1000 and np.abs(out[k, 0] - imu[k]).max() <= 0.002 + 1e-12 and "sharing a row" in note


def test_stamps_that_do_not_overlap_the_imus_are_another_time_base(tmp_path, capsys):
    """PX4's sensor_mag stamped 1000 s after the IMU (a clock of its own): not placed, one line."""
    p = _ulog(tmp_path, mag_shift_us=1_000_000_000)
    rec = read(p)
    assert rec.mag is None and rec.acc is not None
    warn = [n for n in rec.notes if n.startswith(MAG_WARNING)]
    assert len(warn) == 1 and "another time base" in warn[0] and "overlap in 0 s" in warn[0]


# ---- ROS -------------------------------------------------------------------------------------------------------

def _bag(tmp_path, kind, *, mags=None, latency=0.002, seed=0):
    pytest.importorskip("rosbags")
    from tests.ros_synthetic import write_imu_bag

    t, acc, m = simulate_session(seed)
    tm = t[::EVERY] + 0.003
    mags = {"/mag": (T0 + tm, m[::EVERY] * 1e-6, latency)} if mags is None else mags(T0 + tm, m[::EVERY] * 1e-6)
    name = {"ros1": "s.bag", "mcap": "s.mcap"}.get(kind, "s")
    return write_imu_bag(tmp_path / name, T0 + t, acc, np.zeros_like(acc), kind=kind, mag=mags)


@pytest.mark.parametrize("kind", ["ros1", "ros2-sqlite3", "mcap"])
def test_ros_magnetic_field_in_tesla_recovers_hard_and_soft_iron(tmp_path, kind, capsys):
    """sensor_msgs/msg/MagneticField.msg (ros2/common_interfaces): "Vector3 magnetic_field #
    x, y, and z components of the field vector in Tesla"; read as µT (x 1e6)."""
    bag = _bag(tmp_path, kind)
    rec = read(bag)
    k = np.isfinite(rec.mag[:, 0])
    assert rec.mag_unit == "uT" and k.sum() == len(rec.t[::EVERY])
    t, acc, m = simulate_session(0)
    assert np.allclose(rec.mag[k], m[::EVERY], atol=1e-6)  # tesla -> µT, on the nearest rows
    out = tmp_path / "m.json"
    assert main(["mag", str(bag), "--out", str(out)]) == 0
    _check_model(json.loads(out.read_text())["magnetometer"])


def test_ros_calibrate_keeps_the_accelerometer_and_calibrates_the_magnetometer(tmp_path, capsys):
    bag = _bag(tmp_path, "ros2-sqlite3")
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(bag), "--out", str(out), "--g", "9.81", "--no-gyro"]) == 0
    assert "warning: magnetometer" not in capsys.readouterr().err
    _check_model(json.loads(out.read_text())["magnetometer"])


def test_ros_several_mag_topics_need_mag_topic(tmp_path, capsys):
    bag = _bag(tmp_path, "ros2-sqlite3", mags=lambda tm, f: {"/mag": (tm, f, 0.002), "/mag2": (tm, f * 2, 0.002)})
    rec = read(bag)
    assert rec.mag is None and rec.acc is not None
    warn = [n for n in rec.notes if n.startswith(MAG_WARNING)]
    assert len(warn) == 1 and "--mag-topic" in warn[0] and "/mag2" in warn[0]
    assert np.isfinite(read(bag, mag_topic="/mag2").mag).any()
    out = tmp_path / "m.json"
    assert main(["mag", str(bag), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--mag-topic" in err[0] and not out.exists()
    assert main(["mag", str(bag), "--out", str(out), "--mag-topic", "/mag"]) == 0


def test_ros_mag_on_another_time_base_is_refused_or_warned(tmp_path, capsys):
    """The magnetometer stamped by another clock (here 5 s off, against the same record times)."""
    bag = _bag(tmp_path, "ros2-sqlite3", mags=lambda tm, f: {"/mag": (tm - 5.0, f, 5.002)})
    out = tmp_path / "m.json"
    assert main(["mag", str(bag), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "another time base" in err[0] and "--time-source log" in err[0] and not out.exists()
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(bag), "--out", str(cal), "--g", "9.81", "--no-gyro"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "warning: magnetometer:" in ln]
    assert len(lines) == 1 and "another time base" in lines[0]
    assert "magnetometer" not in json.loads(cal.read_text())
    # by the bag's record times both are on one clock: read and calibrated
    assert main(["mag", str(bag), "--out", str(out), "--time-source", "log"]) == 0


# ---- PX4 -------------------------------------------------------------------------------------------------------

def _ulog(tmp_path, *, mags=(0,), raw=True, vehicle=False, seed=0, spoil=None, mag_shift_us=0, old=False):
    pytest.importorskip("pyulog")
    from tests.log_fixtures import write_ulog

    t, acc, m = simulate_session(seed)
    us = (1_000_000 + t * 1e6).astype(np.int64)
    imu = {"timestamp": us + 300, "timestamp_sample": us, "device_id": np.full(len(t), 7, np.uint32)}
    topics = {("sensor_accel", 0): {**imu, "x": acc[:, 0].astype(np.float32), "y": acc[:, 1].astype(np.float32),
                                    "z": acc[:, 2].astype(np.float32)},
              ("sensor_gyro", 0): {**imu, "x": np.zeros(len(t), np.float32), "y": np.zeros(len(t), np.float32),
                                   "z": np.zeros(len(t), np.float32)}}
    ms = us[::EVERY] + 3000 + mag_shift_us
    gauss = (m[::EVERY] / 100.0).astype(np.float32)  # SensorMag.msg: x, y, z in gauss
    if spoil is not None:
        gauss = spoil(gauss)
    for i in mags if raw else ():
        topics[("sensor_mag", i)] = {"timestamp": ms + 200, "timestamp_sample": ms,
                                     "device_id": np.full(len(ms), 396825 + i, np.uint32),
                                     "x": gauss[:, 0] * (1 + i), "y": gauss[:, 1], "z": gauss[:, 2],
                                     "is_external": np.ones(len(ms), np.uint32),
                                     **({"x_raw": np.zeros(len(ms), np.uint32)} if old else {})}
    if vehicle:
        topics[("vehicle_magnetometer", 0)] = {"timestamp": ms, **{f"magnetometer_ga[{k}]": gauss[:, k]
                                                                    for k in range(3)}}
    return write_ulog(tmp_path / "s.ulg", topics, params={"CAL_MAG0_ID": 396825, "CAL_MAG0_XOFF": 0.12})


def test_px4_sensor_mag_in_gauss_recovers_hard_and_soft_iron(tmp_path, capsys):
    """PX4-Autopilot msg/SensorMag.msg: "float32 x # [Gauss] magnetic field in the FRD board
    frame X-axis"; read as µT (x 100), before calibration::Magnetometer::Correct."""
    p = _ulog(tmp_path)
    rec = read(p)
    k = np.isfinite(rec.mag[:, 0])
    t, acc, m = simulate_session(0)
    assert rec.mag_unit == "uT" and np.allclose(rec.mag[k], m[::EVERY], atol=1e-3)
    assert any("CAL_MAG0_XOFF=0.12" in n for n in rec.notes)
    out = tmp_path / "m.json"
    assert main(["mag", str(p), "--out", str(out)]) == 0
    _check_model(json.loads(out.read_text())["magnetometer"])
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(p), "--out", str(cal), "--g", "9.81", "--no-gyro"]) == 0
    _check_model(json.loads(cal.read_text())["magnetometer"])


def test_px4_several_compasses_and_calibrated_only_logs(tmp_path, capsys):
    p = _ulog(tmp_path, mags=(0, 1))
    rec = read(p)
    assert rec.mag is None and any(n.startswith(MAG_WARNING) and "--mag-instance" in n for n in rec.notes)
    assert np.nanmax(read(p, mag_instance=1).mag[:, 0]) > np.nanmax(read(p, mag_instance=0).mag[:, 0])
    (tmp_path / "old").mkdir()
    old = read(_ulog(tmp_path / "old", old=True))  # PX4 < 1.10: x, y, z calibrated by the driver
    assert old.mag is None and any(n.startswith(MAG_WARNING) and "x_raw" in n for n in old.notes)
    (tmp_path / "v").mkdir()
    q = _ulog(tmp_path / "v", raw=False, vehicle=True)
    out = tmp_path / "m.json"
    assert main(["mag", str(q), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "vehicle_magnetometer" in err[0] and "not the raw sensor_mag" in err[0]


# ---- ArduPilot -------------------------------------------------------------------------------------------------

DIA, ODI, SCALE = (1.02, 0.98, 1.01), (0.01, -0.02, 0.015), 1.05
OFS = np.array([-100, 200, -40])  # milligauss: an earlier calibration's COMPASS_OFS (added)


def _dataflash(tmp_path, *, scale=SCALE, mo=0, params=True, seed=0):
    pytest.importorskip("pymavlink")
    from tests.log_fixtures import write_dataflash

    t, acc, m = simulate_session(seed)
    us = (1_000_000 + t * 1e6).astype(np.int64)
    mat = np.array([[DIA[0], ODI[0], ODI[1]], [ODI[0], DIA[1], ODI[2]], [ODI[1], ODI[2], DIA[2]]])
    raw_mg = m[::EVERY] * 10.0  # µT -> milligauss
    logged = np.trunc((raw_mg + OFS) * scale @ mat.T + mo)  # correct_field, then (int16_t) in Write_Compass_instance
    rows = []
    for k, tu in enumerate(us[::EVERY] + 3000):
        row = (tu, 0, *logged[k], *OFS, mo, mo, mo, 1, tu)
        rows += [row, (tu + 2000, *row[1:])]  # logged twice: the same sample (same S) once
    p = {"COMPASS_SCALE": scale, **{f"COMPASS_DIA_{a}": v for a, v in zip("XYZ", DIA)},
         **{f"COMPASS_ODI_{a}": v for a, v in zip("XYZ", ODI)}} if params else {}
    return write_dataflash(tmp_path / "s.bin", us, acc, np.zeros_like(acc), mag=rows, params=p)


def test_ardupilot_mag_milligauss_with_its_correction_undone(tmp_path, capsys):
    """libraries/AP_Compass/LogStructure.h: MAG "QBhhhhhhhhhBI", units "s#GGGGGGGGG-s", multipliers
    "F-CCCCCCCCC-F" (G gauss x C 1e-3: milligauss); AP_Compass_Logging.cpp logs get_field(), the field
    after AP_Compass_Backend::correct_field (offsets added, scale, DIA/ODI matrix, motor offsets)."""
    p = _dataflash(tmp_path)
    rec = read(p)
    k = np.isfinite(rec.mag[:, 0])
    t, acc, m = simulate_session(0)
    assert rec.mag_unit == "uT" and k.sum() == len(m[::EVERY])  # each sample once, though logged twice
    assert np.abs(rec.mag[k] - m[::EVERY]).max() < 0.25  # whole milligauss: 0.1 µT, through mat^-1 / scale
    assert any("repeated samples" in n for n in rec.notes)
    out = tmp_path / "m.json"
    assert main(["mag", str(p), "--out", str(out)]) == 0
    _check_model(json.loads(out.read_text())["magnetometer"])


@pytest.mark.parametrize("case, says", [({"mo": 5}, "motor compensation"), ({"scale": 1.45}, "COMPASS_SCALE=1.45"),
                                        ({"params": False}, "no COMPASS_DIA_X")])
def test_ardupilot_mag_that_cannot_be_undone_is_refused(tmp_path, capsys, case, says):
    p = _dataflash(tmp_path, **case)
    out = tmp_path / "m.json"
    assert main(["mag", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0] and "--no-mag" not in err[0] and not out.exists()
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(p), "--out", str(cal), "--g", "9.81", "--no-gyro"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "warning: magnetometer:" in ln]
    assert len(lines) == 1 and says in lines[0] and "--no-mag" in lines[0]
    assert "magnetometer" not in json.loads(cal.read_text())


@pytest.mark.parametrize("spoil, says", [(lambda g: g * [1, 0, 1], "magnetometer y is constant"),
                                         (lambda g: np.minimum(g, [0.2, 9, 9]).astype(np.float32), "saturated")])
def test_px4_bad_magnetometer_columns(tmp_path, capsys, spoil, says):
    """A constant (zero) axis, a saturated axis: `mag` refuses in one line, `calibrate` keeps the
    accelerometer with one `warning: magnetometer:` line."""
    p = _ulog(tmp_path, spoil=spoil)
    out = tmp_path / "m.json"
    assert main(["mag", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0] and not out.exists()
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(p), "--out", str(cal), "--g", "9.81", "--no-gyro"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "warning: magnetometer:" in ln]
    assert len(lines) == 1 and says in lines[0] and "magnetometer" not in json.loads(cal.read_text())
