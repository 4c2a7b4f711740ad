"""Gyro-only sessions (rotations of known angle, no accelerometer): the rotations found in the
gyro, each run with its own bias (accelcal.gyro.rotations), from Python and from ``accelcal
calibrate``; the CTU rig's record against the logic of its repository's script; every
refusal one line, exit 2, nothing written."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from accelcal import cli
from accelcal.formats import read
from accelcal.gyro.errors import NoMotionError, RotationAngleError, TooFewMotionsError
from accelcal.gyro.rotations import calibrate_rotations, find_rotations

CTU = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "ctu_ferraris" / "measured_angular_rates.mat"
RATE = 100.0
#: The true gyro of the synthetic sessions: raw = C⁻¹ ω + b (rad/s).
C_TRUE = np.array([[1.004, 0.002, -0.001], [0.0015, 0.995, 0.003], [-0.002, 0.001, 1.002]])
NOISE = np.deg2rad(0.3)


def _run(axis: int, angle_deg: float, bias, rng, sense: float = 1.0) -> np.ndarray:
    """One run: 20 s rest, a turn of ``angle_deg`` about ``axis`` in 5 s (a smooth rate), 15 s rest."""
    n_rest1, n_turn, n_rest2 = int(20 * RATE), int(5 * RATE), int(15 * RATE)
    s = np.sin(np.pi * (np.arange(n_turn) + 0.5) / n_turn) ** 2
    rate = s / (s.sum() / RATE) * np.deg2rad(angle_deg) * sense  # integrates to the angle exactly
    omega = np.zeros((n_rest1 + n_turn + n_rest2, 3))
    omega[n_rest1:n_rest1 + n_turn, axis] = rate
    return omega @ np.linalg.inv(C_TRUE).T + np.asarray(bias) + NOISE * rng.standard_normal(omega.shape)


def _session(rng, biases, angles=(360.0, 365.0, 362.0), axes=(0, 1, 2)):
    runs = [_run(a, ang, b, rng) for a, ang, b in zip(axes, angles, biases)]
    return runs, np.cumsum([0] + [len(r) for r in runs])


BIASES = np.deg2rad([[0.05, -0.04, -0.08], [-0.01, -0.03, 0.06], [0.11, -0.01, 0.05]])  # the CTU runs' own


def test_per_run_biases_recover_the_gyro_and_pooling_them_does_not():
    rng = np.random.default_rng(1)
    runs, edges = _session(rng, BIASES)
    gyro = np.concatenate(runs)
    t = np.concatenate([np.arange(len(r)) / RATE + 100.0 * k for k, r in enumerate(runs)])
    per = calibrate_rotations(t, gyro, angles_deg=(360.0, 365.0, 362.0), runs=np.column_stack([edges[:-1], edges[1:]]))
    err = (per.model.C - C_TRUE) / per.standard_errors["C"]
    assert np.all(np.abs(err) < 4.5), err
    assert np.all(per.standard_errors["scale_factors"] < 2e-3)
    for run, b in zip(per.settings["runs"], BIASES):
        assert np.all(np.abs(np.asarray(run["bias"]) - b) < 5 * np.asarray(run["bias_se"]))
    pooled = calibrate_rotations(t, gyro, angles_deg=(360.0, 365.0, 362.0))  # one bias for the three runs
    assert np.max(np.abs((pooled.model.C - C_TRUE) / per.standard_errors["C"])) > 6


def test_the_rotations_are_found_with_their_axes_and_windows():
    rng = np.random.default_rng(2)
    runs, edges = _session(rng, BIASES, axes=(2, 0, 1))
    gyro = np.concatenate(runs)
    t = np.arange(len(gyro)) / RATE
    rots, rests, notes = find_rotations(t, gyro, np.column_stack([edges[:-1], edges[1:]]), nominal=1.0)
    assert [r.axis for r in rots] == [2, 0, 1] and notes == []
    for r, a in zip(rots, edges[:-1]):
        assert r.motion[0] - a == pytest.approx(2000, abs=30) and r.motion[1] - a == pytest.approx(2500, abs=30)
        assert r.window[0] < r.motion[0] and r.window[1] > r.motion[1]
    assert all(len(x.intervals) == 2 for x in rests)
    # three angles are per axis x, y, z whatever the order of the rotations
    cal = calibrate_rotations(t, gyro, angles_deg=(365.0, 362.0, 360.0), runs=np.column_stack([edges[:-1], edges[1:]]))
    assert cal.motions["stated_deg"] == [360.0, 365.0, 362.0]


def test_refusals_name_the_cause():
    rng = np.random.default_rng(3)
    still = BIASES[0] + NOISE * rng.standard_normal((3000, 3))
    t = np.arange(3000) / RATE
    with pytest.raises(NoMotionError, match="no rotation found .* accelcal noise"):
        calibrate_rotations(t, still, angles_deg=360)
    runs, _ = _session(rng, BIASES, axes=(0, 0, 2))
    g = np.concatenate(runs)
    with pytest.raises(TooFewMotionsError, match=r"\d+ deg about x, \d+ deg about x, \d+ deg about z; .* each of x, y "
                                                 "and z"):
        calibrate_rotations(np.arange(len(g)) / RATE, g, angles_deg=360)
    runs, _ = _session(rng, BIASES)
    g = np.concatenate(runs)
    with pytest.raises(RotationAngleError, match="2 rotation angles for 3 rotations"):
        calibrate_rotations(np.arange(len(g)) / RATE, g, angles_deg=(360, 360))
    with pytest.raises(RotationAngleError, match=r"rotation turns 36\d\.\d deg by the nominal gyro scale, not the stated 90"):
        calibrate_rotations(np.arange(len(g)) / RATE, g, angles_deg=(360, 90, 360))


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def _mat(tmp_path, **variables) -> Path:
    path = tmp_path / "rates.mat"
    scipy.io.savemat(path, variables)
    return path


def test_cli_calibrates_a_gyro_only_mat_file_run_by_run(tmp_path):
    rng = np.random.default_rng(4)
    runs, _ = _session(rng, BIASES)
    path = _mat(tmp_path, x_rot=np.rad2deg(runs[0]), y_rot=np.rad2deg(runs[1]), z_rot=np.rad2deg(runs[2]))
    out = tmp_path / "gyro.json"
    code, err = _cli("calibrate", path, "--variable", "x_rot,y_rot,z_rot", "--columns", "gx=1,gy=2,gz=3", "--rate",
                     "100", "--gyro-unit", "deg/s", "--rotation-angle", "360,365,362", "--out", out)
    assert code == 0, err
    d = json.loads(out.read_text())
    assert d["sensor"] == "gyroscope" and d["accelerometer"] is None
    g = d["gyroscope"]
    assert g["settings"]["bias_mode"] == "per run" and len(g["settings"]["runs"]) == 3
    se = np.array(g["standard_errors"]["C"])
    assert np.all(np.abs((np.array(g["model"]["C"]) - C_TRUE) / se) < 4.5)
    assert "scale factors [ppm]" in err and "run 3:" in err and "vs rotation axes" in err
    from accelcal.calibration import load_calibration
    from accelcal.calibration.base import CalibrationFileError
    from accelcal.gyro.result import GyroCalibration

    assert GyroCalibration.from_dict(g).to_dict() == g  # the gyroscope object reads back
    with pytest.raises(CalibrationFileError, match="a gyroscope calibrated alone .* apply and export take"):
        load_calibration(out)


@pytest.mark.parametrize("args, message", [
    ((), "a gyro without accelerometer is calibrated from rotations of known angle: give their angles with "
         "--rotation-angle"),
    (("--rotation-angle", "360"), "no rotation found"),
])
def test_cli_refuses_a_gyro_only_file_without_rotations_or_angles(tmp_path, args, message):
    rng = np.random.default_rng(5)
    path = _mat(tmp_path, rest=np.rad2deg(BIASES[0] + NOISE * rng.standard_normal((3000, 3))))
    out = tmp_path / "gyro.json"
    code, err = _cli("calibrate", path, "--columns", "gx=1,gy=2,gz=3", "--rate", "100", "--gyro-unit", "deg/s", *args,
                     "--out", out)
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err, err
    assert not out.exists()


@pytest.fixture(scope="module")
def ctu():
    if not CTU.is_file():
        pytest.skip("../shared/data/ctu_ferraris is absent")
    return read(CTU, variable="x_rotation,y_rotation,z_rotation", columns="gx=1,gy=2,gz=3", rate=100.0,
                gyro_unit="deg/s")


class _Identity:
    """An accelerometer calibration that leaves the samples as they are (m/s²)."""

    def apply(self, raw):
        return np.asarray(raw, float)


def test_with_an_accelerometer_a_turn_about_the_vertical_has_gravity_for_its_axis():
    """The turntable's axes tilted 1.5 deg from the sensor's: gravity measures them, so C comes
    out in the accelerometer's frame; the nominal axes would put the tilt into T (26 mrad)."""
    rng = np.random.default_rng(6)
    tilt = np.deg2rad(1.5)
    true_axes = np.array([[np.cos(tilt), np.sin(tilt), 0.0], [0.0, np.cos(tilt), np.sin(tilt)],
                          [np.sin(tilt), 0.0, np.cos(tilt)]])
    gyro, acc = [], []
    for k, (axis, angle) in enumerate(zip(true_axes, (360.0, 365.0, 362.0))):
        one = np.zeros(3)
        one[k] = 1.0
        omega = _run(k, angle, np.zeros(3), rng) @ C_TRUE.T  # a turn about e_k (and its noise), no bias
        R = _rotation_onto(one, axis)  # turned onto the tilted axis
        gyro.append((omega @ R.T) @ np.linalg.inv(C_TRUE).T + BIASES[k])
        acc.append(9.81 * axis + 0.01 * rng.standard_normal((len(omega), 3)))
    g, a = np.concatenate(gyro), np.concatenate(acc)
    edges = np.cumsum([0] + [len(x) for x in gyro])
    runs = np.column_stack([edges[:-1], edges[1:]])
    t = np.arange(len(g)) / RATE
    cal = calibrate_rotations(t, g, angles_deg=(360.0, 365.0, 362.0), runs=runs, accel=_Identity(), acc=a)
    assert cal.settings["frame"] == "accelerometer frame"
    assert np.all(np.abs((cal.model.C - C_TRUE) / cal.standard_errors["C"]) < 4.5)
    nominal = calibrate_rotations(t, g, angles_deg=(360.0, 365.0, 362.0), runs=runs)
    assert np.max(np.abs(nominal.model.C - C_TRUE)) > 0.02


def _rotation_onto(u, v) -> np.ndarray:
    """The rotation matrix turning unit vector ``u`` onto ``v``."""
    c = np.cross(u, v)
    s, d = np.linalg.norm(c), float(u @ v)
    K = np.array([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])
    return np.eye(3) + K + K @ K * ((1 - d) / s ** 2 if s > 0 else 0.0)


def test_a_gyro_only_table_is_calibrated_where_it_was_refused(tmp_path):
    """A CSV of t, gx, gy, gz (the CTU rotations as a user converts them) once stopped at 'no
    column for ax, ay, az'; one run holding the three rotations has one bias, from all its rests."""
    rng = np.random.default_rng(7)
    runs, _ = _session(rng, [BIASES[0]] * 3)
    g = np.rad2deg(np.concatenate(runs))
    path, out = tmp_path / "rates.csv", tmp_path / "gyro.json"
    np.savetxt(path, np.column_stack([np.arange(len(g)) / RATE, g]), delimiter=",", header="t,gx,gy,gz", comments="",
               fmt="%.6f")
    code, err = _cli("calibrate", path, "--gyro-unit", "deg/s", "--rotation-angle", "360,365,362", "--out", out)
    assert code == 0, err
    gyro = json.loads(out.read_text())["gyroscope"]
    assert gyro["settings"]["bias_mode"] == "all" and len(gyro["settings"]["runs"][0]["rests"]) == 4
    assert np.all(np.abs((np.array(gyro["model"]["C"]) - C_TRUE) / np.array(gyro["standard_errors"]["C"])) < 4.5)


def test_a_unit_off_by_57_is_refused_by_the_stated_angles(tmp_path):
    """The stated angles decide the unit: deg/s read as rad/s turns 57x too far: one line."""
    rng = np.random.default_rng(8)
    runs, _ = _session(rng, BIASES)
    path = _mat(tmp_path, a=np.rad2deg(runs[0]), b=np.rad2deg(runs[1]), c=np.rad2deg(runs[2]))
    code, err = _cli("calibrate", path, "--variable", "a,b,c", "--columns", "gx=1,gy=2,gz=3", "--rate", "100",
                     "--gyro-unit", "rad/s", "--rotation-angle", "360,365,362", "--out", tmp_path / "g.json")
    assert code == 2 and __import__("re").search(r"turns 20\d{3}\.\d deg", err) and "(--gyro-unit, --gyro-sens" in err
    assert not (tmp_path / "g.json").exists()


@pytest.mark.parametrize("command", [("apply", "CAL"), ("discrepancy", "--g", "9.81")])
def test_commands_that_need_an_accelerometer_refuse_a_gyro_alone(tmp_path, command):
    rng = np.random.default_rng(9)
    path = _mat(tmp_path, rest=BIASES[0] + NOISE * rng.standard_normal((500, 3)))
    out = tmp_path / "out"
    args = [a if a != "CAL" else tmp_path / "cal.json" for a in command]
    if command[0] == "apply":  # a calibration of a simulated accelerometer to apply
        from accelcal.calibration import calibrate_recording
        from accelcal.recording import Recording
        from accelcal.simulation import random_directions, simulate_recording

        u = np.vstack([[0, 0, 1.0], random_directions(rng, 15)])
        sim = simulate_recording(rng, u, 9.81, np.eye(3), np.zeros(3), noise_std=0.01)
        calibrate_recording(Recording(sim["t"], sim["acc"], None, "sim", unit="m/s^2"), 9.81,
                            "full_lls")[0].save(tmp_path / "cal.json")
        args = [args[0], args[1], path]
    else:
        args = [args[0], path, *args[1:]]
    code, err = _cli(*args, "--columns", "gx=1,gy=2,gz=3", "--rate", "100", "--out", out)
    assert code == 2 and not out.exists()
    assert f"no accelerometer in this recording (a gyro alone), which 'accelcal {command[0]}' needs" in err, err


def test_the_python_accelerometer_calibration_refuses_a_gyro_alone(ctu):
    from accelcal import calibrate_recording
    from accelcal.errors import RecordingError

    with pytest.raises(RecordingError, match=r"no accelerometer in this recording .*\.calibrate_rotations"):
        calibrate_recording(ctu, 9.81)
