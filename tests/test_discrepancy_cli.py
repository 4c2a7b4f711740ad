"""`accelcal discrepancy` end to end, its bad-input behaviour, and its defaults against the config
(on the reproductions' simulated sessions: tests/test_repro_discrepancy_cli.py)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import yaml

from accelcal import cli
from accelcal.discrepancy import report
from accelcal.discrepancy.rules import Rules
from accelcal.formats import write_recording
from accelcal.recording import Recording
from accelcal.simulation import random_directions, simulate_recording

from tests.configs import load_config

ROOT = Path(__file__).resolve().parents[1]
#: A quick stochastic layer for the tests (the bootstrap is its cost); the defaults are checked below.
QUICK = report.StochasticSettings(n_boot=19, n_resim=1)


def _run(*args):
    return subprocess.run([sys.executable, "-m", "accelcal.cli", *map(str, args)], capture_output=True, text=True)


def test_cli_defaults_are_the_configured_rules():
    """The CLI and the workflow must apply the same rules: config/config.yaml's section
    holds the library defaults (config/ci.yaml may only shrink the stochastic bootstrap)."""
    for name in ("config.yaml", "ci.yaml"):
        cfg = load_config(name)["discrepancy"]
        assert Rules.from_config(cfg["rules"]) == Rules(), name
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["discrepancy"]
    assert report.StochasticSettings.from_config(cfg["stochastic"]) == report.DEFAULT_STOCHASTIC


def test_too_few_poses_for_the_wander_say_so(tmp_path, monkeypatch, capsys):
    """12 poses fit the base model (9 parameters) but leave 3 degrees of freedom: the bias
    wander cannot be estimated.  The report says so and why (not a silent white-noise
    fallback), nothing is named, and the outcome is not_identifiable."""
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", QUICK)
    rng = np.random.default_rng(4)
    sim = simulate_recording(rng, random_directions(rng, 12), 9.80665, 415 * np.eye(3), np.full(3, 32768.0), 3.3,
                             rest_s=8.0, init_rest_s=30.0)
    p = tmp_path / "twelve.csv"
    write_recording(p, Recording(sim["t"], np.round(sim["acc"]), None, ""))
    out = tmp_path / "r.json"
    assert cli.main(["discrepancy", str(p), "--g", "9.80665", "--out", str(out)]) == 0
    rep = json.loads(out.read_text())
    assert rep["noise_model"]["estimated"] is False and "degrees of freedom" in rep["noise_model"]["reason"]
    assert rep["outcome"] == "not_identifiable" and rep["effects"] == []
    assert all("bias wander cannot be estimated" in " ".join(r) for r in rep["not_identifiable_reasons"].values())
    assert "bias wander not estimated" in capsys.readouterr().err
