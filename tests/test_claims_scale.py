"""The least sample each claim rule needs, pinned on small tables: below it the row is
not_testable_at_this_scale whatever the data, at it the rule decides and can fail.

Burkhard (2024): tests/test_burkhard2024_checks.py; discrepancy: tests/test_discrepancy_claims.py;
the shared minimum functions: tests/test_claims.py.  The measured stage has no rule (every
row is not_reproducible: no public data)."""

import numpy as np
import pandas as pd
import pytest

from accelcal.batista.filter import STATES
from accelcal_repro.batista2011.claims import MINIMUM_RUNS, calibration_claims, filter_claims, observability_claims
from accelcal_repro.claims import NOT_TESTABLE
from accelcal_repro.discrepancy.scoring import accuracy_verdict, clopper_pearson, fpr_verdict
from accelcal_repro.tereshkov.claims import tereshkov_claims


def _verdicts(rows):
    return {r["claim_id"]: r["verdict"] for r in (rows.to_dict("records") if isinstance(rows, pd.DataFrame) else rows)}


# ------------------------------------------------------------------ Batista (2011), Sec. V-A
GROUPS = ["F_inv"] * 9 + ["b_prime"] * 3 + ["f2"] * 3 + ["g_table"] * 3


def _calibration(runs, mean=0.0, se=1e-12, bias=0.0, std=1e-8, crlb=1e-8):
    """A calibration summary of 18 parameters, every one alike."""
    n = len(GROUPS)
    return pd.DataFrame({"method": "batista2011", "data": "quadratic", "group": GROUPS,
                         "parameter": [f"p{i}" for i in range(n)], "n_runs": runs, "n_converged": runs,
                         "mean_error": mean, "se_mean": se, "t_mean": mean / se if se > 0 else np.nan,
                         "std_error": std, "asymptotic_bias": bias, "crlb_std": crlb, "std_over_crlb": std / crlb})


def test_mean_below_1e9_is_decided_by_the_deterministic_bias_at_any_number_of_runs():
    rows = calibration_claims(_calibration(2, bias=5.8e-8, se=2e-6))
    r = rows[0]
    assert r["claim_id"] == "cal_mean_error_below_1e9" and r["verdict"] == "not_reproduced"
    assert r["reproduced_value"].startswith("5.8e-08 (deterministic bias")


def test_mean_below_1e9_needs_the_runs_that_resolve_1e9():
    """Without a deterministic bias above the threshold, a mean of standard error 2e-6 cannot
    show it is below 1e-9: not testable, with the runs it would take; resolved, it can fail."""
    r = calibration_claims(_calibration(60, mean=1e-10, se=2e-6, bias=1e-11))[0]
    assert r["verdict"] == NOT_TESTABLE
    assert "n 60 (Monte Carlo runs), needs n >= 3.84e+09" in r["evidence"]
    assert calibration_claims(_calibration(60, mean=1e-10, se=2e-10, bias=1e-11))[0]["verdict"] == "reproduced"
    assert calibration_claims(_calibration(60, mean=3e-9, se=2e-10, bias=1e-11))[0]["verdict"] == "not_reproduced"


def test_unbiased_and_std_rules_need_two_runs_and_can_fail_at_two():
    v = _verdicts(calibration_claims(_calibration(1, se=np.nan)))
    assert v["cal_unbiased"] == v["cal_std_below_1e7"] == v["cal_mean_error_below_1e9"] == NOT_TESTABLE
    assert MINIMUM_RUNS["cal_unbiased"].needed == MINIMUM_RUNS["cal_std_below_1e7"].needed == 2
    v = _verdicts(calibration_claims(_calibration(2, mean=5e-9, se=1e-9)))      # |t| = 5 > 4
    assert v["cal_unbiased"] == "not_reproduced" and v["cal_std_below_1e7"] == "reproduced"
    v = _verdicts(calibration_claims(_calibration(2, std=2e-7, crlb=2e-7)))
    assert v["cal_unbiased"] == "reproduced" and v["cal_std_below_1e7"] == "not_reproduced"


# ------------------------------------------------------------------ Batista (2011), Sec. V-B and IV
BIAS = np.array([0.1, -0.05, 0.025])


def _filter(runs, rms=1e-4, mean=0.0):
    """Filter tables over 0-200 s: every error ``rms`` from t = 10 s on (10x |b| before), each
    run's error ``mean`` plus an alternating ±1e-5 (so that the mean has a standard error)."""
    t = np.arange(0.0, 201.0, 10.0)
    err = np.where(t < 10, 10 * np.linalg.norm(BIAS), rms)
    summary = pd.DataFrame([{"t": ti, "state": s, "rms_error": e, "filter_sigma": 0.01}
                            for ti, e in zip(t, err) for s in STATES])
    per_run = [mean + (1e-5 if k % 2 else -1e-5) for k in range(runs)]
    runs_t = pd.DataFrame([{"run": k, "t": ti, **{f"e_{s}": m for s in STATES}}
                           for k, m in enumerate(per_run) for ti in t])
    return summary, runs_t


def test_filter_rules_minimum_runs():
    assert {k: m.needed for k, m in MINIMUM_RUNS.items() if k.startswith("filter_")} == {
        "filter_bias_converges_quickly": 1, "filter_mean_errors_converge_to_zero": 2,
        "filter_bias_error_below_accel_noise": 1, "filter_gravity_error_below_accel_noise": 1}
    v = _verdicts(filter_claims(*_filter(1), BIAS, 0.0013, steady_from_s=100.0))
    assert v["filter_mean_errors_converge_to_zero"] == NOT_TESTABLE   # one run: no standard error
    assert v["filter_bias_converges_quickly"] == v["filter_bias_error_below_accel_noise"] == "reproduced"
    v = _verdicts(filter_claims(*_filter(1, rms=1e-3), BIAS, 0.0013, steady_from_s=100.0))
    assert v["filter_bias_error_below_accel_noise"] == v["filter_gravity_error_below_accel_noise"] == "not_reproduced"
    v = _verdicts(filter_claims(*_filter(2), BIAS, 0.0013, steady_from_s=100.0))
    assert v["filter_mean_errors_converge_to_zero"] == "reproduced"
    v = _verdicts(filter_claims(*_filter(2, mean=1e-3), BIAS, 0.0013, steady_from_s=100.0))   # |t| = 100
    assert v["filter_mean_errors_converge_to_zero"] == "not_reproduced"


def _observability(stuck):
    rows = []
    for case in ("changing", "constant"):
        for comp in ("g_axial", "b_axial", "g_perp", "b_perp"):
            late = stuck if case == "constant" and comp.endswith("axial") else 0.01
            rows += [{"case": case, "t": t, "component": comp, "rms_error": 1.0 if t == 0 else late}
                     for t in (0.0, 50.0, 150.0)]
    gram = pd.DataFrame({"case": ["changing", "constant"], "eig_ratio": [1e-4, 1e-16], "null_alignment": [0.0, 1.0]})
    return pd.DataFrame(rows), gram


def test_observability_rule_needs_one_run_and_can_fail_at_one():
    assert observability_claims(*_observability(1.0), steady_from_s=100.0, n_runs=0)[0]["verdict"] == NOT_TESTABLE
    assert observability_claims(*_observability(1.0), steady_from_s=100.0, n_runs=1)[0]["verdict"] == "reproduced"
    assert observability_claims(*_observability(0.2), steady_from_s=100.0, n_runs=1)[0]["verdict"] == "not_reproduced"
    # a table that does not count its runs is judged
    assert observability_claims(*_observability(1.0), steady_from_s=100.0)[0]["verdict"] == "reproduced"


# ------------------------------------------------------------------ Tereshkov
def _tereshkov(runs, t_gyro=130.0, rms_acc=0.01):
    summary = pd.DataFrame([
        {"scenario": sc, "sensor": se, "t_conv": t, "update_time_at_conv": 50.0, "update_fraction": 0.5,
         "ss_rms": r, "e_ss": r, "final_ratio": f, "runs": runs}
        for sc, se, t, r, f in (("field", "gyro", t_gyro, 0.004, 0.02), ("field", "accel", 330.0, rms_acc, 0.04),
                                ("straight", "gyro", 120.0, 0.003, 0.02), ("straight", "accel", np.nan, 0.2, 1.0))])
    obs = pd.DataFrame([{"run": k, "mode": m, "sensitivity": s, "predicted_rms_dps": 0.13, "shift_mps2": 0.2}
                        for k in range(max(runs, 1)) for m, s in (("straight", 0.01), ("turn", 0.67))])
    art = pd.DataFrame({"axis": ["xy"], "rms_vs_artificial": [0.02], "rms_difference": [0.01], "rms_vs_truth": [0.01]})
    sweep = pd.DataFrame([{"reference": ref, "kind": k, "angle_deg": a, "sensor": se, "ss_rms": r,
                           "final_ratio": 0.05, "runs": runs}
                          for ref in ("equivalent", "sensor_axes") for k in ("roll_pitch", "yaw") for a in (0.0, 15.0)
                          for se, r in (("gyro", 0.002), ("accel", rms_acc), ("attitude", 0.05))])
    return summary, obs, art, sweep


def test_tereshkov_rules_need_one_run_and_can_fail_at_one():
    judged = {"gyro_convergence_time", "accel_convergence_time", "accel_slower_than_gyro", "gyro_steady_state_rms",
              "accel_steady_state_rms", "accel_unobservable_straight", "installation_roll_pitch", "installation_yaw"}
    v = _verdicts(tereshkov_claims(*_tereshkov(0), artificial_runs=0))
    assert {k for k, x in v.items() if x == NOT_TESTABLE} == judged | {"artificial_bias_test"}
    v = _verdicts(tereshkov_claims(*_tereshkov(1), artificial_runs=1))
    assert all(v[k] == "reproduced" for k in judged | {"artificial_bias_test"}), v
    v = _verdicts(tereshkov_claims(*_tereshkov(1, t_gyro=500.0, rms_acc=0.05), artificial_runs=1))
    assert v["gyro_convergence_time"] == v["accel_steady_state_rms"] == v["installation_yaw"] == "not_reproduced"


# ------------------------------------------------------------------ the benchmark summary's own verdicts
def test_benchmark_summary_verdicts_are_not_testable_below_the_minimum():
    """The summary's goal verdicts follow the same minima as the claims: a false-positive rate
    needs 36 recordings (alpha 0.05) to pass, a naming accuracy 3 (power 0.8) to fail."""
    for n, verdict in ((6, NOT_TESTABLE), (35, NOT_TESTABLE), (36, "pass")):
        lo, hi = clopper_pearson(0, n)
        assert fpr_verdict(lo, hi, n, 0.05) == verdict, n
    lo, hi = clopper_pearson(3, 36)
    assert fpr_verdict(lo, hi, 36, 0.05) == "fail"
    for n, verdict in ((1, NOT_TESTABLE), (2, NOT_TESTABLE), (3, "fail")):
        assert accuracy_verdict(clopper_pearson(0, n)[1], n, 0.8) == verdict, n
    assert accuracy_verdict(clopper_pearson(3, 3)[1], 3, 0.8) == "pass"
    assert accuracy_verdict(clopper_pearson(0, 2.5)[1], 2.5, 0.8) == "fail"   # 0/2.5: upper end 0.771 < 0.8


@pytest.mark.parametrize("runs", [0, 1])
def test_tereshkov_unknown_artificial_runs_are_judged(runs):
    v = _verdicts(tereshkov_claims(*_tereshkov(runs)))
    assert v["artificial_bias_test"] == "reproduced"
