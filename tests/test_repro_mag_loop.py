"""The magnetometer's discrepancy loop: nothing named on effect-free sessions with correlated
noise, each hidden effect at 3x its MDE named (the disturbance with its stretch), the noise model
that makes the false positives honest, and the report's `magnetometer` section."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.discrepancy import mag_loop as ML
from accelcal.discrepancy.report import discrepancy_report
from accelcal.discrepancy.schema import REPORT_SCHEMA, check_statuses
from accelcal.gyro.simulate import simulate_recording
from accelcal.recording import Recording
from accelcal.mag.fit import FieldSamples
from accelcal.mag.noise import fit_ar
from accelcal_repro.mag import loop_benchmark as LB


@pytest.fixture(scope="module")
def null_case():
    return LB.run_case(5, n_boot=99)


def test_an_effect_free_session_names_nothing_and_every_candidate_has_an_mde(null_case):
    assert null_case["named"] == []
    assert set(null_case["mde"]) == set(ML.CANDIDATE_NAMES)
    assert null_case["excess_before"] == pytest.approx(1.0, abs=0.2)


@pytest.mark.parametrize("effect", ML.CANDIDATE_NAMES)
def test_a_hidden_effect_at_three_times_its_mde_is_named(null_case, effect):
    case = LB.run_case(6, effect, 3.0 * null_case["mde"][effect], n_boot=99)
    assert effect in case["named"]


def test_the_disturbance_is_found_where_it_was_hidden():
    m, temp, sigma = LB.simulate(np.random.default_rng(7), "disturbance", 3.0)
    res = ML.mag_discrepancy(FieldSamples(m, noise_cov=np.eye(3) * sigma**2), temp, n_boot=99)
    assert "disturbance" in res.named
    row = next(r["disturbance"] for r in res.rounds if "disturbance" in r and r["disturbance"].get("window"))
    n = len(m)
    assert row["window"] == [n // 3, 2 * n // 3]
    est = res.estimates["disturbance"]["db_x"]
    assert abs(est[0] - 3.0) < 4 * est[1]


def test_without_the_noise_models_correlated_noise_names_effects_that_are_not_there(monkeypatch):
    """The noise models keep the false positives at alpha: with the residuals taken as independent
    (AR(0), no block test), strongly low-passed noise names a disturbance or soft iron."""
    design = {"rho": 0.95}
    seeds = range(40, 44)
    both = [LB.run_case(s, n_boot=99, design=design)["named"] for s in seeds]
    monkeypatch.setattr(ML, "fit_ar", lambda r, **kw: fit_ar(r, max_order=0))
    monkeypatch.setattr(ML, "block_p", lambda *a, **kw: 0.0)
    neither = [LB.run_case(s, n_boot=99, design=design)["named"] for s in seeds]
    assert sum(bool(x) for x in both) <= 1
    assert sum(bool(x) for x in neither) >= 3


def test_the_report_section_has_the_gyroscopes_keys_and_a_reason_when_it_cannot_run():
    m, temp, _ = LB.simulate(np.random.default_rng(8))
    res, err = ML.mag_layer(SimpleNamespace(mag=m, temp=temp, source="sim"), None, n_boot=49)
    assert err is None
    d = res.to_dict()
    for key in ("named", "outcome", "candidates", "excess_before", "excess_after", "estimates", "alpha", "n_boot",
                "noise_model", "notes"):
        assert key in d
    assert d["outcome"] in REPORT_SCHEMA["properties"]["magnetometer"]["properties"]["outcome"]["enum"]
    res, err = ML.mag_layer(SimpleNamespace(mag=np.zeros((100, 3)), temp=None, source="f.csv"), None)
    assert res is None and err.startswith("magnetometer not tested: ") and "\n" not in err


def test_the_discrepancy_report_holds_the_magnetometer_section_and_its_summary_line():
    rng = np.random.default_rng(2)
    sim = simulate_recording(rng, n_motions=10, angle_deg=100.0, peak_rate_dps=150.0, rest_s=3.0, init_rest_s=10.0,
                             gyro_noise=0.003, acc_noise=0.01)
    m, _, _ = LB.simulate(rng, design={"n_samples": len(sim["t"])})
    rec = Recording(t=sim["t"], acc=sim["acc"], temp=None, source="s", unit="m/s^2", mag=m, mag_unit="uT")
    rep = discrepancy_report(rec, 9.81, stochastic=None, search=True, min_poses=6)
    d = rep.to_dict()
    check_statuses(d)
    assert d["magnetometer"]["outcome"] in ("none", "effect", "not_identifiable")
    assert "magnetometer: " in rep.summary()
    off = discrepancy_report(rec, 9.81, stochastic=None, search=True, min_poses=6, mag=False).to_dict()
    assert off["magnetometer"] == {"outcome": "not_tested", "reason": "magnetometer left out (--no-mag)"}
