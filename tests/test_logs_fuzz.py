"""Property-based fuzzing of the log formats of the registry: a damaged log gives a valid Recording
or one RecordingError line, never another exception.

Inputs: small valid logs of every kind (ROS 1 bag, ROS 2 bag folder with sqlite3 storage,
its bare .db3, MCAP, ULog, DataFlash; written by rosbags' writers and the test writers)
damaged by truncation, bit flips, overwritten and deleted byte spans and inserted bytes, read
through :func:`accelcal.formats.read` with the format named (the registry's path: its extra
check, the reader, the options).  tests/test_reader_fuzz.py also damages each log format's
sample file (tests/format_samples.py) with the text formats' fuzzer, named and detected.
The number of examples is ``ACCELCAL_FUZZ_EXAMPLES`` (default 250); the total tried is
printed (``pytest -s``).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.errors import RecordingError
from accelcal.formats import read
from .ros_synthetic import write_imu_bag
from accelcal.recording import MIN_ROWS
from tests.log_fixtures import write_dataflash, write_ulog

N = int(os.environ.get("ACCELCAL_FUZZ_EXAMPLES", "250"))
COUNT = {"tried": 0, "read": 0, "refused": 0}
KINDS_TRIED: set = set()
KINDS = ("ros1", "ros2-folder", "db3", "mcap", "ulog", "dataflash")


@pytest.fixture(scope="module")
def originals():
    """One small valid log of each kind, as bytes (folders: the storage file's bytes and the folder)."""
    tmp = Path(tempfile.mkdtemp())
    rng = np.random.default_rng(3)
    n = 60
    t = 1.7e9 + np.arange(n) / 100
    acc, gyro = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    out = {"ros1": write_imu_bag(tmp / "a.bag", t, acc, gyro, kind="ros1").read_bytes(),
           "mcap": write_imu_bag(tmp / "a.mcap", t, acc, gyro, kind="mcap").read_bytes()}
    folder = write_imu_bag(tmp / "f", t, acc, gyro, kind="ros2-sqlite3")
    out["ros2-folder"] = out["db3"] = next(folder.glob("*.db3")).read_bytes()
    out["metadata"] = (folder / "metadata.yaml").read_bytes()
    ts = np.arange(n, dtype=np.uint64) * 1000 + 10**6
    topics = {("sensor_accel", 0): {"timestamp": ts, "timestamp_sample": ts, "device_id": np.full(n, 1, np.uint32),
                                    **{k: acc[:, j].astype(np.float32) for j, k in enumerate("xyz")}},
              ("sensor_gyro", 0): {"timestamp": ts, "timestamp_sample": ts, "device_id": np.full(n, 2, np.uint32),
                                   **{k: gyro[:, j].astype(np.float32) for j, k in enumerate("xyz")}}}
    out["ulog"] = write_ulog(tmp / "a.ulg", topics).read_bytes()
    out["dataflash"] = write_dataflash(tmp / "a.bin", 10**6 + np.arange(n) * 2500, acc, gyro).read_bytes()
    yield out
    shutil.rmtree(tmp)


@st.composite
def damage(draw, size: int):
    ops = []
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["truncate", "flip", "overwrite", "delete", "insert"]))
        at = draw(st.integers(0, max(size - 1, 0)))
        ops.append((op, at, draw(st.integers(1, 64)), draw(st.binary(min_size=1, max_size=32))))
    return ops


def _apply(data: bytes, ops) -> bytes:
    b = bytearray(data)
    for op, at, k, junk in ops:
        at = min(at, max(len(b) - 1, 0))
        if op == "truncate":
            del b[at:]
        elif op == "flip" and b:
            b[at] ^= 1 << (k % 8)
        elif op == "overwrite":
            b[at:at + len(junk)] = junk
        elif op == "delete":
            del b[at:at + k]
        else:
            b[at:at] = junk
    return bytes(b)


def _write(tmp: Path, kind: str, data: bytes, originals) -> Path:
    if kind == "ros2-folder":
        d = tmp / "bag"
        d.mkdir()
        (d / "metadata.yaml").write_bytes(originals["metadata"])
        (d / "f_0.db3").write_bytes(data)
        return d
    name = {"ros1": "x.bag", "db3": "x.db3", "mcap": "x.mcap", "ulog": "x.ulg", "dataflash": "x.bin"}[kind]
    (tmp / name).write_bytes(data)
    return tmp / name


def _check(rec) -> None:
    assert rec.n >= MIN_ROWS and rec.acc.shape == (rec.n, 3) and np.all(np.isfinite(rec.acc))
    assert np.all(np.diff(rec.t) > 0) and np.all(np.isfinite(rec.t))
    assert rec.gyro is None or (rec.gyro.shape == (rec.n, 3) and np.all(np.isfinite(rec.gyro)))


@settings(max_examples=N, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                                                 HealthCheck.function_scoped_fixture])
@given(st.sampled_from(KINDS), st.data())
def test_a_damaged_log_is_read_or_refused_in_one_line(originals, kind, data):
    damaged = _apply(originals[kind], data.draw(damage(len(originals[kind]))))
    KINDS_TRIED.add(kind)
    COUNT["tried"] += 1  # after the draw: hypothesis abandons examples whose draw overruns
    fmt = {"ulog": "px4", "dataflash": "ardupilot"}.get(kind, "ros")
    with tempfile.TemporaryDirectory() as tmp:
        path = _write(Path(tmp), kind, damaged, originals)
        try:
            rec = read(path, format=fmt)
        except RecordingError as e:
            assert str(e) and "\n" not in str(e)
            COUNT["refused"] += 1
        else:
            _check(rec)
            COUNT["read"] += 1


def test_report_count():
    """How many damaged logs were tried (`pytest -s` prints it): each read or refused, every
    kind of log among them, and both outcomes (a damage that every reader refuses at its
    header would exercise nothing past it).  Needs the property above in the same session."""
    print(f"\nlog fuzz: {COUNT['tried']} damaged logs ({COUNT['read']} read, {COUNT['refused']} refused)")
    if not COUNT["tried"]:
        pytest.skip("the property did not run in this session")
    assert COUNT["read"] + COUNT["refused"] == COUNT["tried"]
    if COUNT["tried"] >= 10 * len(KINDS):
        assert set(KINDS_TRIED) == set(KINDS), f"kinds never tried: {set(KINDS) - set(KINDS_TRIED)}"
        assert COUNT["read"] > 0 and COUNT["refused"] > 0, COUNT
