"""The discrepancy report's summary, on sessions simulated by the reproductions' benchmark (accelcal_repro.discrepancy.benchmark).

Moved from tests/test_summaries.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

import numpy as np
import pytest
from accelcal import cli
from accelcal.discrepancy import report
from accelcal.discrepancy.rules import Rules
from accelcal.formats import read, write_recording
from accelcal_repro.discrepancy import benchmark as B
from tests.test_summaries import G, QUICK, _without_progress


@pytest.fixture(scope="module")
def two_effects(tmp_path_factory):
    rec, _ = B.simulate_case("quadratic+bias_drift", 8.0, 0, seed=11, session=B.Session(), rules=Rules())
    path = tmp_path_factory.mktemp("rec") / "pair.csv"
    write_recording(path, rec)
    return path


def test_discrepancy_prints_the_reports_summary(two_effects, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", QUICK)
    out = tmp_path / "report.json"
    assert cli.main(["discrepancy", str(two_effects), "--g", str(G), "--out", str(out)]) == 0
    err = _without_progress(capsys.readouterr().err)
    rec = read(two_effects)
    rep = report.discrepancy_report(rec, G, stochastic=QUICK, unit=rec.unit)
    assert err == rep.summary(written_to=out) + "\n"
    lines = err.splitlines()
    assert lines[0] == "discrepancy: 30 poses; effect named: quadratic (then bias_drift)"
    assert lines[1].startswith("  gap (RMS residual / noise) ")
    assert any(ln.startswith("  noise between poses: ") for ln in lines)
    assert any(ln.startswith("  excess: ") and "against the rests' white noise alone" in ln for ln in lines)
    assert lines[-3].startswith("  noise terms named: x: ") and lines[-1] == f"  written to {out}"
    # the deterministic layer's own summary is the report's first lines
    det = rep.deterministic.summary(unit=rep.unit).splitlines()
    assert lines[:len(det)] == det and len(det) < len(lines)


def test_a_report_without_the_stochastic_layer_says_so(two_effects):
    rec = read(two_effects)
    rep = report.discrepancy_report(rec, G, stochastic=None, unit=rec.unit)
    text = rep.summary()
    assert text.splitlines()[-1] == "  stochastic layer: not run" and "noise terms named" not in text


def test_the_summary_prints_what_json_cannot_hold(two_effects):
    """Non-finite numbers come from the objects as they are (the JSON has None for NaN and inf)."""
    from dataclasses import replace

    rec = read(two_effects)
    rep = report.discrepancy_report(rec, G, stochastic=None, unit=rec.unit)
    det = rep.deterministic
    nm = {**det.noise_model, "estimated": True, "term": "bias_wander", "process": "random_walk", "size": np.inf,
          "tau_s": np.inf, "size_ci": [0.0, np.inf], "tau_ci": [np.nan, np.inf], "axis_correlation": np.nan,
          "random_walk_K": 2e-4, "random_walk_K_ci": [1e-4, 4e-4], "change_over_session": 0.004, "session_s": 400.0}
    text = replace(det, noise_model=nm).summary()
    line = next(ln for ln in text.splitlines() if ln.startswith("  noise between poses: "))
    # a random walk is said as such: its coefficient and its change over the session, no infinite size or tau
    assert "a random walk" in line and "K 0.0002" in line and "over the 400 s session" in line
    assert "inf" not in line and "correlation between" not in line
