"""`accelcal discrepancy` end to end on sessions simulated by the reproductions' benchmark (accelcal_repro.discrepancy.benchmark).

Moved from tests/test_discrepancy_cli.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

import json
import numpy as np
import pandas as pd
import pytest
from accelcal import cli
from accelcal_repro.discrepancy import benchmark as B
from accelcal.discrepancy import report
from accelcal.discrepancy.rules import Rules
from accelcal.formats import write_recording
from accelcal.recording import Recording
from accelcal.simulation import random_directions, simulate_recording
from tests.test_discrepancy_cli import QUICK, _run


SESSION = B.Session()


@pytest.fixture(scope="module")
def drift_recording(tmp_path_factory):
    rec, key = B.simulate_case("bias_drift", 4.0, 0, seed=5, session=SESSION, rules=Rules())
    path = tmp_path_factory.mktemp("rec") / "drift.csv"
    write_recording(path, rec)
    return path, key


def test_discrepancy_end_to_end(drift_recording, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", QUICK)
    path, key = drift_recording
    out, figs = tmp_path / "report.json", tmp_path / "figs"
    assert cli.main(["discrepancy", str(path), "--g", str(SESSION.g), "--out", str(out), "--figures", str(figs)]) == 0
    rep = json.loads(out.read_text())
    assert rep["effect"] == "bias_drift" and rep["effects"][0] == "bias_drift"
    assert rep["gap_after"] < rep["gap_before"]
    for c in rep["candidates"]:
        for k in ("effect", "round", "statistic", "p_value", "p_adjusted", "delta_bic", "identifiable", "estimate",
                  "se", "mde", "mde_data", "absorbed"):
            assert k in c
    first = [c for c in rep["candidates"] if c["round"] == 1]
    assert {c["effect"] for c in first} == set(Rules().candidates)  # the recording has a temperature column
    named = [c for c in first if c["named"]][0]
    np.testing.assert_allclose(named["estimate"], [key[f"param_{a}"] for a in "xyz"],
                               atol=5 * max(named["se"]))
    st = rep["stochastic"]
    assert set(st["axes"]) == {"x", "y", "z"} and st["n_boot"] == 19
    for k in ("taus", "adev_measured", "named", "gap_before", "gap_after"):
        assert k in st["axes"]["x"]
    assert rep["noise_implication"]["dof"] == rep["dof_after"]
    assert len(rep["poses"]["residual_before"]) == rep["n_poses"]
    assert sorted(p.name for p in figs.iterdir()) == ["discrepancy_allan.pdf", "discrepancy_allan.png",
                                                      "discrepancy_residuals.pdf", "discrepancy_residuals.png"]
    err = capsys.readouterr().err
    assert "effect named: bias_drift" in err and "noise terms named" in err


def test_no_temperature_column_means_not_applicable(drift_recording, tmp_path, monkeypatch):
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", QUICK)
    path, _ = drift_recording
    df = pd.read_csv(path).drop(columns="temp")
    p = tmp_path / "notemp.csv"
    df.to_csv(p, index=False)
    out = tmp_path / "r.json"
    assert cli.main(["discrepancy", str(p), "--g", str(SESSION.g), "--out", str(out)]) == 0
    rep = json.loads(out.read_text())
    assert set(rep["not_applicable"]) == {"temperature", "temperature_scale"}
    assert rep["effect"] == "bias_drift"


def _bad(tmp_path):
    rng = np.random.default_rng(0)
    good, _ = B.simulate_case("none", 0.0, 0, seed=1, session=SESSION, rules=Rules())
    cases = {}
    p = tmp_path / "cols.csv"
    pd.DataFrame({"time": good.t, "x": good.acc[:, 0]}).to_csv(p, index=False)
    cases["cols"] = (p, "--columns")
    p = tmp_path / "nan.csv"
    acc = good.acc.copy()
    acc[500, 1] = np.nan
    write_recording(p, Recording(good.t, acc, None, ""))
    cases["nan"] = (p, "column 'ay'")
    # only 8 poses: the 9-parameter base model needs at least 10
    sim = simulate_recording(rng, random_directions(rng, 8), 9.80665, 415 * np.eye(3), np.full(3, 32768.0), 3.3)
    p = tmp_path / "few.csv"
    write_recording(p, Recording(sim["t"], np.round(sim["acc"]), None, ""))
    cases["few"] = (p, "poses")
    # the sensor never rests: a slow continuous rotation
    t = np.arange(3000) / 100.0
    ang = 0.5 * t
    acc = 32768 + 415 * 9.8 * np.column_stack([np.cos(ang), np.sin(ang), 0.1 * np.ones_like(t)])
    p = tmp_path / "moving.csv"
    write_recording(p, Recording(t, acc + rng.normal(0, 3, acc.shape), None, ""))
    cases["moving"] = (p, "rest")
    cases["missing"] = (tmp_path / "nope.csv", "no such file")
    return cases


def test_bad_inputs_fail_in_one_line_and_write_nothing(tmp_path):
    for name, (path, words) in _bad(tmp_path).items():
        out, figs = tmp_path / f"{name}.json", tmp_path / f"figs_{name}"
        p = _run("discrepancy", path, "--g", 9.80665, "--out", out, "--figures", figs)
        assert p.returncode == 2, (name, p.stderr)
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("accelcal: error:"), (name, p.stderr)
        assert words in lines[0], (name, lines[0])
        assert "Traceback" not in p.stderr
        assert not out.exists() and not figs.exists(), name


def test_bad_g_and_usage(drift_recording, tmp_path):
    path, _ = drift_recording
    p = _run("discrepancy", path, "--g", -1, "--out", tmp_path / "x.json")
    assert p.returncode == 2 and "--g" in p.stderr and not (tmp_path / "x.json").exists()
    p = _run("discrepancy", path, "--g", 9.8)  # --out missing: argparse usage error, exit 2
    assert p.returncode == 2
    p = _run("discrepancy", "--help")
    assert p.returncode == 0
    for word in ("gap_before", "not_identifiable", "z = M x + b", "stochastic"):
        assert word in p.stdout
