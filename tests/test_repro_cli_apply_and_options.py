"""The discrepancy report's named effect applied by `accelcal apply`, on a session simulated by the reproductions' benchmark (accelcal_repro.discrepancy.benchmark).

Moved from tests/test_cli_apply_and_options.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

from __future__ import annotations

import json
import numpy as np
import pytest
from accelcal_repro.discrepancy import benchmark as B
from tests.test_cli_apply_and_options import run


@pytest.mark.parametrize("effect", ["temperature", "quadratic"])
def test_discrepancy_report_applies_its_named_effect(effect, tmp_path, monkeypatch):
    """`accelcal discrepancy` names the hidden effect; `accelcal apply REPORT` applies it:
    the pose magnitudes come closer to g than with the base model alone."""
    from accelcal.calibration import load_calibration
    from accelcal.discrepancy import report
    from accelcal.discrepancy.rules import Rules
    from accelcal.formats import write_recording
    from accelcal.static import detect_static_recording
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", report.StochasticSettings(n_boot=19, n_resim=1))
    session = B.Session()
    rec, key = B.simulate_case(effect, 6.0, 0, seed=3, session=session, rules=Rules())
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    code, err = run("discrepancy", path, "--g", session.g, "--out", tmp_path / "d.json")
    assert code == 0, err
    rep = json.loads((tmp_path / "d.json").read_text())
    assert effect in rep["effects"], rep["effects"]
    cal = load_calibration(tmp_path / "d.json")
    assert effect in [e.id for e in cal.effects]
    poses = detect_static_recording(rec)

    def rms(x):
        mags = [np.linalg.norm(x[a:b].mean(axis=0)) - session.g for a, b in poses.intervals]
        return float(np.sqrt(np.mean(np.square(mags))))

    with_effect = rms(cal.apply(rec.acc, t=rec.t, temp=rec.temp))
    base = rms(cal.apply(rec.acc, t=rec.t, temp=rec.temp, effects=False))
    assert with_effect < 0.7 * base, (with_effect, base)
    code, err = run("apply", tmp_path / "d.json", path, "--out", tmp_path / "o.csv")
    assert code == 0 and f"effects applied: {effect}" in err, err
