"""`accelcal calibrate` end to end on simulated recordings, and its handling of bad ones."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from accelcal.registry import estimators
from accelcal.simulation import classic_directions, random_directions, sample_truth, simulate_recording

G = 9.80665


def _run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "accelcal.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


def _write(path, rec, temp=False):
    df = pd.DataFrame({"t": rec["t"], "ax": rec["acc"][:, 0], "ay": rec["acc"][:, 1], "az": rec["acc"][:, 2]})
    if temp:
        df["temp"] = rec["temp"]
    df["gyro_x"] = 0.0  # other columns are ignored
    df.to_csv(path, index=False)
    return path


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    rng = np.random.default_rng(3)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 29)])
    rec = simulate_recording(rng, u, G, tr["M"], tr["bias"], noise_std=0.01, temperature=(20.0, 25.0))
    path = _write(tmp_path_factory.mktemp("rec") / "session.csv", rec, temp=True)
    return path, tr, len(u)


@pytest.mark.parametrize("method", [e.cli_name for e in estimators("accelerometer")])
def test_calibrate_end_to_end(session, tmp_path, method):
    path, tr, n = session
    out = tmp_path / "result.json"
    p = _run("calibrate", path, "--g", G, "--method", method, "--out", out)
    assert p.returncode == 0, p.stderr
    res = json.loads(out.read_text())
    for key in ("bias", "M", "scale_factors", "nonorthogonality_deg", "n_poses", "residual_rms",
                "standard_errors", "method", "g"):
        assert key in res
    assert res["method"] == method and res["g"] == G and res["n_poses"] == n
    assert np.shape(res["M"]) == (3, 3) and len(res["bias"]) == 3
    assert len(res["poses"]["temp"]) == n
    # 400 samples per pose at 0.01 m/s²: pose means good to ~1e-3 m/s²
    if method.startswith("full"):
        np.testing.assert_allclose(res["bias"], tr["bias"], atol=3e-3)
        np.testing.assert_allclose(res["scale_factors"], tr["scale_factors"], atol=5e-4)
    else:  # the bias-only model is misspecified here (M != I): the bias is still near
        np.testing.assert_allclose(res["bias"], tr["bias"], atol=2e-2)
    assert method in p.stderr and "bias" in p.stderr  # the human summary


def test_calibrate_raw_counts(tmp_path):
    """Counts in, g in m/s²: M carries the sensitivity, the bias is in counts."""
    rng = np.random.default_rng(4)
    sens = np.diag([415.0, 413.0, 415.0])
    rec = simulate_recording(rng, classic_directions(24)[::-1], G, sens, np.full(3, 32768.0), noise_std=2.0)
    out = tmp_path / "r.json"
    p = _run("calibrate", _write(tmp_path / "counts.csv", rec), "--g", G, "--method", "full-lls", "--out", out)
    assert p.returncode == 0, p.stderr
    res = json.loads(out.read_text())
    np.testing.assert_allclose(np.diag(res["M"]), np.diag(sens), rtol=1e-3)
    np.testing.assert_allclose(res["bias"], 32768.0, atol=1.0)


def test_help_explains_model_and_input():
    p = _run("calibrate", "--help")
    assert p.returncode == 0
    for word in ("z = M x + b", "ax,ay,az", "temp", "full-lls", "bias-nlls", "counts"):
        assert word in p.stdout


def _bad_cases(tmp_path, session):
    rng = np.random.default_rng(5)
    path, tr, _ = session
    good = pd.read_csv(path)
    cases = {}
    (tmp_path / "empty.csv").write_text("")
    cases["empty"] = (tmp_path / "empty.csv", "full-lls", "empty")
    good.rename(columns={"ay": "channel_2"}).to_csv(tmp_path / "cols.csv", index=False)
    cases["columns"] = (tmp_path / "cols.csv", "full-lls", "--columns")
    bad = good.astype({"ax": object})
    bad.loc[500, "ax"] = "abc"
    bad.to_csv(tmp_path / "text.csv", index=False)
    cases["non-numeric"] = (tmp_path / "text.csv", "full-lls", "ax")
    nan = good.copy()
    nan.loc[700, "az"] = np.nan
    nan.to_csv(tmp_path / "nan.csv", index=False)
    cases["nan"] = (tmp_path / "nan.csv", "full-lls", "")
    few = simulate_recording(rng, classic_directions(6), G, np.eye(3), tr["bias"], noise_std=0.01)
    cases["few poses"] = (_write(tmp_path / "few.csv", few), "full-lls", "at least 10")
    a = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    plane = simulate_recording(rng, np.column_stack([np.cos(a), np.sin(a), 0 * a]), G, np.eye(3), tr["bias"], 0.01)
    cases["coplanar"] = (_write(tmp_path / "plane.csv", plane), "bias-lls", "plane")
    t = np.arange(6000) / 100.0
    moving = {"t": t, "acc": G * np.column_stack([np.sin(0.7 * t), np.cos(1.1 * t), np.sin(0.3 * t)])
              + rng.normal(0, 2.0, (len(t), 3))}
    cases["never rests"] = (_write(tmp_path / "moving.csv", moving), "full-lls", "")
    cases["missing file"] = (tmp_path / "nope.csv", "full-lls", "nope.csv")
    return cases


def test_bad_recordings_fail_cleanly(tmp_path, session):
    for name, (path, method, expect) in _bad_cases(tmp_path, session).items():
        out = tmp_path / f"{name}.json"
        p = _run("calibrate", path, "--g", G, "--method", method, "--out", out)
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2, (name, p.stderr)
        assert len(lines) == 1 and lines[0].startswith("accelcal: error: "), (name, p.stderr)
        assert "Traceback" not in p.stderr and expect in lines[0], (name, lines[0])
        assert not out.exists(), name
        assert not list(tmp_path.glob(f".{name}.json*")), name  # no half-written temp file


def test_bias_only_needs_one_unit(tmp_path):
    rng = np.random.default_rng(6)
    rec = simulate_recording(rng, classic_directions(12), G, 415 * np.eye(3), np.full(3, 32768.0), 2.0)
    p = _run("calibrate", _write(tmp_path / "c.csv", rec), "--g", G, "--method", "bias-lls", "--out", tmp_path / "o.json")
    assert p.returncode == 2 and "raw counts" in p.stderr and "full-lls" in p.stderr
