"""`accelcal apply` writing a calibrated log of the kind it read: the real ROS 2 bag read back by rosbags
(every field of every message) and by accelcal; ROS 1, ROS 2 (sqlite3, MCAP) and bare MCAP logs with
other topics copied byte for byte; covariances from a noise report; out-of-order stamps; outputs whole
or not at all; PX4 sensor_combined refused; another device warned; logs that cannot be written back."""

from __future__ import annotations

import contextlib
import functools
import io
import json
from pathlib import Path

import numpy as np
import pytest

import accelcal
from accelcal import cli
from accelcal.calibration import FullLLSCalibration
from accelcal.errors import LogFormatError
from accelcal.formats import px4, ros, ros_write
from .ros_synthetic import write_imu_bag
from tests.log_fixtures import write_ulog

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
BAG = DATA / "imutk_fork_sessions" / "data1" / "rosbag2_2023_08_11-21_37_35"
ULOG = DATA / "px4_ulog" / "sample_log_small.ulg"
SUFFIX = {"ros1": ".bag", "mcap": ".mcap"}
N = 300
RNG = np.random.default_rng(11)
T = 1.7e9 + np.arange(N) / 200.0
ACC = np.array([0.1, -0.2, 9.8]) + 0.01 * RNG.standard_normal((N, 3))
GYRO = 0.001 * RNG.standard_normal((N, 3))
#: A calibration with every term of M and b non-zero.
CAL = FullLLSCalibration(bias=np.array([0.05, -0.03, 0.08]),
                         M=np.array([[1.01, 0.0, 0.0], [0.002, 0.99, 0.0], [-0.003, 0.001, 1.02]]), g=9.80665,
                         unit="m/s^2", input_unit="m/s^2")


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def _noise_json(path: Path, fs: float, acc_n=(1e-3, 2e-3, 3e-3), gyro_n=(1e-4, 2e-4, 3e-4)) -> Path:
    """The keys of an accelcal noise report that apply reads (checked against a real report below)."""
    def sensor(unit, n):
        return {"unit": unit, "axes": {a: {"noise_density": {"value": v}} for a, v in zip("xyz", n)}}
    path.write_text(json.dumps({"format": "accelcal-noise", "fs_hz": fs, "sensors": {
        "accelerometer": sensor("m/s^2", acc_n), "gyroscope": sensor("rad/s", gyro_n)}}))
    return path


def _messages(path) -> list:
    """(topic, record time, raw bytes) of every message, in the bag's order, read by rosbags alone."""
    path = Path(path)
    if path.suffix == ".bag":
        from rosbags.rosbag1 import Reader
    else:
        from rosbags.rosbag2 import Reader
    with Reader(path) as r:
        return [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in r.messages()]


@functools.cache
def _store(ros1: bool):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.LATEST)


def _deserialise(raw: bytes, ros1: bool):
    store = _store(ros1)
    return (store.deserialize_ros1 if ros1 else store.deserialize_cdr)(raw, "sensor_msgs/msg/Imu")


def _vec(v) -> np.ndarray:
    return np.array([v.x, v.y, v.z])


@pytest.mark.skipif(not BAG.is_dir(), reason="shared data not present")
def test_the_real_bag_calibrated_is_read_back_by_rosbags_and_by_accelcal(tmp_path):
    """Every message deserialised by rosbags: header, frame, orientation unchanged; acceleration and rate
    are the calibration's correction; covariances N^2 f_s; accelcal reads the same numbers back."""
    rec = ros.read(BAG)
    cal_path = tmp_path / "cal.json"
    cal = FullLLSCalibration(bias=CAL.bias, M=CAL.M, g=CAL.g, unit="m/s^2", input_unit="m/s^2")
    cal.save(cal_path)
    noise = _noise_json(tmp_path / "noise.json", rec.rate)
    out = tmp_path / "calibrated"
    code, err = _cli("apply", cal_path, BAG, "--out", out, "--noise", noise)
    assert code == 0, err
    assert f"9139 messages of /imu in {BAG} (ROS 2 bag)" in err and "linear_acceleration replaced" in err
    assert (out / "metadata.yaml").is_file() and (out / "calibrated.db3").is_file()
    before, after = _messages(BAG), _messages(out)
    assert len(before) == len(after) == 9139
    acc_var = np.array([1e-3, 2e-3, 3e-3]) ** 2 * rec.rate
    gyro_var = np.array([1e-4, 2e-4, 3e-4]) ** 2 * rec.rate
    raw_acc, new_acc = [], []
    for (topic, typ, t0, raw0), (topic1, typ1, t1, raw1) in zip(before, after):
        assert (topic, typ, t0) == (topic1, typ1, t1)
        m0, m1 = _deserialise(raw0, False), _deserialise(raw1, False)
        assert m0.header == m1.header and m0.orientation == m1.orientation
        assert np.array_equal(m0.orientation_covariance, m1.orientation_covariance)
        raw_acc.append(_vec(m0.linear_acceleration))
        new_acc.append(_vec(m1.linear_acceleration))
        assert np.array_equal(_vec(m1.angular_velocity), _vec(m0.angular_velocity))  # no gyro in the calibration
        assert np.array_equal(np.diag(m1.linear_acceleration_covariance.reshape(3, 3)), acc_var)
        assert np.array_equal(np.diag(m1.angular_velocity_covariance.reshape(3, 3)), gyro_var)
        assert np.count_nonzero(m1.linear_acceleration_covariance) == 3
    assert np.array_equal(np.array(new_acc), cal.apply(np.array(raw_acc)))
    back = ros.read(out)
    assert np.array_equal(back.acc, cal.apply(rec.acc)) and np.array_equal(back.gyro, rec.gyro)
    assert np.array_equal(back.time_column[1], rec.time_column[1])


@pytest.mark.parametrize("kind", ["ros1", "ros2-sqlite3", "ros2-mcap", "mcap"])
def test_every_kind_is_written_back_with_the_other_topics_verbatim(tmp_path, kind):
    src = write_imu_bag(tmp_path / ("in" + SUFFIX.get(kind, "")), T, ACC, GYRO, kind=kind,
                        extra_topics={"/chatter": "std_msgs/msg/String", "/imu_other": "sensor_msgs/msg/Imu"})
    cal_path = tmp_path / "cal.json"
    CAL.save(cal_path)
    out = tmp_path / ("out" + SUFFIX.get(kind, ""))
    code, err = _cli("apply", cal_path, src, "--out", out, "--topic", "/imu")
    assert code == 0, err
    assert "600 other messages of 2 other topics copied verbatim" in err
    before, after = _messages(src), _messages(out)
    assert [m[:3] for m in before] == [m[:3] for m in after]
    assert [m for m in before if m[0] != "/imu"] == [m for m in after if m[0] != "/imu"]
    changed = [(a[3], b[3]) for a, b in zip(before, after) if a[0] == "/imu"]
    # only the 24 bytes of linear_acceleration differ; the covariances are copied without --noise
    assert all(len(a) == len(b) and sum(x != y for x, y in zip(a, b)) <= 24 for a, b in changed)
    back = ros.read(out, topic="/imu")
    assert np.array_equal(back.acc, CAL.apply(ros.read(src, topic="/imu").acc))
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())  # no temporary left


def test_messages_recorded_out_of_stamp_order_get_their_own_values(tmp_path):
    t = T.copy()
    t[[100, 101]] = t[[101, 100]]
    src = write_imu_bag(tmp_path / "in.bag", t, ACC, GYRO, kind="ros1", latency_s=T - t + 0.002)
    CAL.save(tmp_path / "cal.json")
    code, err = _cli("apply", tmp_path / "cal.json", src, "--out", tmp_path / "out.bag")
    assert code == 0, err
    raws = [m[3] for m in _messages(tmp_path / "out.bag")]
    acc = np.array([_vec(_deserialise(r, True).linear_acceleration) for r in raws])
    assert np.array_equal(acc, CAL.apply(ACC))  # message i keeps its own sample, not the sorted one


def test_a_copy_that_fails_leaves_nothing(tmp_path):
    src = write_imu_bag(tmp_path / "in.mcap", T, ACC, GYRO, kind="mcap")
    got = ros.read_topic(src)
    wrong = got.header_ns.copy()
    wrong[-1] += 1
    with pytest.raises(LogFormatError, match="message 299 is stamped"):
        ros_write.write_calibrated(src, tmp_path / "out.mcap", topic="/imu", stamps_ns=wrong, acc=ACC)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.mcap"]


def test_outputs_that_do_not_fit_the_log_are_one_line_and_write_nothing(tmp_path):
    src = write_imu_bag(tmp_path / "in.bag", T, ACC, GYRO, kind="ros1")
    CAL.save(tmp_path / "cal.json")
    (tmp_path / "exists.bag").write_text("keep")
    cases = [(tmp_path / "x.mcap", "ROS 1 bag: its calibrated copy is a .bag file"),
             (tmp_path / "exists.bag", "exists; a calibrated log is written only to a new path"),
             (src, "exists")]
    for out, says in cases:
        code, err = _cli("apply", tmp_path / "cal.json", src, "--out", out)
        assert code == 2 and len(err.splitlines()) == 1 and says in err, err
    code, err = _cli("apply", tmp_path / "cal.json", src, "--out", tmp_path / "y.bag", "--rate", "100")
    assert code == 2 and "--rate does not apply" in err
    assert (tmp_path / "exists.bag").read_text() == "keep" and not (tmp_path / "x.mcap").exists()


def test_a_log_that_cannot_be_written_back_is_one_line_exit_2_nothing_written(tmp_path):
    CAL.save(tmp_path / "cal.json")
    ulg = write_ulog(tmp_path / "raw.ulg", _ulog_topics())
    for out in (tmp_path / "out.ulg", tmp_path / "out.bag"):
        code, err = _cli("apply", tmp_path / "cal.json", ulg, "--out", out)
        assert code == 2 and len(err.splitlines()) == 1, err
        assert "is a PX4 ULog, which accelcal cannot write back as a log" in err and "--out NAME.csv" in err
        assert not out.exists()
    table = tmp_path / "t.csv"
    table.write_text("t,ax,ay,az\n" + "".join(f"{i / 100},0,0,9.8\n" for i in range(20)))
    code, err = _cli("apply", tmp_path / "cal.json", table, "--out", tmp_path / "t.mcap")
    assert code == 2 and "not a ROS bag or MCAP file" in err and not (tmp_path / "t.mcap").exists()


def _ulog_topics(n=200, device=7):
    ts = np.arange(n, dtype=np.uint64) * 2500 + 1_000_000
    acc = {k: (ACC[:n, j]).astype(np.float32) for j, k in enumerate("xyz")}
    return {("sensor_accel", 0): {"timestamp": ts + 50, "timestamp_sample": ts,
                                  "device_id": np.full(n, device, np.uint32), **acc}}


def test_px4_sensor_combined_is_refused_and_another_device_warned(tmp_path):
    cal_path = tmp_path / "cal.json"
    FullLLSCalibration(bias=CAL.bias, M=CAL.M, g=CAL.g, unit="m/s^2", input_unit="m/s^2",
                       provenance={"device_id": "7"}).save(cal_path)
    same = write_ulog(tmp_path / "same.ulg", _ulog_topics(device=7))
    other = write_ulog(tmp_path / "other.ulg", _ulog_topics(device=9))
    assert px4.read(same).device_id == "7" and px4.read(same).precalibrated is None
    code, err = _cli("apply", cal_path, same, "--out", tmp_path / "same.csv")
    assert code == 0 and "warning" not in err, err
    code, err = _cli("apply", cal_path, other, "--out", tmp_path / "other.csv")
    assert code == 0 and "made on device 7, but" in err and "device 9" in err, err
    if ULOG.is_file():
        code, err = _cli("apply", cal_path, ULOG, "--out", tmp_path / "c.csv")
        assert code == 2 and "PX4 sensor_combined" in err and "--already-calibrated" in err
        assert not (tmp_path / "c.csv").exists()


def test_a_real_noise_report_fills_the_covariances(tmp_path):
    """The report of accelcal noise (not a hand-made one): its white-noise densities give the diagonal."""
    from accelcal.noise.report import analyse_noise
    from accelcal.recording import Recording

    rng = np.random.default_rng(3)
    n, fs = 40000, 200.0
    rec = Recording(np.arange(n) / fs, [0, 0, 9.8] + 0.02 * rng.standard_normal((n, 3)), None, "sim",
                    unit="m/s^2", gyro=0.001 * rng.standard_normal((n, 3)), gyro_unit="rad/s")
    report = analyse_noise(rec, n_boot=50)
    path = tmp_path / "noise.json"
    path.write_text(json.dumps(report.to_dict()))
    src = write_imu_bag(tmp_path / "in.bag", T, ACC, GYRO, kind="ros1")
    CAL.save(tmp_path / "cal.json")
    code, err = _cli("apply", tmp_path / "cal.json", src, "--out", tmp_path / "o.bag", "--noise", path)
    assert code == 0 and "covariances from" in err, err
    m = _deserialise(_messages(tmp_path / "o.bag")[0][3], True)
    want = [report.sensors["accelerometer"].terms[j]["white"].value ** 2 * 200.0 for j in range(3)]
    assert np.allclose(np.diag(m.linear_acceleration_covariance.reshape(3, 3)), want, rtol=1e-6)
    assert np.allclose(want, 0.02 ** 2, rtol=0.1)  # N^2 f_s is the per-sample variance drawn


def test_a_noise_report_in_counts_or_not_a_report_is_one_line(tmp_path):
    src = write_imu_bag(tmp_path / "in.bag", T, ACC, GYRO, kind="ros1")
    CAL.save(tmp_path / "cal.json")
    bad = _noise_json(tmp_path / "n.json", 200.0)
    d = json.loads(bad.read_text())
    d["sensors"]["accelerometer"]["unit"] = "counts"
    bad.write_text(json.dumps(d))
    code, err = _cli("apply", tmp_path / "cal.json", src, "--out", tmp_path / "o.bag", "--noise", bad)
    assert code == 2 and "noise is in counts" in err and not (tmp_path / "o.bag").exists()
    (tmp_path / "x.json").write_text("{}")
    code, err = _cli("apply", tmp_path / "cal.json", src, "--out", tmp_path / "o.bag", "--noise", tmp_path / "x.json")
    assert code == 2 and "not a noise report" in err


def test_the_real_bag_calibration_is_applied_as_calibrated(tmp_path):
    """apply's log carries exactly what its table carries (the same calibration, both outputs)."""
    if not BAG.is_dir():
        pytest.skip("shared data not present")
    CAL.save(tmp_path / "cal.json")
    assert _cli("apply", tmp_path / "cal.json", BAG, "--out", tmp_path / "t.csv")[0] == 0
    assert _cli("apply", tmp_path / "cal.json", BAG, "--out", tmp_path / "log")[0] == 0
    import pandas as pd

    table = pd.read_csv(tmp_path / "t.csv")
    assert np.array_equal(table[["ax", "ay", "az"]].to_numpy(), ros.read(tmp_path / "log").acc)
    assert accelcal.load_calibration(tmp_path / "cal.json").CAL_TYPE == CAL.CAL_TYPE


def test_writing_a_calibrated_bag_costs_at_most_a_few_copies(tmp_path):
    """Speed, as a ratio side by side: the calibrated copy against rosbags' verbatim copy of the same bag
    (1.5x measured on 20,000 messages; 4.5x fails a 3x slip without flaking under load)."""
    import time

    from rosbags.rosbag2 import Reader, StoragePlugin, Writer

    n = 4000
    bag = write_imu_bag(tmp_path / "in", 1.7e9 + np.arange(n) / 400, np.ones((n, 3)), np.zeros((n, 3)),
                        serialize="fast")
    got = ros.read_topic(bag)

    def copy(dst):
        with Reader(bag) as r:
            w = Writer(dst, version=9, storage_plugin=StoragePlugin.SQLITE3)
            w.open()
            cmap = {c.id: ros_write._add_connection(w, c, False) for c in r.connections}
            for c, t, raw in r.messages():
                w.write(cmap[c.id], t, raw)
            w.close()

    ratios = []
    for k in range(3):
        t0 = time.perf_counter()
        copy(tmp_path / f"c{k}")
        t1 = time.perf_counter()
        ros_write.write_calibrated(bag, tmp_path / f"a{k}", topic="/imu", stamps_ns=got.header_ns,
                                   acc=got.recording.acc * 1.01, gyro=got.recording.gyro, acc_cov=[1, 2, 3],
                                   gyro_cov=[1, 2, 3])
        ratios.append((time.perf_counter() - t1) / (t1 - t0))
    assert np.median(ratios[1:]) < 4.5, ratios  # the first pair warms the caches
