"""Damaged bags read up to the damage: truncated MCAP and sqlite3 files give their intact messages (the
same values as the whole file's first ones) with a note on what was lost; the exact loss from a ROS 2
bag's metadata.yaml; a bag damaged beyond its header is one line; apply copies the intact part."""

from __future__ import annotations

import contextlib
import io
import shutil
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli
from accelcal.calibration import FullLLSCalibration
from accelcal.errors import LogFormatError
from accelcal.formats import ros
from .ros_synthetic import write_imu_bag

N = 6000
T = 1.7e9 + np.arange(N) / 400.0
ACC = np.random.default_rng(5).normal(size=(N, 3))
GYRO = np.random.default_rng(6).normal(size=(N, 3))


def _cut(src: Path, dst: Path, frac: float) -> Path:
    data = src.read_bytes()
    dst.write_bytes(data[: int(len(data) * frac)])
    return dst


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp("bags")
    mcap = write_imu_bag(d / "b.mcap", T, ACC, GYRO, kind="mcap", serialize="fast")
    folder = write_imu_bag(d / "sq", T, ACC, GYRO, kind="ros2-sqlite3", serialize="fast")
    return mcap, folder


@pytest.mark.parametrize("frac", [0.3, 0.75, 0.999])
def test_a_truncated_mcap_file_gives_every_message_before_the_cut(tmp_path, bags, frac):
    cut = _cut(bags[0], tmp_path / "cut.mcap", frac)
    rec = ros.read(cut)
    from rosbags.rosbag2 import Reader

    with Reader(bags[0]) as r:
        record = 1 + 8 + 22 + len(next(r.messages())[2])  # an MCAP message record: op, length, header, data
    cut_at = cut.stat().st_size
    # every complete message record before the cut, including those of the incomplete last chunk; the
    # bytes before them that are not messages: the header, schema, channel, the chunks' message indexes
    assert cut_at - 4096 - 16 * rec.n - record < rec.n * record <= cut_at
    assert np.array_equal(rec.acc, ACC[: rec.n]) and np.array_equal(rec.gyro, GYRO[: rec.n])
    assert rec.notes[-1].startswith(f"warning: cut.mcap is damaged: read up to the damage, {rec.n} messages of /imu")
    assert "beyond the file's end is not known" in rec.notes[-1]


@pytest.mark.parametrize("frac", [0.3, 0.9])
def test_a_truncated_sqlite3_file_gives_its_intact_rows_and_estimates_the_loss(tmp_path, bags, frac):
    db = next(bags[1].glob("*.db3"))
    cut = _cut(db, tmp_path / "cut.db3", frac)
    rec = ros.read(cut)
    assert 0.9 * frac * N < rec.n < N  # the index pages share the file with the rows
    assert np.array_equal(rec.acc, ACC[: rec.n])
    note = rec.notes[-1]
    assert f"read up to the damage, {rec.n} messages of /imu" in note and "of the" in note
    said = int(note.split("about ")[1].split(" more")[0])
    assert abs(said - (N - rec.n)) < 0.05 * N  # the estimate from the header's page count
    assert not list(Path(tmp_path).glob(".accelcal-recover-*"))


def test_a_bag_folder_with_its_metadata_gives_the_exact_loss(tmp_path, bags):
    folder = tmp_path / "bag"
    shutil.copytree(bags[1], folder)
    db = next(folder.glob("*.db3"))
    _cut(db, db, 0.5)
    rec = ros.read(folder)
    assert f"{N - rec.n} of its {N} messages are lost" in rec.notes[-1]


@pytest.mark.parametrize("cut", [12, 30, 200])
def test_a_bag_damaged_in_its_header_is_one_line(tmp_path, bags, cut):
    for src, suffix in ((bags[0], ".mcap"), (next(bags[1].glob("*.db3")), ".db3")):
        q = tmp_path / f"h{suffix}"
        q.write_bytes(src.read_bytes()[:cut])
        with pytest.raises(LogFormatError) as e:
            ros.read(q)
        text = str(e.value)
        assert "\n" not in text and str(q) in text
        assert "nothing to recover" in text or "not a ROS bag" in text or "read up to the damage" in text


def test_apply_on_a_truncated_bag_writes_the_intact_part_and_warns(tmp_path, bags):
    cut = _cut(bags[0], tmp_path / "cut.mcap", 0.6)
    cal = FullLLSCalibration(bias=np.array([0.1, 0.0, -0.1]), M=np.diag([1.01, 0.99, 1.0]), g=9.80665,
                             unit="m/s^2", input_unit="m/s^2")
    cal.save(tmp_path / "cal.json")
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main(["apply", str(tmp_path / "cal.json"), str(cut), "--out", str(tmp_path / "out.mcap")])
    assert code == 0, err.getvalue()
    assert "warning: cut.mcap is damaged: read up to the damage" in err.getvalue()
    n = ros.read(cut).n
    back = ros.read(tmp_path / "out.mcap")
    assert back.n == n and not any("damaged" in x for x in back.notes)
    assert np.array_equal(back.acc, cal.apply(ACC[:n]))


def test_damage_anywhere_gives_the_intact_messages_or_one_line(tmp_path, bags):
    """Bytes overwritten and cut at random places of both storages: a recording or one LogFormatError line,
    never a traceback.  Neither format can tell overwritten values inside a message (sqlite3 has no
    checksums; rosbags writes MCAP chunks without a CRC): at most the two messages the 64 bytes touch
    differ from the bag's own, every other sample is one of them."""
    rng = np.random.default_rng(9)
    for src in (bags[0], next(bags[1].glob("*.db3"))):
        data = src.read_bytes()
        for k in range(12):
            b = bytearray(data[: int(len(data) * rng.uniform(0.05, 1.0))])
            at = int(rng.integers(0, len(b) - 64))
            b[at: at + 64] = rng.integers(0, 256, 64, dtype=np.uint8).tobytes()
            q = tmp_path / f"f{k}{src.suffix}"
            q.write_bytes(bytes(b))
            try:
                rec = ros.read(q)
            except LogFormatError as e:
                assert "\n" not in str(e) and str(q) in str(e)
                continue
            rows = {tuple(r) for r in ACC}
            assert sum(tuple(r) not in rows for r in rec.acc) <= 2  # nothing invented beyond the bytes hit
