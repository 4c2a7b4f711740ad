"""`accelcal calibrate` options (detection, intervals, columns, units), its warnings on the
real recordings, and `accelcal apply` (round trip, time column kept, effects, refusals)."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from accelcal import cli
from accelcal.simulation import random_directions, sample_truth, simulate_recording

G = 9.80665
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")


def run(*args):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def warnings_of(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.startswith("warning:")]


@pytest.fixture(scope="module")
def sim():
    rng = np.random.default_rng(8)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 24)])
    return simulate_recording(rng, u, G, tr["M"], tr["bias"], noise_std=0.01, temperature=(20.0, 23.0)), tr


def _write(path, sim, **cols):
    rec = sim[0]
    df = pd.DataFrame({"timestamp_ms": np.round(rec["t"] * 1000).astype(np.int64), "acc_x": rec["acc"][:, 0],
                       "acc_y": rec["acc"][:, 1], "acc_z": rec["acc"][:, 2], "temp": rec["temp"], **cols})
    df.to_csv(path, index=False)
    return path


def test_clean_fit_prints_no_warning_and_apply_round_trips(sim, tmp_path):
    path = _write(tmp_path / "rec.csv", sim)
    code, err = run("calibrate", path, "--g", G, "--out", tmp_path / "cal.json", "--figures", tmp_path / "figs")
    assert code == 0 and warnings_of(err) == [], err
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == ["calibration_coverage.pdf",
                                                                      "calibration_coverage.png"]
    code, err = run("apply", tmp_path / "cal.json", path, "--out", tmp_path / "out.csv")
    assert code == 0, err
    out = pd.read_csv(tmp_path / "out.csv")
    src = pd.read_csv(path)
    assert list(out.columns) == ["timestamp_ms", "ax", "ay", "az", "temp"]
    assert (out["timestamp_ms"] == src["timestamp_ms"]).all()  # the time column as written
    cal = json.loads((tmp_path / "cal.json").read_text())
    t = src["timestamp_ms"].to_numpy() / 1000
    for a, b, res in zip(cal["poses"]["t_start"], cal["poses"]["t_end"], cal["residuals"]):
        m = (t >= a - 1e-9) & (t <= b + 1e-9)
        x = out.loc[m, ["ax", "ay", "az"]].to_numpy().mean(axis=0)
        assert np.linalg.norm(x) - G == pytest.approx(res, abs=1e-9)


def test_apply_refuses_the_wrong_unit_and_missing_temperature(sim, tmp_path):
    path = _write(tmp_path / "rec.csv", sim)
    assert run("calibrate", path, "--out", tmp_path / "cal.json")[0] == 0
    counts = tmp_path / "counts.csv"
    df = pd.read_csv(path)
    df[["acc_x", "acc_y", "acc_z"]] = np.round(df[["acc_x", "acc_y", "acc_z"]] * 1670)
    df.to_csv(counts, index=False)
    code, err = run("apply", tmp_path / "cal.json", counts, "--out", tmp_path / "o.csv")
    assert code == 2 and "--unit" in err and "counts" in err and not (tmp_path / "o.csv").exists()
    code, err = run("apply", tmp_path / "nope.json", path, "--out", tmp_path / "o.csv")
    assert code == 2 and "no such calibration file" in err and len(err.strip().splitlines()) == 1
    # a calibration with a temperature term needs the temperature of every sample
    cal = json.loads((tmp_path / "cal.json").read_text())
    cal["cal_type"] = "extended"
    cal["effects"] = [{"id": "temperature", "reference": 21.5,
                       "parameters": {"gamma_x": 1e-3, "gamma_y": 0.0, "gamma_z": 0.0}}]
    (tmp_path / "ext.json").write_text(json.dumps(cal))
    notemp = tmp_path / "notemp.csv"
    pd.read_csv(path).drop(columns=["temp"]).to_csv(notemp, index=False)
    code, err = run("apply", tmp_path / "ext.json", notemp, "--out", tmp_path / "o.csv")
    assert code == 2 and "temperature term needs the temp" in err and not (tmp_path / "o.csv").exists()
    code, err = run("apply", tmp_path / "ext.json", path, "--out", tmp_path / "o.csv")
    assert code == 0 and "effects applied: temperature" in err


def test_detection_options_and_init_rest(sim, tmp_path):
    rec = sim[0]
    n = 400  # the first 4 s shaken: no initial rest
    acc = rec["acc"].copy()
    acc[:n] += 1.5 * np.random.default_rng(1).standard_normal((n, 3))
    p = tmp_path / "shaken.csv"
    pd.DataFrame({"t": rec["t"], "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2]}).to_csv(p, index=False)
    code, err = run("calibrate", p, "--out", tmp_path / "a.json")
    assert code == 0 and "quietest 2 s" in err and "not at rest" in err, err
    code, err = run("calibrate", p, "--out", tmp_path / "b.json", "--init-rest", "20")
    assert code == 2 and "not at rest" in err and len(err.strip().splitlines()) == 1
    code, err = run("calibrate", p, "--out", tmp_path / "c.json", "--init-rest", "none", "--window", "0.5",
                    "--threshold", "4", "--min-duration", "1.5", "--trim", "0.3")
    assert code == 0, err
    static = json.loads((tmp_path / "c.json").read_text())["static"]
    assert static["reference"] == "quietest_stretch" and static["window"] == 0.5 and static["threshold_factor"] == 4
    code, err = run("calibrate", p, "--out", tmp_path / "d.json", "--threshold", "0.5")
    assert code == 2 and "--threshold must exceed 1" in err


def test_columns_unit_and_time_unit_options(sim, tmp_path):
    rec = sim[0]
    p = tmp_path / "odd.csv"
    pd.DataFrame({"clock": rec["t"] * 1e3, "ch1": rec["acc"][:, 0] / G, "ch2": rec["acc"][:, 1] / G,
                  "ch3": rec["acc"][:, 2] / G}).to_csv(p, index=False)
    code, err = run("calibrate", p, "--out", tmp_path / "a.json")
    assert code == 2 and "--columns" in err
    code, err = run("calibrate", p, "--out", tmp_path / "a.json", "--columns", "t=clock,ax=ch1,ay=ch2,az=4",
                    "--unit", "g", "--time-unit", "ms")
    assert code == 0, err
    js = json.loads((tmp_path / "a.json").read_text())
    np.testing.assert_allclose(js["bias"], sim[1]["bias"], atol=2e-3)
    assert js["unit"] == "m/s^2" and any("--unit" in n for n in js["notes"])


def test_a_wrong_time_unit_gets_a_hint(sim, tmp_path):
    rec = sim[0]
    p = tmp_path / "ms.csv"
    pd.DataFrame({"t": np.round(rec["t"] * 1000), "ax": rec["acc"][:, 0], "ay": rec["acc"][:, 1],
                  "az": rec["acc"][:, 2]}).to_csv(p, index=False)
    code, err = run("calibrate", p, "--out", tmp_path / "a.json", "--time-unit", "s")
    assert code == 2 and "--time-unit" in err and "0.1 Hz" in err, err


@needs_data
def test_xsens_warns_that_residuals_exceed_the_noise(tmp_path):
    code, err = run("calibrate", DATA / "imu_tk_xsens" / "xsens_acc.mat", "--g", 9.81744, "--out", tmp_path / "x.json")
    assert code == 0
    w = warnings_of(err)
    assert len(w) == 1 and "what the pose noise predicts" in w[0] and "accelcal discrepancy" in w[0]
    q = json.loads((tmp_path / "x.json").read_text())["quality"]
    assert 2.0 < q["excess"] < 3.5 and q["p_value"] < 1e-10 and not q["trustworthy"]


@needs_data
def test_mpu6050_ten_poses_warn_about_one_degree_of_freedom(tmp_path):
    code, err = run("calibrate", DATA / "mpu6050_suarez" / "example_data_calibration.csv", "--out", tmp_path / "m.json")
    assert code == 0
    w = [x for x in warnings_of(err) if not x.startswith("warning: gyroscope:")]  # the accelerometer's
    assert len(w) == 1 and "1 degree(s) of freedom" in w[0]


@needs_data
def test_fork_session_is_clean_and_calibrates_the_other_sessions(tmp_path):
    """One IMU, three sessions: calibrated on data2, applied to data3, the pose magnitudes
    of data3 are within a few mm/s² of g (an independent check of apply)."""
    d = DATA / "imutk_fork_sessions"
    code, err = run("calibrate", d / "data2" / "acc_data.txt", "--out", tmp_path / "c.json")
    assert code == 0 and warnings_of(err) == [], err
    assert run("apply", tmp_path / "c.json", d / "data3" / "acc_data.txt", "--out", tmp_path / "o.csv")[0] == 0
    assert run("calibrate", d / "data3" / "acc_data.txt", "--out", tmp_path / "c3.json")[0] == 0
    poses = json.loads((tmp_path / "c3.json").read_text())["poses"]
    out = pd.read_csv(tmp_path / "o.csv", header=0, names=["t", "ax", "ay", "az"])
    dev = []
    for a, b in zip(poses["t_start"], poses["t_end"]):
        m = (out.t >= a) & (out.t <= b)
        dev.append(np.linalg.norm(out.loc[m, ["ax", "ay", "az"]].to_numpy().mean(axis=0)) - G)
    assert np.sqrt(np.mean(np.square(dev))) < 0.01  # m/s²; uncalibrated the bias alone is ~0.1


@needs_data
def test_imucal_section_list_as_known_intervals(tmp_path):
    d = DATA / "imucal_ferraris"
    code, err = run("calibrate", d / "example_ferraris_session.csv", "--g", 9.81, "--method", "bias-lls",
                    "--intervals", d / "example_ferraris_session_list.json", "--out", tmp_path / "i.json")
    assert code == 0, err
    js = json.loads((tmp_path / "i.json").read_text())
    assert js["n_poses"] == 6 and js["poses"]["labels"] == ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"]
    assert js["static"]["reference"] == "known_intervals"
    # imucal's own Ferraris calibration of these samples (results/measured/peer_imucal.csv): b = (0.537, -0.616, 0.399)
    np.testing.assert_allclose(js["bias"], [0.537, -0.616, 0.399], atol=2e-3)
    csv = tmp_path / "iv.csv"
    csv.write_text("start,end,label\n" + "\n".join(f"{a / 102.4},{(b - 1) / 102.4},{k}" for k, (a, b) in
                                                   zip(["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"],
                                                       [(540, 1271), (1620, 2361), (2814, 3298), (3740, 4152),
                                                        (4522, 4975), (5376, 5983)])) + "\n")
    code, err = run("calibrate", d / "example_ferraris_session.csv", "--g", 9.81, "--method", "bias-lls",
                    "--intervals", csv, "--out", tmp_path / "j.json")
    assert code == 0, err
    assert json.loads((tmp_path / "j.json").read_text())["bias"] == js["bias"]


@needs_data
@pytest.mark.parametrize("rel, poses", [("fastahrs_fxos8700/data_sample.csv", 18),
                                        ("fastahrs_fxos8700/data_sample2.csv", 20)])
def test_fxos_block_logs_read_directly(rel, poses, tmp_path):
    code, err = run("calibrate", DATA / rel, "--out", tmp_path / "f.json")
    assert code == 0, err
    js = json.loads((tmp_path / "f.json").read_text())
    assert js["n_poses"] == poses and js["static"]["reference"] == "known_intervals"
    assert any("what the pose noise predicts" in w for w in warnings_of(err))  # 18-29x: a nonlinear sensor


@needs_data
def test_too_few_orientations_is_named_as_the_cause(tmp_path):
    """imucal's session: 13 rests but 6 orientations; the full model's failure says why."""
    code, err = run("calibrate", DATA / "imucal_ferraris" / "example_ferraris_session.csv", "--g", 9.81,
                    "--out", tmp_path / "i.json")
    assert code == 2 and "only 6 distinct orientations" in err and "bias-only" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "i.json").exists()


def test_sensitivity_converts_counts_for_the_bias_only_models(sim, tmp_path):
    rec = sim[0]
    counts = np.round(np.array([120.0, -340.0, 610.0]) + rec["acc"] / G * 16384)
    p = tmp_path / "counts.csv"
    pd.DataFrame({"t": rec["t"], "ax": counts[:, 0], "ay": counts[:, 1], "az": counts[:, 2]}).to_csv(p, index=False)
    code, err = run("calibrate", p, "--method", "bias-lls", "--out", tmp_path / "a.json")
    assert code == 2 and "raw counts" in err
    code, err = run("calibrate", p, "--method", "bias-lls", "--sensitivity", "16384", "--zero", "120,-340,610",
                    "--out", tmp_path / "b.json")
    assert code == 0 and "converted to m/s^2 by the nominal sensitivity" in err, err
    js = json.loads((tmp_path / "b.json").read_text())
    assert js["unit"] == "m/s^2" and js["input"]["unit"] == "counts"
    np.testing.assert_allclose(js["input"]["sensitivity"], 16384 / G)
    # apply takes the raw counts and gives m/s²
    code, err = run("apply", tmp_path / "b.json", p, "--out", tmp_path / "o.csv")
    assert code == 0, err
    out = pd.read_csv(tmp_path / "o.csv")
    assert abs(np.median(np.linalg.norm(out[["ax", "ay", "az"]].to_numpy(), axis=1)) - G) < 0.2
    for bad, words in ((["--zero", "5"], "--zero needs --sensitivity"), (["--sensitivity", "16384/furlong"], "per g"),
                       (["--sensitivity", "a,b"], "one or three numbers")):
        code, err = run("calibrate", p, "--out", tmp_path / "c.json", *bad)
        assert code == 2 and words in err and not (tmp_path / "c.json").exists(), err
    m = tmp_path / "ms2.csv"
    pd.DataFrame({"t": rec["t"], "ax": rec["acc"][:, 0], "ay": rec["acc"][:, 1], "az": rec["acc"][:, 2]}).to_csv(
        m, index=False)
    code, err = run("calibrate", m, "--sensitivity", "16384", "--out", tmp_path / "d.json")
    assert code == 2 and "converts raw counts" in err
