"""Recording readers: canonical CSV round trip, strict errors, the three public formats."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from accelcal.errors import RecordingError
from accelcal.formats import read, write_recording
from accelcal.formats.block_log import read_block_log
from accelcal.formats.imucal import read_imucal_session
from accelcal.formats.imucal_annotated import read_imucal_annotated
from accelcal.formats.imutk import read_imutk_ascii
from accelcal.formats.intervals import read_imucal_section_list
from accelcal.formats.mpu6050 import read_mpu6050_csv
from accelcal.nominal import nominal_conversion
from accelcal.recording import Recording


@pytest.fixture(scope="module")
def data_dir() -> Path:
    d = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
    if not d.is_dir():
        pytest.skip("shared/data not available")
    return d


def _rec(n=50, temp=True, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 100.0
    acc = rng.standard_normal((n, 3)) * 0.01 + [0.1, -0.2, 9.81]
    return Recording(t, acc, 20.0 + 0.01 * t if temp else None, "test")


def _csv(tmp_path, text, name="rec.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _good_lines(n=12):
    return [f"{i / 100:.2f},0.1,0.2,9.8" for i in range(n)]


def _strict(path):
    return read(path, strict=True)


def _raises(path, reader=_strict, match=None) -> str:
    with pytest.raises(RecordingError) as e:
        reader(path)
    msg = str(e.value)
    assert msg and "\n" not in msg and "Traceback" not in msg, msg
    if match:
        assert match in msg, msg
    return msg


# --------------------------------------------------------------------------- canonical CSV


@pytest.mark.parametrize("temp", [True, False])
def test_round_trip_is_exact(tmp_path, temp):
    rec = _rec(temp=temp)
    p = tmp_path / "out.csv"
    write_recording(p, rec)
    back = _strict(p)
    np.testing.assert_array_equal(back.t, rec.t)
    np.testing.assert_array_equal(back.acc, rec.acc)
    if temp:
        np.testing.assert_array_equal(back.temp, rec.temp)
    else:
        assert back.temp is None
    assert back.source == str(p)
    assert [f.name for f in tmp_path.iterdir()] == ["out.csv"]  # no temp file left behind


def test_write_replaces_existing_file(tmp_path):
    p = _csv(tmp_path, "old content\n", "out.csv")
    write_recording(p, _rec(n=20, temp=False))
    assert _strict(p).n == 20


def test_extra_columns_ignored_and_header_whitespace_tolerated(tmp_path):
    lines = [" t , ax,ay ,az,gx,comment"] + [f"{i / 100},{i},{2 * i},{3 * i},0,x" for i in range(12)]
    rec = _strict(_csv(tmp_path, "\n".join(lines) + "\n\n"))  # trailing blank line is harmless
    assert rec.n == 12 and rec.temp is None
    np.testing.assert_array_equal(rec.acc[3], [3, 6, 9])
    assert rec.rate == pytest.approx(100.0)


def test_recording_is_frozen():
    rec = _rec()
    with pytest.raises(ValueError):
        rec.acc[0, 0] = 1.0
    with pytest.raises(AttributeError):
        rec.t = None


def test_missing_file(tmp_path):
    _raises(tmp_path / "nope.csv", match="no such file")


def test_empty_file(tmp_path):
    _raises(_csv(tmp_path, ""), match="empty file")


def test_header_only(tmp_path):
    _raises(_csv(tmp_path, "t,ax,ay,az\n"), match="no data rows")


def test_no_header(tmp_path):
    _raises(_csv(tmp_path, "\n".join(_good_lines()) + "\n"), match="no header")


def test_wrong_columns_are_named(tmp_path):
    msg = _raises(_csv(tmp_path, "time,ax,ay,accz\n" + "\n".join(_good_lines()) + "\n"), match="missing column")
    assert "t," in msg and "az" in msg


def test_duplicate_columns(tmp_path):
    _raises(_csv(tmp_path, "t,ax,ay,az,ax\n" + "\n".join(l + ",1" for l in _good_lines()) + "\n"),
            match="duplicate")


def test_non_numeric_names_column_and_line(tmp_path):
    lines = _good_lines()
    lines[4] = "0.04,0.1,abc,9.8"
    msg = _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(lines) + "\n"), match="non-numeric")
    assert "'ay'" in msg and "line 6" in msg and "abc" in msg


@pytest.mark.parametrize("value", ["nan", "NaN", "inf", "-inf"])
def test_non_finite(tmp_path, value):
    lines = _good_lines()
    lines[2] = f"0.02,{value},0.2,9.8"
    msg = _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(lines) + "\n"), match="non-finite")
    assert "'ax'" in msg and "line 4" in msg


def test_truncated_last_line(tmp_path):
    text = "t,ax,ay,az\n" + "\n".join(_good_lines()) + "\n0.12,0.1,0."
    _raises(_csv(tmp_path, text), match="missing value")


def test_blank_line_inside(tmp_path):
    lines = _good_lines()
    lines.insert(5, "")
    _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(lines) + "\n"), match="line 7")


def test_too_many_fields(tmp_path):
    lines = _good_lines()
    lines[3] += ",5"
    _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(lines) + "\n"), match="malformed")


def test_too_few_rows(tmp_path):
    _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(_good_lines(5)) + "\n"), match="need at least")


def test_time_not_increasing(tmp_path):
    lines = _good_lines()
    lines[6] = lines[5]
    msg = _raises(_csv(tmp_path, "t,ax,ay,az\n" + "\n".join(lines) + "\n"), match="time (column 't') repeats at line 8")
    assert msg.endswith("pass --rate HZ to time the samples by their index")


def test_binary_garbage(tmp_path):
    p = tmp_path / "rec.csv"
    p.write_bytes(bytes(range(256)) * 4)
    _raises(p)


# --------------------------------------------------------------------------- public formats


def test_read_imutk_ascii(data_dir):
    rec = read_imutk_ascii(data_dir / "imu_tk_xsens" / "xsens_acc.mat")
    assert rec.n == 51175 and rec.temp is None
    # the stamps are in whole milliseconds (1 / median step: 100.000 Hz); the clock fitted to them
    # says what samples / duration says, 100.010 Hz
    assert rec.rate == pytest.approx((rec.n - 1) / (511.718 - 0.02984), rel=2e-5)
    np.testing.assert_array_equal(rec.acc[0], [33108, 33329, 36429])
    assert rec.t[0] == pytest.approx(0.02984, abs=1e-3)


def test_read_imucal_session(data_dir):
    rec = read_imucal_session(data_dir / "imucal_ferraris" / "example_ferraris_session.csv")
    assert rec.n == 10376
    np.testing.assert_allclose(rec.t, np.arange(10376) / 102.4)  # n_samples is the row counter; imucal's rate
    assert np.linalg.norm(rec.acc[0]) == pytest.approx(10.35, abs=0.05)  # m/s²
    np.testing.assert_allclose(rec.gyro[0], np.deg2rad([-0.6103515625, -0.30517578125, 0.06103515625]))
    assert rec.gyro_unit == "rad/s"


def test_read_imucal_section_list(data_dir):
    s = read_imucal_section_list(data_dir / "imucal_ferraris" / "example_ferraris_session_list.json")
    assert set(s) == {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot"}
    assert s["x_p"] == (540, 1271)


def test_read_imucal_annotated(data_dir):
    rec, parts = read_imucal_annotated(data_dir / "imucal_ferraris" / "annotated_session.csv")
    assert rec.n == len(parts) == 9414
    np.testing.assert_allclose(np.diff(rec.t), 1 / 102.4)
    assert rec.gyro_unit == "counts" and rec.gyro.shape == (9414, 3)
    order = [parts[0]] + [b for a, b in zip(parts[:-1], parts[1:]) if a != b]
    assert order == ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot"]  # contiguous, time order
    assert abs(rec.acc[parts == "x_p", 0].mean() - 2040) < 10  # raw counts


def test_read_mpu6050(data_dir):
    rec = read_mpu6050_csv(data_dir / "mpu6050_suarez" / "example_data_calibration.csv")
    assert rec.n == 10245
    assert rec.rate == pytest.approx(100.0)
    np.testing.assert_array_equal(rec.acc[0], [-12, -812, 15032])


def test_nominal_conversions():
    x = nominal_conversion("imutk_xsens")
    np.testing.assert_array_equal(x.offset, 32768)
    np.testing.assert_array_equal(x.counts_per_unit, [415, 413, 415])
    assert x.g_local == 9.81744
    m = nominal_conversion("mpu6050")
    assert m.to_si([0, 0, 16384])[2] == pytest.approx(9.80665)
    np.testing.assert_array_equal(nominal_conversion("imucal_session").to_si([1.0, 2.0, 3.0]), [1, 2, 3])
    assert nominal_conversion("imucal_annotated") is None
    with pytest.raises(RecordingError):
        nominal_conversion("nonsense")


def _damaged(tmp_path, src: Path, cut_chars: int = 0, replace=None) -> Path:
    """A copy of ``src`` in tmp_path, cut ``cut_chars`` before its end or with one substitution."""
    text = src.read_text()
    if cut_chars:
        text = text[:-cut_chars]
    if replace:
        text = text.replace(*replace, 1)
    p = tmp_path / src.name
    p.write_text(text)
    return p


@pytest.mark.parametrize("reader, rel, cut, replace", [
    (read_imutk_ascii, "imu_tk_xsens/xsens_acc.mat", 35, None),  # last line loses a field
    (read_imutk_ascii, "imu_tk_xsens/xsens_acc.mat", 4, None),  # last number cut inside its exponent
    (read_imutk_ascii, "imu_tk_xsens/xsens_acc.mat", 0, ("3.3329000e+04", "3.33#9000e+04")),
    (read_imucal_session, "imucal_ferraris/example_ferraris_session.csv", 30, None),
    (read_imucal_session, "imucal_ferraris/example_ferraris_session.csv", 0, ("10.336904296875", "10.33x")),
    (read_mpu6050_csv, "mpu6050_suarez/example_data_calibration.csv", 12, None),  # gyro fields lost
    (read_mpu6050_csv, "mpu6050_suarez/example_data_calibration.csv", 0, ("Fs,100", "Fs,fast")),
    (read_mpu6050_csv, "mpu6050_suarez/example_data_calibration.csv", 0, ("ax,ay,az", "ax,ay")),
    (lambda p: read_imucal_annotated(p)[0], "imucal_ferraris/annotated_session.csv", 10, None),
    # a repeated sample number: refused by the check of every recording (formats.read), at its line
    (lambda p: read(p, format="imucal-annotated"), "imucal_ferraris/annotated_session.csv", 0,
     ("x_a,1029,", "x_a,1028,")),
])
def test_damaged_public_files_raise(tmp_path, data_dir, reader, rel, cut, replace):
    _raises(_damaged(tmp_path, data_dir / rel, cut, replace), reader=reader)


def test_public_readers_reject_empty_and_missing(tmp_path):
    for reader in (read_imutk_ascii, read_imucal_session, read_mpu6050_csv, read_imucal_annotated,
                   read_imucal_section_list):
        _raises(tmp_path / "missing", reader=reader)
    empty = _csv(tmp_path, "", "empty.txt")
    for reader in (read_imutk_ascii, read_imucal_session, read_mpu6050_csv, read_imucal_annotated):
        _raises(empty, reader=reader)
    _raises(_csv(tmp_path, "{not json", "s.json"), reader=read_imucal_section_list)
    _raises(_csv(tmp_path, '{"x_p": {"start": 10, "end": 5}}', "s2.json"), reader=read_imucal_section_list)


# --------------------------------------------------------------------------- known intervals


def test_pose_column_round_trips_known_intervals(tmp_path):
    rec = _rec(n=60)
    rec = Recording(rec.t, rec.acc, rec.temp, "test", intervals=[(0, 20), (20, 35), (40, 60)],
                    labels=("x_p", "x_a", "x_p"))
    p = tmp_path / "out.csv"
    write_recording(p, rec)
    back = _strict(p)
    np.testing.assert_array_equal(back.intervals, [(0, 20), (20, 35), (40, 60)])
    assert back.labels == ("x_p", "x_a", "x_p")
    np.testing.assert_array_equal(back.acc, rec.acc)


def test_pose_column_cannot_merge_touching_intervals_of_one_label(tmp_path):
    rec = _rec(n=30)
    rec = Recording(rec.t, rec.acc, None, "test", intervals=[(0, 10), (10, 20)], labels=("a", "a"))
    with pytest.raises(RecordingError, match="cannot be written"):
        write_recording(tmp_path / "out.csv", rec)
    assert not (tmp_path / "out.csv").exists()


@pytest.mark.parametrize("intervals, match", [([(5, 3)], "not a range"), ([(0, 10), (5, 20)], "overlap"),
                                              ([(0, 100)], "not a range"), ([], "empty")])
def test_bad_known_intervals_raise(intervals, match):
    rec = _rec(n=50)
    with pytest.raises(RecordingError, match=match):
        Recording(rec.t, rec.acc, None, "test", intervals=intervals)


@pytest.mark.parametrize("name, blocks", [("data_sample.csv", 18), ("data_sample2.csv", 20)])
def test_read_block_log(data_dir, name, blocks):
    rec = read_block_log(data_dir / "fastahrs_fxos8700" / name)
    assert len(rec.intervals) == blocks and rec.n == 4000 * blocks
    assert rec.rate == pytest.approx(400.0)
    np.testing.assert_array_equal(np.diff(rec.intervals, axis=1), 4000)
    assert any("no time stamps" in n for n in rec.notes)
    # every block is a still pose (noise std well below 0.1 m/s²) with a magnitude within 10 % of g
    # (this cheap sensor is off by up to 6 %: the calibration's job)
    for a, b in rec.intervals:
        assert 0.9 * 9.80665 < np.linalg.norm(rec.acc[a:b].mean(axis=0)) < 1.1 * 9.80665
        assert rec.acc[a:b].std(axis=0).max() < 0.1


def _block_log(blocks, rows=40, seconds=0.1):
    lines = ["Sensor:       FXOS8700_A", "Type:         Acceleration (m/s2)", "x, y, z"]
    for k in range(blocks):
        lines += [">>> Place accelerometer ...", ">>> Type key when ready...",
                  f">>> Gathering data for {seconds:g} seconds..."]
        lines += [f"0.{k}1, -0.2, 9.8" for _ in range(rows)]
    return lines


def test_block_log_small(tmp_path):
    rec = read_block_log(_csv(tmp_path, "\r\n".join(_block_log(3)) + "\r\n"))
    assert len(rec.intervals) == 3 and rec.rate == pytest.approx(400.0) and "unit from the banner: m/s2" in rec.notes


@pytest.mark.parametrize("edit, match", [
    (lambda L: L[:-25], "truncated or interrupted"),                    # last block cut short
    (lambda L: L[:8] + ["0.1, abc, 9.8"] + L[9:], "expected three numbers"),
    (lambda L: L[:8] + ["0.1, 9.8"] + L[9:], "expected three numbers"),
    (lambda L: [l for l in L if not l.startswith(">>> Gathering")], "no '>>> Gathering data"),
    (lambda L: L[:-35], "has 5 rows"),
    (lambda L: [l.replace("for 0.1 seconds", "for 1.2.3 seconds") for l in L], "duration '1.2.3' is not a number"),
])
def test_damaged_block_log_raises(tmp_path, edit, match):
    _raises(_csv(tmp_path, "\n".join(edit(_block_log(3))) + "\n"), reader=read_block_log, match=match)
