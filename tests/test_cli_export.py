"""``accelcal export`` and ``calibrate --strict`` on the command line: files, summary lines, exit codes."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from accelcal import cli
from accelcal.simulation import random_directions, sample_truth, simulate_recording

from .export_fixtures import full_calibration, gyro_quality, noise_report


def run(capsys, *args):
    code = cli.main([str(a) for a in args])
    return code, capsys.readouterr().err


@pytest.fixture
def files(tmp_path):
    cal, no_gyro, noise = tmp_path / "cal.json", tmp_path / "acc_only.json", tmp_path / "noise.json"
    full_calibration().save(cal)
    full_calibration(gyro=False).save(no_gyro)
    noise.write_text(json.dumps(noise_report()))
    return cal, no_gyro, noise


def test_export_writes_the_file_and_says_what_is_left_out(files, tmp_path, capsys):
    cal, _, noise = files
    out = tmp_path / "vehicle.params"
    code, err = run(capsys, "export", cal, "--to", "px4", "--out", out)
    assert code == 0, err
    assert "CAL_ACC0_XSCALE" in out.read_text() and "CAL_GYRO0_ZOFF" in out.read_text()
    assert "left out: the accelerometer's non-orthogonality" in err and " mg at the worst orientation" in err
    code, err = run(capsys, "export", cal, "--noise", noise, "--to", "openvins", "--model", "rpng",
                    "--out", tmp_path / "chain.yaml")
    assert code == 0 and "left out" not in err and "rpng model" in err, err
    code, err = run(capsys, "export", cal, "--imutk", tmp_path / "t" / "imu")  # the old spelling
    assert code == 0 and sorted(p.name for p in (tmp_path / "t").iterdir()) == ["imu_acc.calib", "imu_gyro.calib"]


@pytest.mark.parametrize("args,words", [
    (("--to", "kfgins"), "needs the noise densities and random walks: pass --noise"),
    (("--to", "px4", "--exact"), "--exact: px4's model cannot hold"),
    (("--to", "px4", "--acc-range", "0.01"), "implausible calibration: the accelerometer's offset"),
    (("--to", "px4", "--instance", "7"), "PX4 has calibration slots 0-3"),
    (("--out", "x"), "name one target"),
])
def test_refusals_are_one_line_exit_2_and_write_nothing(files, tmp_path, capsys, args, words):
    cal, _, _ = files
    out = tmp_path / "out.file"
    args = [a if a != "x" else out for a in args]
    code, err = run(capsys, "export", cal, *args, *(("--out", out) if "--out" not in args else ()))
    assert code == 2 and words in err and err.count("\n") == 1, err
    assert not out.exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


def test_a_consumer_that_needs_the_gyroscope_refuses_an_accelerometer_calibration(files, tmp_path, capsys):
    _, no_gyro, noise = files
    for target in ("imucal", "kfgins"):
        out = tmp_path / f"{target}.out"
        code, err = run(capsys, "export", no_gyro, "--noise", noise, "--to", target, "--out", out)
        assert code == 2 and "needs the gyroscope" in err and "calibrate a recording with gyro" in err, err
        assert not out.exists()


def test_strict_refuses_an_untrustworthy_calibration_with_exit_3(tmp_path, capsys):
    cal = full_calibration()
    bad = tmp_path / "bad.json"
    replace(cal, gyro=replace(cal.gyro, quality=gyro_quality(["motions too short"]))).save(bad)
    out = tmp_path / "x.parm"
    code, err = run(capsys, "export", bad, "--to", "ardupilot", "--out", out, "--strict")
    assert code == 3 and "--strict" in err and "gyroscope: motions too short" in err and not out.exists(), err
    code, err = run(capsys, "export", bad, "--to", "ardupilot", "--out", out)
    assert code == 0 and "warning: the calibration is untrustworthy" in err and out.exists()


def test_a_noise_file_that_is_not_a_noise_report_is_refused(files, tmp_path, capsys):
    cal, _, _ = files
    code, err = run(capsys, "export", cal, "--noise", cal, "--to", "vins", "--out", tmp_path / "v.yaml")
    assert code == 2 and "not a noise report of accelcal noise" in err


def test_calibrate_strict_exits_3_on_an_untrustworthy_fit_and_0_on_a_good_one(tmp_path, capsys):
    import pandas as pd

    rng = np.random.default_rng(3)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 17)])
    rec = simulate_recording(rng, u, 9.80665, tr["M"], tr["bias"], noise_std=0.01)
    path = tmp_path / "s.csv"
    pd.DataFrame({"t": rec["t"], "ax": rec["acc"][:, 0], "ay": rec["acc"][:, 1], "az": rec["acc"][:, 2]}).to_csv(
        path, index=False)
    code, err = run(capsys, "calibrate", path, "--out", tmp_path / "good.json", "--strict")
    assert code == 0, err
    # the bias-only model misses the scale factors: its residuals exceed the noise
    code, err = run(capsys, "calibrate", path, "--method", "bias-lls", "--out", tmp_path / "bad.json", "--strict")
    assert code == 3 and "accelcal: error: --strict: the calibration is untrustworthy" in err, err
    assert (tmp_path / "bad.json").exists()
