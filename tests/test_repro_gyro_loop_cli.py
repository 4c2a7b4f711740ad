"""The gyroscope's loop through the command line, on sessions simulated by the reproductions' gyro benchmark (accelcal_repro.gyro.loop_benchmark).

Moved from tests/test_gyro_loop_cli.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

from __future__ import annotations

import json
import numpy as np
import pandas as pd
from accelcal_repro.gyro import loop_benchmark as LB
from tests.test_gyro_loop_cli import _table, run


def test_apply_corrects_the_named_gyro_effect(tmp_path):
    """A scale asymmetry of 1 % on the x gyro (about 8x its MDE): `discrepancy` names it,
    `apply` of its report corrects the negative x rates to the truth; `--no-effects` does not."""
    rng = np.random.default_rng(12)
    sim = LB.simulate_recording(rng, **LB.DESIGN)
    gyro = LB._hide(sim, "scale_asymmetry", 0.01)
    path = _table(tmp_path, sim["t"], sim["acc"], gyro)
    code, err = run("discrepancy", path, "--g", sim["g"], "--out", tmp_path / "d.json", "--gyro-unit", "rad/s")
    assert code == 0, err
    gyr = json.loads((tmp_path / "d.json").read_text())["gyroscope"]
    assert gyr["named"][:1] == ["scale_asymmetry"], gyr["named"]
    assert gyr["calibration"]["settings"]["effects"][0]["id"] == "scale_asymmetry"
    errors = {}
    for flag in ((), ("--no-effects",)):
        code, err = run("apply", tmp_path / "d.json", path, "--out", tmp_path / "o.csv", "--gyro-unit", "rad/s", *flag)
        assert code == 0, err
        assert ("gyroscope effects applied: scale_asymmetry" in err) == (not flag), err
        out = pd.read_csv(tmp_path / "o.csv")
        w = out[["gx", "gy", "gz"]].to_numpy()
        neg = sim["rates"][:, 0] < -0.5
        errors[flag] = float(np.sqrt(np.mean((w[neg, 0] - sim["rates"][neg, 0]) ** 2)))
    # the hidden effect alone: 1 % of the negative rates; the noise: 0.003 rad/s per sample
    hidden = float(np.sqrt(np.mean((0.01 * sim["rates"][neg, 0]) ** 2)))
    assert errors[("--no-effects",)] > 0.5 * hidden, (errors, hidden)
    assert errors[()] < 0.35 * errors[("--no-effects",)], (errors, hidden)


def test_a_quantised_gyro_whose_rests_show_no_noise_is_one_line_and_the_accelerometer_loop_runs(tmp_path):
    """A gyro read in steps of 0.05 rad/s with 0.003 rad/s of noise: at rest it reads one level,
    so its noise (the weights of every test) cannot be measured: one line, exit 0, the
    accelerometer's report whole."""
    sim = LB.simulate_recording(np.random.default_rng(12), **LB.DESIGN)
    path = _table(tmp_path, sim["t"], sim["acc"], np.round(sim["gyro"] / 0.05) * 0.05)
    code, err = run("discrepancy", path, "--g", sim["g"], "--out", tmp_path / "d.json", "--gyro-unit", "rad/s")
    assert code == 0, err
    rep = json.loads((tmp_path / "d.json").read_text())
    assert rep["outcome"] in ("none", "effect", "not_identifiable") and rep["poses"]  # the accelerometer's loop ran
    g = rep["gyroscope"]
    assert g["outcome"] == "not_tested" and "\n" not in g["reason"]
    assert "do not measure the gyro's noise" in g["reason"] and "quantised" in g["reason"]
    assert "gyroscope: gyroscope not tested: the rests do not measure" in err


def test_too_few_motions_leave_a_candidate_not_identifiable_with_the_motions_it_needs(tmp_path):
    """Ten motions: 20 residuals, 9 for C, 9 for the g-sensitivity leave 2 degrees of freedom:
    not identifiable, with the 11 motions it needs; the three-parameter candidates are tested."""
    sim = LB.simulate_recording(np.random.default_rng(3), **{**LB.DESIGN, "n_motions": 10})
    path = _table(tmp_path, sim["t"], sim["acc"], sim["gyro"])
    code, err = run("discrepancy", path, "--g", sim["g"], "--out", tmp_path / "d.json", "--gyro-unit", "rad/s")
    assert code == 0, err
    rows = json.loads((tmp_path / "d.json").read_text())["gyroscope"]["candidates"][0]
    g = rows["g_sensitivity"]
    assert g["status"] == "not_identifiable" and g["motions_needed"] == 11, g
    assert "10 here, at least 11 needed" in g["why"] and "gravity points along each axis" in g["needs"]
    assert rows["scale_asymmetry"]["status"] == "tested" and rows["motion_bias"]["status"] == "tested"
    assert rows["clock_rate"]["status"] == "not_identifiable" and "time reference" in rows["clock_rate"]["needs"]
    assert all(r["status"] in ("tested", "not_identifiable") and r["needs"] for r in rows.values())
