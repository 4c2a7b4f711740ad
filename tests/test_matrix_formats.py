"""MATLAB and R files (accelcal.formats.mat, .rda, .variables): a variable read as a table (its
columns by name, or numbered as a headerless table's), the choice among several
(``--variable``), several as runs of one session, and the refusals: no usable variable, a
damaged file, a v7.3 file, a missing extra; the project's own records (the CTU rates, the
ADIS16405 record) read directly."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from accelcal import cli
from accelcal.errors import RecordingError
from accelcal.formats import detect_format, read
from accelcal.formats.variables import RUN_GAP_S

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def _acc(rng, n=200):
    return np.array([0.1, -0.2, 9.8]) + 0.01 * rng.standard_normal((n, 3))


def test_an_unnamed_matrix_is_numbered_as_a_headerless_table(tmp_path):
    rng = np.random.default_rng(0)
    acc = _acc(rng)
    path = tmp_path / "m.mat"
    scipy.io.savemat(path, {"data": np.column_stack([np.arange(200) / 50.0, acc])})
    rec = read(path)
    assert detect_format(path) == "mat" and rec.n == 200 and rec.rate == pytest.approx(50.0)
    np.testing.assert_array_equal(rec.acc, acc)
    assert "no header: columns read as t=column 1, ax=column 2, ay=column 3, az=column 4 (pass --columns to change)" \
        in rec.notes
    gyro_only = read(path, columns="t=1,gx=2,gy=3,gz=4", gyro_unit="rad/s")
    assert gyro_only.acc is None and gyro_only.unit is None
    np.testing.assert_array_equal(gyro_only.gyro, acc)
    with pytest.raises(RecordingError, match="no header and 7 columns: say which is which with --columns"):
        scipy.io.savemat(path, {"data": np.column_stack([acc, acc, acc[:, :1]])})
        read(path)


def test_several_variables_are_listed_chosen_or_joined_as_runs(tmp_path):
    rng = np.random.default_rng(1)
    a, b = _acc(rng), _acc(rng, 150) + [0.0, 0.0, 0.05]
    path = tmp_path / "runs.mat"
    scipy.io.savemat(path, {"first": a, "second": b, "label": "rig 2", "means": a[:3].T})
    with pytest.raises(RecordingError, match=r"2 variables could be the recording: first, second; choose one with "
                                             r"--variable NAME \(several runs of one session: --variable first,second\)"):
        read(path, rate=100.0)
    np.testing.assert_array_equal(read(path, variable="second", rate=100.0).acc, b)
    rec = read(path, variable="first,second", rate=100.0)
    assert rec.runs.tolist() == [[0, 200], [200, 350]] and rec.n == 350
    assert rec.t[200] - rec.t[199] == pytest.approx(RUN_GAP_S) and rec.t[201] - rec.t[200] == pytest.approx(0.01)
    assert any("2 runs joined (first, second)" in n for n in rec.notes)
    with pytest.raises(RecordingError, match=r"variable 'means' is \(3x3 float64\), not a recording .* usable: first, "
                                             "second"):
        read(path, variable="means", rate=100.0)
    with pytest.raises(RecordingError, match=r"no variable 'third' .*found: first \(200x3 values\), second"):
        read(path, variable="third", rate=100.0)
    with pytest.raises(RecordingError, match="--variable applies to the mat or rda formats, not to csv"):
        (tmp_path / "t.csv").write_text("t,ax,ay,az\n" + "\n".join(f"{i},0,0,9.8" for i in range(20)))
        read(tmp_path / "t.csv", variable="x")


def test_a_struct_of_vectors_is_a_table_with_a_header(tmp_path):
    rng = np.random.default_rng(2)
    acc = _acc(rng)
    path = tmp_path / "s.mat"
    scipy.io.savemat(path, {"log": {"time_ms": (10 * np.arange(200))[:, None], "AccX_g": acc[:, :1] / 9.80665,
                                    "AccY_g": acc[:, 1:2] / 9.80665, "AccZ_g": acc[:, 2:] / 9.80665}})
    rec = read(path)
    np.testing.assert_allclose(rec.acc, acc, rtol=1e-12)
    assert rec.rate == pytest.approx(100.0)
    gyro = 0.01 * rng.standard_normal((200, 3))
    scipy.io.savemat(path, {"imu": {"t": np.arange(200) / 100.0, "acc": acc, "gyr": gyro}})  # triads: acc_x ...
    rec = read(path, gyro_unit="rad/s")
    assert "variable imu (200x7 values; columns t, acc_x, acc_y, acc_z, gyr_x, gyr_y, gyr_z)" in rec.notes
    np.testing.assert_array_equal(rec.gyro, gyro)


def test_column_vectors_side_by_side_are_a_table(tmp_path):
    """MATLAB's import of a spreadsheet: one vector per column; the odd one out is left alone."""
    rng = np.random.default_rng(5)
    acc = _acc(rng)
    path = tmp_path / "v.mat"
    scipy.io.savemat(path, {"Time": np.arange(200) / 100.0, "AccX": acc[:, 0], "AccY": acc[:, 1], "AccZ": acc[:, 2],
                            "Temp": np.ones(7), "unit": "m/s^2"})
    rec = read(path)
    np.testing.assert_array_equal(rec.acc, acc)
    assert "variable vectors (200x4 values; columns Time, AccX, AccY, AccZ)" in rec.notes


@pytest.mark.parametrize("content, message", [
    ({"means": np.ones((3, 24))}, r"no variable of this MATLAB file is a recording \(found: means \(3x24 float64\)\)"),
    ({"name": "abc", "flags": np.ones((100, 3), dtype=complex)}, r"found: name \(1 char\), flags \(100x3 complex\)"),
])
def test_a_mat_without_a_usable_variable_is_one_line_exit_2(tmp_path, content, message):
    path, out = tmp_path / "x.mat", tmp_path / "cal.json"
    scipy.io.savemat(path, content)
    code, err = _cli("calibrate", path, "--out", out)
    assert code == 2 and len(err.strip().splitlines()) == 1 and not out.exists()
    assert __import__("re").search(message, err), err


def test_damaged_and_v73_files_are_one_line_exit_2(tmp_path):
    good = tmp_path / "good.mat"
    scipy.io.savemat(good, {"data": _acc(np.random.default_rng(3), 500)})
    out = tmp_path / "cal.json"
    for cut in (200, 1000):
        bad = tmp_path / f"cut{cut}.mat"
        bad.write_bytes(good.read_bytes()[:cut])
        code, err = _cli("calibrate", bad, "--out", out)
        assert code == 2 and not out.exists() and "is damaged or not a .mat" in err and len(err.splitlines()) == 1
    v73 = tmp_path / "v73.mat"
    v73.write_bytes(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(124) + b"\x00\x02IM" + b"\0" * 400)
    code, err = _cli("calibrate", v73, "--out", out)  # the header, but no HDF5 after it
    assert code == 2 and "not a readable MATLAB v7.3 file" in err and len(err.splitlines()) == 1


def _save_v73(path, variables: dict) -> Path:
    """A MATLAB v7.3 file as MATLAB writes one: a 512-byte user block holding the MAT header, then
    HDF5 datasets with MATLAB's dimensions reversed and a MATLAB_class attribute (a struct: a group)."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, value in variables.items():
            if isinstance(value, dict):
                g = f.create_group(name)
                g.attrs["MATLAB_class"] = np.bytes_("struct")
                for k, v in value.items():
                    g.create_dataset(k, data=np.atleast_2d(np.asarray(v, float).T))  # (n, k) in MATLAB
                    g[k].attrs["MATLAB_class"] = np.bytes_("double")
            elif isinstance(value, str):
                f.create_dataset(name, data=np.array([[ord(c)] for c in value], np.uint16))
                f[name].attrs["MATLAB_class"] = np.bytes_("char")
            else:
                f.create_dataset(name, data=np.asarray(value, float).T)
                f[name].attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(116) + bytes(8) + b"\x00\x02IM")
    return path


def test_a_v73_file_reads_as_its_v5_twin(tmp_path):
    """The same variables saved as v5 (scipy) and v7.3 (HDF5 as MATLAB lays it out) give the same recording."""
    rng = np.random.default_rng(4)
    acc, t = _acc(rng, 300), np.arange(300) / 100.0
    v73 = _save_v73(tmp_path / "s73.mat", {"imu": {"t": t, "acc": acc}, "note": "rig 2", "m": np.c_[t, acc]})
    scipy.io.savemat(tmp_path / "s5.mat", {"imu": {"t": t[:, None], "acc": acc}, "note": "rig 2", "m": np.c_[t, acc]})
    for variable in ("imu", "m"):
        a, b = read(v73, variable=variable), read(tmp_path / "s5.mat", variable=variable)
        np.testing.assert_array_equal(a.acc, b.acc)
        np.testing.assert_array_equal(a.t, b.t)
    with pytest.raises(RecordingError) as v73_err:
        read(v73, variable="note")
    with pytest.raises(RecordingError) as v5_err:
        read(tmp_path / "s5.mat", variable="note")
    assert str(v73_err.value).split(": ", 1)[1] == str(v5_err.value).split(": ", 1)[1]  # both: (1 char)


def test_a_v73_file_without_h5py_names_the_extra(tmp_path, monkeypatch):
    v73 = _save_v73(tmp_path / "s73.mat", {"m": np.c_[np.arange(50) / 10, _acc(np.random.default_rng(5), 50)]})
    monkeypatch.setitem(__import__("sys").modules, "h5py", None)
    code, err = _cli("calibrate", v73, "--out", tmp_path / "cal.json")
    assert code == 2 and "accelcal[mat73]" in err and "'-v7'" in err and len(err.splitlines()) == 1


def test_a_missing_rdata_extra_is_one_line(tmp_path, monkeypatch):
    import importlib.util

    sample = tmp_path / "x.rda"
    from .format_samples import SAMPLES

    sample.write_bytes(SAMPLES["rda"](np.random.default_rng(0)))
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "rdata" else real(name, *a))
    code, err = _cli("calibrate", sample, "--out", tmp_path / "cal.json")
    assert code == 2 and err.strip() == (f"accelcal: error: {sample}: reading rda files needs rdata, not installed: "
                                         "pip install accelcal[rdata]")


def test_a_damaged_rda_is_one_line(tmp_path):
    from .format_samples import SAMPLES

    data = SAMPLES["rda"](np.random.default_rng(0))
    bad = tmp_path / "bad.rda"
    bad.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match="not a readable R data file .* damaged"):
        read(bad)


@pytest.fixture(scope="module")
def adis():
    path = DATA / "smac_adis16405" / "adis_16405_imu1.rda"
    if not path.is_file():
        pytest.skip("../shared/data/smac_adis16405 is absent")
    return path


def test_the_adis_record_reads_directly_its_rate_from_the_file(adis):
    """A 10^6 x 6 xz-compressed imudata matrix: columns by its dimnames, 100 Hz from its freq attribute."""
    rec = read(adis, gyro_unit="deg/s")
    assert rec.n == 1_000_000 and rec.rate == pytest.approx(100.0) and rec.unit == "m/s^2"
    assert "t = sample index / 100 Hz (the freq attribute of adis_16405_imu1)" in rec.notes
    assert np.median(rec.acc[:, 2]) == pytest.approx(-1.01565 * 9.80665, rel=0.01)  # Accel. Z in g
    assert np.median(np.abs(rec.gyro)) < np.deg2rad(1.0)


def test_the_ctu_rates_read_as_three_runs():
    path = DATA / "ctu_ferraris" / "measured_angular_rates.mat"
    if not path.is_file():
        pytest.skip("../shared/data/ctu_ferraris is absent")
    code, err = _cli("noise", path, "--out", Path("/nonexistent/x.json"))
    assert code == 2 and "3 variables could be the recording: x_rotation, y_rotation, z_rotation" in err
    rec = read(path, variable="x_rotation,y_rotation,z_rotation", columns="gx=1,gy=2,gz=3", rate=100.0,
               gyro_unit="deg/s")
    assert rec.acc is None and rec.runs.tolist() == [[0, 4001], [4001, 8002], [8002, 12003]]
    code, err = _cli("noise", path, "--variable", "x_rotation,y_rotation", "--columns", "gx=1,gy=2,gz=3", "--rate",
                     "100", "--out", Path("/nonexistent/x.json"))
    assert code == 2 and "2 runs recorded apart: one Allan deviation needs one uninterrupted record" in err
    assert np.rad2deg(rec.gyro[:, 0].max()) == pytest.approx(116.94, abs=0.01)


def test_rds_and_several_r_variables(tmp_path):
    """saveRDS's single object is named after the file; save()'s several are listed and chosen."""
    import pandas as pd
    import rdata

    rng = np.random.default_rng(6)
    acc = _acc(rng)
    df = pd.DataFrame({"time": np.arange(200) / 100.0, "acc_x": acc[:, 0], "acc_y": acc[:, 1], "acc_z": acc[:, 2]})
    rdata.write_rds(tmp_path / "one.rds", df)
    rec = read(tmp_path / "one.rds")
    assert detect_format(tmp_path / "one.rds") == "rda" and "variable one (200x4 values; columns time, acc_x, acc_y, " \
        "acc_z)" in rec.notes
    np.testing.assert_array_equal(rec.acc, acc)
    rdata.write_rda(tmp_path / "two.RData", {"a": df, "b": df.iloc[::2].reset_index(drop=True), "n": np.arange(3.0)},
                    compression="bzip2")
    with pytest.raises(RecordingError, match=r"2 variables could be the recording: a, b; choose one with --variable"):
        read(tmp_path / "two.RData")
    assert read(tmp_path / "two.RData", variable="b").n == 100
