"""The log formats: the real ROS 2 bag against its text export (read, and calibrated through the CLI),
ROS 1 / ROS 2 / MCAP files written by rosbags' own writers, the PX4 sample logs, and written ULog and
DataFlash files; topic choice, time sources, the log options through the registry, a missing extra,
and every refusal in one line."""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import accelcal
from accelcal import cli
from accelcal.errors import LogFormatError, RecordingError, TopicError
from accelcal.formats import FORMATS, ardupilot, detect_format, px4, read, ros
from .ros_synthetic import write_imu_bag
from tests.log_fixtures import write_dataflash, write_ulog

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
SESSION = DATA / "imutk_fork_sessions" / "data1"
BAG = SESSION / "rosbag2_2023_08_11-21_37_35"
PX4 = DATA / "px4_ulog"
needs_data = pytest.mark.skipif(not BAG.is_dir(), reason="shared data not present")

N = 400
RNG = np.random.default_rng(7)
T = 1.7e9 + np.arange(N) / 200.0
ACC = np.array([0.1, -0.2, 9.8]) + 0.01 * RNG.standard_normal((N, 3))
GYRO = 0.001 * RNG.standard_normal((N, 3))
SUFFIX = {"ros1": ".bag", "mcap": ".mcap"}


def _bag(tmp_path, kind, name="b", **kw):
    return write_imu_bag(tmp_path / (name + SUFFIX.get(kind, "")), kw.pop("t", T), kw.pop("acc", ACC),
                         kw.pop("gyro", GYRO), kind=kind, **kw)


# --------------------------------------------------------------------------- the real ROS 2 bag


@needs_data
def test_real_bag_equals_its_text_export_to_rounding():
    rec = ros.read(BAG)
    acc = np.loadtxt(SESSION / "acc_data.txt")
    gyro = np.loadtxt(SESSION / "gyro_data.txt")
    assert rec.n == len(acc) == 9139 and rec.unit == "m/s^2" and rec.gyro_unit == "rad/s"
    # the export writes 8 significant digits (%.7e): half a unit of its last digit
    for mine, text in ((rec.acc, acc[:, 1:]), (rec.gyro, gyro[:, 1:])):
        assert np.all(np.abs(mine - text) <= 0.5e-7 * np.abs(mine) + 1e-300)
    stamps = (rec.time_column[1] - rec.time_column[1][0]) * 1e-9
    assert np.max(np.abs(stamps - acc[:, 0])) < 1e-6  # header stamps minus the first, 8 digits
    assert rec.time_column[0] == "header_stamp_ns"
    # both are timed by the clock fitted to those stamps (accelcal.formats.clock)
    assert np.max(np.abs(rec.t - read(SESSION / "acc_data.txt").t)) < 1e-6


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


#: Settings for the still phases of the data1 session (about 1 s each), given explicitly: the
#: comparison is at fixed settings, whatever the defaults of the rest detection.
STILL = ("--window", "0.5", "--min-duration", "0.5", "--trim", "0.1")


@needs_data
def test_real_bag_calibration_equals_the_text_export_calibration(tmp_path):
    """`accelcal calibrate` on the bag folder and on the session's text export, same settings."""
    out = {}
    for name, path in (("bag", BAG), ("text", SESSION / "acc_data.txt")):
        code, err = _cli("calibrate", path, "--out", tmp_path / f"{name}.json", *STILL)
        assert code == 0, err
        out[name] = accelcal.load_calibration(tmp_path / f"{name}.json")
    bag, text = out["bag"], out["text"]
    assert bag.n_poses == text.n_poses >= 10
    # to the rounding of the export (8 significant digits): far below the standard errors (~1e-3 m/s^2)
    assert np.max(np.abs(bag.bias - text.bias)) < 1e-7
    assert np.max(np.abs(bag.M - text.M)) < 1e-8
    assert np.max(np.abs(bag.bias - text.bias)) < 1e-3 * np.min(bag.standard_errors_noise["bias"])
    prov = json.loads((tmp_path / "bag.json").read_text())
    assert prov["recording"] == str(BAG) and len(prov["recording_sha256"]) == 64  # a folder has a digest too


@needs_data
def test_numpy_decoding_equals_rosbags_deserialisation_on_every_message():
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.LATEST)
    with Reader(BAG) as r:
        msgs = [store.deserialize_cdr(raw, c.msgtype) for c, _, raw in r.messages()]
    rec = ros.read(BAG)
    ref = np.array([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z,
                     m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in msgs])
    stamps = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in msgs])
    assert np.array_equal(np.hstack([rec.acc, rec.gyro]), ref)
    assert np.array_equal(rec.time_column[1], stamps)


@needs_data
def test_real_bag_is_sniffed_from_the_folder_its_metadata_and_its_db3():
    db3 = next(BAG.glob("*.db3"))
    for p in (BAG, BAG / "metadata.yaml", db3):
        assert detect_format(p) == "ros"
    assert np.array_equal(ros.read(db3).acc, ros.read(BAG / "metadata.yaml").acc)


# --------------------------------------------------------------------------- written bags


@pytest.mark.parametrize("kind", ["ros1", "ros2-sqlite3", "ros2-mcap", "mcap"])
def test_bags_written_by_rosbags_read_back_exactly(tmp_path, kind):
    p = _bag(tmp_path, kind, extra_topics={"/chatter": "std_msgs/msg/String"})
    assert detect_format(p) == "ros"
    rec = ros.read(p)
    assert np.array_equal(rec.acc, ACC) and np.array_equal(rec.gyro, GYRO)
    assert np.array_equal(rec.time_column[1], np.round(T * 1e9).astype(np.int64))
    assert rec.notes[0].startswith("ROS 1 bag" if kind == "ros1" else "MCAP file" if kind == "mcap" else "ROS 2 bag")


def test_frame_ids_of_varying_length_are_decoded_one_by_one(tmp_path):
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    from .ros_synthetic import _message

    store = get_typestore(Stores.LATEST)
    p = tmp_path / "var"
    with Writer(p, version=9) as w:
        c = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for i in range(N):
            msg = _message(store, int(T[i] * 1e9), ACC[i], GYRO[i], "f" * (i % 11))
            w.write(c, int(T[i] * 1e9) + 1000, store.serialize_cdr(msg, "sensor_msgs/msg/Imu"))
    rec = ros.read(p)
    assert np.array_equal(rec.acc, ACC) and np.array_equal(rec.gyro, GYRO)


def test_big_endian_cdr_is_read(tmp_path):
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    from .ros_synthetic import _message

    store = get_typestore(Stores.LATEST)
    p = tmp_path / "be"
    with Writer(p, version=9) as w:
        c = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for i in range(N):
            raw = store.serialize_cdr(_message(store, int(T[i] * 1e9), ACC[i], GYRO[i], "imu"), "sensor_msgs/msg/Imu",
                                      little_endian=False)
            w.write(c, int(T[i] * 1e9), raw)
    assert np.array_equal(ros.read(p).acc, ACC)


def test_several_imu_topics_are_listed_in_one_line_and_chosen_with_topic(tmp_path):
    p = _bag(tmp_path, "ros2-mcap", extra_topics={"/imu_b": "sensor_msgs/msg/Imu"})
    with pytest.raises(TopicError, match=r"2 sensor_msgs/Imu topics: /imu \(400 messages\), /imu_b .*--topic") as e:
        ros.read(p)
    assert "\n" not in str(e.value)
    assert np.array_equal(ros.read(p, topic="/imu").acc, ACC)
    assert np.all(ros.read(p, topic="/imu_b", time_source="log").acc == 0)


def test_a_bag_without_imu_a_topic_of_another_type_and_an_unknown_topic_are_refused(tmp_path):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    p = tmp_path / "noimu.bag"
    with Writer(p) as w:
        c = w.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        w.write(c, 1, store.serialize_ros1(store.types["std_msgs/msg/String"](data="x"), "std_msgs/msg/String"))
    with pytest.raises(TopicError, match=r"no sensor_msgs/Imu topic in this log \(topics: /chatter"):
        ros.read(p)
    with pytest.raises(TopicError, match=r"/chatter is std_msgs/msg/String, .*not a sensor_msgs/Imu topic"):
        ros.read(p, topic="/chatter")
    with pytest.raises(TopicError, match="/nope is not in this log"):
        ros.read(p, topic="/nope")


def test_an_empty_imu_topic_is_refused(tmp_path):
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    p = tmp_path / "empty"
    with Writer(p, version=9) as w:
        w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=get_typestore(Stores.LATEST))
    with pytest.raises(RecordingError, match="topic /imu: no messages; need at least 10 .*choose another"):
        read(p, format="ros")  # the check of every recording, with the topic the reader names


def test_log_time_on_request_and_a_warning_when_the_clocks_disagree(tmp_path):
    jitter = 0.002 + 0.03 * np.arange(N) / N  # the two clocks drift 30 ms apart (no message reordered)
    p = _bag(tmp_path, "ros2-sqlite3", latency_s=jitter)
    rec = ros.read(p)
    assert any(n.startswith("warning: the header stamps and the bag record times disagree") for n in rec.notes)
    log = ros.read(p, time_source="log")
    assert log.time_column[0] == "log_time_ns"
    assert np.allclose(log.t - rec.t, jitter - jitter[0], atol=2e-9)
    calm = ros.read(_bag(tmp_path, "ros2-sqlite3", name="calm"))
    assert not any("disagree" in n for n in calm.notes)


def test_header_stamps_out_of_record_order_are_sorted_repeated_or_zero_ones_point_to_log_time(tmp_path):
    t = T.copy()
    t[[100, 101]] = t[[101, 100]]  # recorded in the other order
    rec = ros.read(_bag(tmp_path, "ros1", t=t, latency_s=T - t + 0.002))  # record times in the original order
    assert np.array_equal(rec.acc[[100, 101]], ACC[[101, 100]]) and np.all(np.diff(rec.t) > 0)
    assert "1 message(s) were recorded out of header-stamp order: sorted by header stamp" in rec.notes
    t[100] = t[98]
    # the bag records in record-time order: its message 99 repeats message 98's stamp
    with pytest.raises(RecordingError, match=r"topic /imu: time \(header.stamp\) repeats at message 99 .*--time-source log"):
        read(_bag(tmp_path, "ros1", name="rep", t=t), format="ros")
    assert ros.read(_bag(tmp_path, "ros1", name="b2", t=t, latency_s=T - t + 0.002), time_source="log").n == N
    with pytest.raises(LogFormatError, match="every header stamp is zero.*--time-source log"):
        ros.read(_bag(tmp_path, "mcap", name="zero", t=np.zeros(N), latency_s=T))


def test_a_truncated_bag_is_one_line(tmp_path):
    p = _bag(tmp_path, "ros1")
    data = p.read_bytes()
    for cut in (len(data) // 3, len(data) - 100, 20):
        q = tmp_path / f"cut{cut}.bag"
        q.write_bytes(data[:cut])
        with pytest.raises(LogFormatError) as e:
            ros.read(q)
        assert "\n" not in str(e.value) and str(q) in str(e.value)


def test_progress_is_reported_to_a_callback(tmp_path):
    seen = []
    ros.read(_bag(tmp_path, "ros2-mcap", t=1.7e9 + np.arange(3 * ros.CHUNK) / 400, acc=np.ones((3 * ros.CHUNK, 3)),
                  gyro=np.zeros((3 * ros.CHUNK, 3)), serialize="fast"), progress=lambda d, n: seen.append((d, n)))
    assert seen == [(ros.CHUNK * k, 3 * ros.CHUNK) for k in (1, 2, 3)]


# --------------------------------------------------------------------------- PX4


@pytest.mark.parametrize("name, n", [("sample.ulg", 17070), ("sample_log_small.ulg", 1298)])
def test_px4_sample_logs_read_sensor_combined_and_say_it_is_calibrated(name, n):
    p = PX4 / name
    if not p.is_file():
        pytest.skip("shared data not present")
    assert detect_format(p) == "px4"
    rec = px4.read(p)
    assert rec.n == n and rec.gyro.shape == (n, 3)
    assert "already calibrated by the autopilot" in rec.notes[0]
    assert 9.0 < np.median(np.linalg.norm(rec.acc, axis=1)) < 10.6  # a flight: gravity plus manoeuvres


def test_px4_sample_log_with_too_few_raw_samples_says_why_it_reads_sensor_combined():
    p = PX4 / "sample_log_small.ulg"
    if not p.is_file():
        pytest.skip("shared data not present")
    assert any("sensor_accel is logged with only 6 samples" in n for n in px4.read(p).notes)
    with pytest.raises(TopicError, match=r"no sensor_accel with at least 10 samples .*--topic sensor_combined"):
        px4.read(p, topic="sensor_accel")


def _ulog_topics(n=300, instances=(0,), gyro_offset_us=200):
    ts = np.arange(n, dtype=np.uint64) * 1000 + 1_000_000
    topics = {}
    for i in instances:
        topics[("sensor_accel", i)] = {"timestamp": ts + 50, "timestamp_sample": ts, "device_id": np.full(n, 7 + i,
                                       np.uint32), **{k: (ACC[:n, j] + i).astype(np.float32) for j, k in
                                                      enumerate("xyz")}, "temperature": np.full(n, 30, np.float32)}
        gt = ts + gyro_offset_us
        lin = (np.arange(n) * 1e-3)[:, None] * np.array([1.0, -2.0, 0.5])  # linear: interpolation is exact
        topics[("sensor_gyro", i)] = {"timestamp": gt + 10, "timestamp_sample": gt, "device_id": np.full(n, 100 + i,
                                      np.uint32), **{k: lin[:, j].astype(np.float32) for j, k in enumerate("xyz")}}
    return topics


def test_px4_raw_sensor_accel_is_preferred_and_the_gyro_interpolated(tmp_path):
    p = write_ulog(tmp_path / "raw.ulg", _ulog_topics(), params={"CAL_ACC0_ID": 7, "CAL_ACC0_XOFF": 0.25})
    rec = px4.read(p)
    assert np.array_equal(rec.acc, ACC[:300].astype(np.float32).astype(float))
    assert np.allclose(rec.temp, 30.0) and rec.time_column[0] == "timestamp_sample_us"
    lin = np.arange(300) * 1e-3 - 0.2e-3  # the gyro sampled 200 us after the accelerometer
    assert np.allclose(rec.gyro[1:, 0], lin[1:], atol=1e-6)
    assert "before the autopilot's calibration" in rec.notes[0]
    assert any("CAL_ACC0_XOFF=0.25" in n for n in rec.notes)
    assert px4.read(p, time_source="log").time_column[0] == "timestamp_us"


def test_px4_several_instances_are_listed_and_chosen(tmp_path):
    p = write_ulog(tmp_path / "multi.ulg", _ulog_topics(instances=(0, 1)))
    with pytest.raises(TopicError, match=r"2 sensor_accel instances: 0 \(300 samples at 1000 Hz\), 1 .*--instance"):
        px4.read(p)
    assert np.allclose(px4.read(p, instance=1).acc, ACC[:300].astype(np.float32) + 1, atol=1e-6)
    with pytest.raises(TopicError, match="5 is not in this log"):
        px4.read(p, instance=5)


def test_px4_truncated_and_foreign_files_are_one_line(tmp_path):
    p = write_ulog(tmp_path / "raw.ulg", _ulog_topics())
    data = p.read_bytes()
    (tmp_path / "head.ulg").write_bytes(data[:10])
    with pytest.raises(LogFormatError, match="not a readable ULog file"):
        px4.read(tmp_path / "head.ulg")
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: len(data) // 2])  # cut in the middle of a data message: what is before is read
    assert 100 < px4.read(cut).n < 300


# --------------------------------------------------------------------------- ArduPilot


def test_dataflash_imu_instances(tmp_path):
    t_us = 10_000_000 + np.arange(300) * 2500
    p = write_dataflash(tmp_path / "a.bin", t_us, ACC[:300], GYRO[:300], instances=(0, 1))
    assert detect_format(p) == "ardupilot"
    with pytest.raises(TopicError, match=r"2 IMU instances: 0 \(300 samples\), 1 \(300 samples\); .*--instance"):
        ardupilot.read(p)
    rec = ardupilot.read(p, instance=1)
    assert np.array_equal(rec.acc, ACC[:300].astype(np.float32).astype(float)) and rec.rate == pytest.approx(400)
    assert "after ArduPilot's own calibration" in rec.notes[0]
    old = write_dataflash(tmp_path / "old.bin", t_us, ACC[:300], GYRO[:300], names=("IMU", "IMU2"))
    with pytest.raises(TopicError, match="2 DataFlash IMU messages"):
        ardupilot.read(old)
    assert ardupilot.read(old, topic="IMU2").n == 300


def test_an_fmt_message_declaring_a_too_short_message_is_one_line_not_a_hang(tmp_path):
    """pymavlink advances by an FMT's declared length minus 3: a length below 3 made it loop
    forever on a damaged log the reader fuzz found; the reader refuses it before pymavlink."""
    t_us = 10_000_000 + np.arange(300) * 2500
    data = bytearray(write_dataflash(tmp_path / "a.bin", t_us, ACC[:300], GYRO[:300]).read_bytes())
    data[4] = 0  # the first FMT message (FMT's own) now declares a 0-byte message
    bad = tmp_path / "bad.bin"
    bad.write_bytes(bytes(data))
    with pytest.raises(LogFormatError, match="FMT message at byte 0 declares a message shorter"):
        ardupilot.read(bad)


# --------------------------------------------------------------------------- extras and registry data


@pytest.mark.parametrize("fmt, module", [("ros", "rosbags"), ("px4", "pyulog"), ("ardupilot", "pymavlink")])
def test_a_missing_extra_is_one_line_naming_the_pip_install_and_exit_2(tmp_path, fmt, module):
    """The extra's module hidden (None in sys.modules: its import fails and find_spec finds nothing):
    `accelcal calibrate` on a log of that format names the extra, exits 2 and writes nothing."""
    log = {"ros": lambda p: _bag(tmp_path, "ros1", name="x"), "px4": lambda p: write_ulog(p, _ulog_topics()),
           "ardupilot": lambda p: write_dataflash(p, 10**6 + np.arange(N) * 2500, ACC, GYRO)}[fmt](tmp_path / "x")
    out = tmp_path / "cal.json"
    code = (f"import sys\nsys.modules[{module!r}] = None\nfrom accelcal.cli import main\n"
            f"sys.exit(main(['calibrate', {str(log)!r}, '--out', {str(out)!r}]))\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.splitlines() == [f"accelcal: error: {log}: reading {fmt} files needs {module}, not installed: "
                                       f"pip install accelcal[{FORMATS[fmt].extra}]"]
    assert not out.exists()


def test_sniffers_claim_only_their_own_files(tmp_path):
    bag = _bag(tmp_path, "ros1")
    text = tmp_path / "t.csv"
    text.write_text("t,ax,ay,az\n0,0,0,9.8\n")
    assert detect_format(text) == "csv"
    logs = [f for f in FORMATS.values() if not f.text]
    assert [f.name for f in logs if f.load_sniff()(bag, bag.read_bytes()[:65536])] == ["ros"]


def test_log_options_go_through_the_registry(tmp_path):
    """read(..., topic, instance, time_source): taken by the formats that declare them, refused in one
    line by the others."""
    p = _bag(tmp_path, "ros2-mcap", extra_topics={"/imu_b": "sensor_msgs/msg/Imu"})
    assert np.array_equal(read(p, topic="/imu").acc, ACC)
    assert read(p, topic="/imu", time_source="log").time_column[0] == "log_time_ns"
    with pytest.raises(RecordingError, match=r"--instance applies to the px4 or ardupilot formats, not to ros"):
        read(p, topic="/imu", instance=1)
    table = tmp_path / "t.csv"
    table.write_text("t,ax,ay,az\n" + "".join(f"{i / 100},0,0,9.8\n" for i in range(20)))
    for kw, flag in (({"topic": "/imu"}, "--topic"), ({"time_source": "log"}, "--time-source")):
        with pytest.raises(RecordingError, match=f"{flag} applies to the ros, px4 or ardupilot formats, not to csv"):
            read(table, **kw)
    with pytest.raises(RecordingError, match="--time-source must be header or log, got 'gps'"):
        read(p, time_source="gps")


def test_time_stamps_that_are_no_time_are_one_line(tmp_path):
    """A damaged stamp beyond 2^53 us would wrap silently in integer nanoseconds (found by the log fuzzer)."""
    t_us = 10_000_000 + np.arange(300) * 2500
    t_us[-1] = 2**60
    p = write_dataflash(tmp_path / "a.bin", t_us, ACC[:300], GYRO[:300])
    with pytest.raises(LogFormatError, match=r"IMU instance 0: TimeUS: time stamp .* at message 299 is not a time"):
        ardupilot.read(p)
    topics = _ulog_topics()
    topics[("sensor_accel", 0)]["timestamp_sample"] = topics[("sensor_accel", 0)]["timestamp_sample"].copy()
    topics[("sensor_accel", 0)]["timestamp_sample"][5] = 2**63 + 7
    with pytest.raises(LogFormatError, match=r"sensor_accel instance 0: timestamp_sample: time stamp .* at message 5"):
        px4.read(write_ulog(tmp_path / "a.ulg", topics))
