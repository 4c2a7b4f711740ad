"""The gyroscope on the command line: calibrated whenever the recording has one, written in the
same file (format 2), applied, exported; every bad input one line, exit 2, nothing written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli
from accelcal.calibration import load_calibration
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
needs_data = pytest.mark.skipif(not (DATA / "imu_tk_xsens").is_dir(), reason="shared data not present")
G = 9.81


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


@pytest.fixture(scope="module")
def session():
    rng = np.random.default_rng(24)
    return simulate_recording(rng, C=random_gyro_matrix(rng), gyro_bias=[0.01, -0.02, 0.005],
                              M=np.diag([1.01, 0.99, 1.0]), acc_bias=[0.1, -0.05, 0.2], n_motions=20)


def write(path, r, gyro=True, gyro_deg=True, t=None):
    t = r["t"] if t is None else t
    cols = [t, r["acc"]]
    header = "t,ax,ay,az"
    if gyro:
        cols.append(np.rad2deg(r["gyro"]) if gyro_deg else r["gyro"])
        header += ",gyr_x [deg/s],gyr_y [deg/s],gyr_z [deg/s]" if gyro_deg else ",wx,wy,wz"
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=header, comments="", fmt="%.10g")
    return path


def test_gyro_columns_are_calibrated_written_applied_and_exported(session, tmp_path, capsys):
    rec = write(tmp_path / "s.csv", session)
    out = tmp_path / "cal.json"
    code, err = run(capsys, "calibrate", rec, "--g", G, "--out", out)
    assert code == 0, err
    assert "gyro unit: deg/s (from the header), converted to rad/s" in err
    assert "\ngyroscope: gyro_iterative" in err and "scale factors [ppm]" in err and "misalignment T" in err
    d = json.loads(out.read_text())
    assert d["format_version"] == 2 and d["gyroscope"]["cal_type"] == "gyro_iterative"
    cal = load_calibration(out)
    se = cal.gyro.standard_errors["C"]
    assert np.abs((cal.gyro.model.C - session["C"]) / se).max() < 4  # within its ± of the truth
    # apply corrects both sensors
    corrected = tmp_path / "corr.csv"
    code, err = run(capsys, "apply", out, rec, "--out", corrected)
    assert code == 0 and "gx, gy, gz in rad/s" in err, err
    table = np.genfromtxt(corrected, delimiter=",", names=True)
    w = np.column_stack([table["gx"], table["gy"], table["gz"]])
    moving = np.linalg.norm(session["rates"], axis=1) > 0.5
    assert np.abs(w - session["rates"])[moving].max() < 0.05  # rad/s: the rate noise of 3e-3 and the ±
    # exports: IMU-TK's two files, imucal's JSON
    code, err = run(capsys, "export", out, "--imutk", tmp_path / "x" / "test_imu")
    assert code == 0, err
    gyro_calib = (tmp_path / "x" / "test_imu_gyro.calib").read_text().split("\n\n")
    T = np.loadtxt(gyro_calib[0].splitlines())
    K = np.loadtxt(gyro_calib[1].splitlines())
    np.testing.assert_allclose(T @ K, cal.gyro.model.C, rtol=1e-10)
    code, err = run(capsys, "export", out, "--imucal", tmp_path / "imucal.json")
    assert code == 0 and json.loads((tmp_path / "imucal.json").read_text())["cal_type"] == "Ferraris"


def test_no_gyro_columns_one_read_line_and_no_gyroscope(session, tmp_path, capsys):
    out = tmp_path / "cal.json"
    code, err = run(capsys, "calibrate", write(tmp_path / "a.csv", session, gyro=False), "--g", G, "--out", out)
    assert code == 0, err
    assert err.count("no gyro columns: the accelerometer alone") == 1 and "gyroscope:" not in err
    assert json.loads(out.read_text())["gyroscope"] is None
    code, err = run(capsys, "calibrate", write(tmp_path / "b.csv", session), "--g", G, "--out", out, "--no-gyro")
    assert code == 0 and "gyro columns ignored (--no-gyro)" in err and "gyroscope:" not in err


def test_gyro_in_a_file_of_its_own(session, tmp_path, capsys):
    acc = write(tmp_path / "acc.txt", session, gyro=False)
    g = tmp_path / "gyro.txt"
    np.savetxt(g, np.column_stack([session["t"], session["gyro"]]))  # IMU-TK's t x y z, rad/s
    out = tmp_path / "cal.json"
    code, err = run(capsys, "calibrate", acc, "--gyro", g, "--gyro-unit", "rad/s", "--g", G, "--out", out)
    assert code == 0 and "gyro from gyro.txt" in err, err
    assert load_calibration(out).gyro is not None


# ------------------------------------------------------------------------ bad input
def _refused(capsys, out, *argv):
    code, err = run(capsys, *argv, "--out", out)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("accelcal: error:"), err
    assert not Path(out).exists()
    return lines[0]


def test_a_gyro_that_does_not_see_the_motions(session, tmp_path, capsys):
    flat = {**session, "gyro": 0.003 * np.random.default_rng(1).standard_normal(session["gyro"].shape)}
    msg = _refused(capsys, tmp_path / "c.json", "calibrate", write(tmp_path / "s.csv", flat, gyro_deg=False),
                   "--g", G)
    assert "gyro shows rotation in only" in msg and "--gyro FILE" in msg


def test_a_saturated_gyro(session, tmp_path, capsys):
    clipped = {**session, "gyro": np.clip(session["gyro"], -0.3, 0.3)}
    msg = _refused(capsys, tmp_path / "c.json", "calibrate", write(tmp_path / "s.csv", clipped, gyro_deg=False),
                   "--g", G, "--gyro-unit", "rad/s", "--gyro-range=-0.3,0.3")
    assert "saturated" in msg and "--gyro-range" in msg


def test_a_gyro_file_on_another_time_base(session, tmp_path, capsys):
    acc = write(tmp_path / "acc.txt", session, gyro=False)
    g = tmp_path / "gyro.txt"
    np.savetxt(g, np.column_stack([session["t"] + 0.5, session["gyro"]]))
    msg = _refused(capsys, tmp_path / "c.json", "calibrate", acc, "--gyro", g, "--g", G)
    assert "time bases do not match" in msg and "--gyro FILE" in msg
    np.savetxt(g, np.column_stack([session["t"][:-50], session["gyro"][:-50]]))
    msg = _refused(capsys, tmp_path / "c.json", "calibrate", acc, "--gyro", g, "--g", G)
    assert "samples" in msg and "--gyro FILE" in msg


def test_a_wrong_gyro_unit(session, tmp_path, capsys):
    msg = _refused(capsys, tmp_path / "c.json", "calibrate", write(tmp_path / "s.csv", session, gyro_deg=False),
                   "--g", G, "--gyro-unit", "deg/s")
    assert "unit or sensitivity is wrong" in msg and "--gyro-unit" in msg


def _ferraris_session(path, angles_deg=(360.0, 360.0, 360.0), stated=None):
    """Six holds, then three turns about x, y, z, and its imucal section list (sections.json)."""
    rng = np.random.default_rng(3)
    fs, parts, acc, gyro = 100.0, [], [], []
    ups = {"x_p": [1, 0, 0], "x_a": [-1, 0, 0], "y_p": [0, 1, 0], "y_a": [0, -1, 0], "z_p": [0, 0, 1],
           "z_a": [0, 0, -1]}
    for name, up in ups.items():
        parts += [name] * 300
        acc.append(np.tile(np.array(up, float) * G, (300, 1)))
        gyro.append(np.zeros((300, 3)))
    for a, name in enumerate(("x_rot", "y_rot", "z_rot")):
        k = 400
        w = np.zeros((k, 3))
        w[:, a] = np.deg2rad(angles_deg[a]) / (k / fs)
        up = np.zeros(3)
        up[a] = 1.0
        parts += [name] * k
        acc.append(np.tile(up * G, (k, 1)))
        gyro.append(w)
    acc = np.concatenate(acc) + 0.01 * rng.standard_normal((len(parts), 3))
    gyro = np.rad2deg(np.concatenate(gyro)) + 0.05 * rng.standard_normal((len(parts), 3))
    t = np.arange(len(parts)) / fs
    with open(path, "w") as f:
        f.write("t,ax,ay,az,gx [deg/s],gy [deg/s],gz [deg/s]\n")
        for i in range(len(parts)):
            f.write(f"{t[i]:.2f},{acc[i, 0]:.5f},{acc[i, 1]:.5f},{acc[i, 2]:.5f},{gyro[i, 0]:.5f},{gyro[i, 1]:.5f},"
                    f"{gyro[i, 2]:.5f}\n")
    sections = {p: None for p in dict.fromkeys(parts)}
    pos = 0
    for p in sections:
        n = parts.count(p)
        sections[p] = {"start": pos, "end": pos + n}
        pos += n
    (path.parent / "sections.json").write_text(json.dumps(sections))
    return path


def test_a_ferraris_session_and_rotations_short_of_the_stated_angle(tmp_path, capsys):
    rec = _ferraris_session(tmp_path / "f.csv")
    out = tmp_path / "f.json"
    code, err = run(capsys, "calibrate", rec, "--g", G, "--method", "bias-lls", "--intervals",
                    tmp_path / "sections.json", "--out", out)
    assert code == 0 and "gyroscope: gyro_ferraris (chosen by the data: rotations of known angle" in err, err
    np.testing.assert_allclose(load_calibration(out).gyro.model.C, np.eye(3), atol=2e-3)
    # an estimator of other data is refused in one line, never silently replaced
    msg = _refused(capsys, tmp_path / "i.json", "calibrate", rec, "--g", G, "--method", "bias-lls", "--intervals",
                   tmp_path / "sections.json", "--gyro-method", "gyro-iterative")
    assert "marks rotations of known angle" in msg and "gyro-iterative fits motions" in msg
    short = _ferraris_session(tmp_path / "g.csv", angles_deg=(360.0, 300.0, 360.0))
    msg = _refused(capsys, tmp_path / "g.json", "calibrate", short, "--g", G, "--method", "bias-lls",
                   "--intervals", tmp_path / "sections.json")
    assert "the y rotation turns 300.0 deg" in msg and "--rotation-angle" in msg
    code, err = run(capsys, "calibrate", short, "--g", G, "--method", "bias-lls", "--intervals",
                    tmp_path / "sections.json", "--rotation-angle", "360,300,360", "--out", tmp_path / "h.json")
    assert code == 0, err  # per axis


# ------------------------------------------------------------------------ real sessions
@needs_data
def test_fork_data1_needs_no_hand_tuning_and_says_what_was_chosen(tmp_path, capsys):
    d = DATA / "imutk_fork_sessions" / "data1"
    code, err = run(capsys, "calibrate", d / "acc_data.txt", "--gyro", d / "gyro_data.txt", "--g", 9.81, "--out",
                    tmp_path / "c.json")
    assert code == 0, err
    assert "static: the default detection found 3 poses; static detection chosen from" in err
    cal = load_calibration(tmp_path / "c.json")
    assert cal.n_poses >= 30 and cal.gyro.quality.n_motions >= 29


@needs_data
def test_xsens_gyro_sensitivities_agree_with_the_data_sheet(tmp_path, capsys):
    d = DATA / "imu_tk_xsens"
    code, err = run(capsys, "calibrate", d / "xsens_acc.mat", "--gyro", d / "xsens_gyro.mat", "--g", 9.81744,
                    "--out", tmp_path / "c.json")
    assert code == 0, err
    sens = 1.0 / np.diag(load_calibration(tmp_path / "c.json").gyro.model.C)
    np.testing.assert_allclose(sens, [4778.0, 4758.0, 4766.0], rtol=2e-3)
