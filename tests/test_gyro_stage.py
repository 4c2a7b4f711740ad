"""The gyro stage's claims are computed from its tables (a verdict follows the numbers)."""

import pandas as pd

from accelcal_repro.gyro.report import stability
from accelcal_repro.gyro.stage import claims


def _tables(ours_fom: float, trials: int = 30, iterative: float = 1.0):
    integ = pd.DataFrame([{"method": m, "rate_dps": 250.0, "fs_hz": 100.0, "rel_angle_rms_ppm": v,
                           "abs_scale_bias_ppm": 1.0, "scale_bias": 1e-6, "angle_deg": 120.0, "n_motions": 5}
                          for m, v in (("rk4", 300.0), ("magnus4", 200.0), ("euler_sum", 1e5))])
    mc = pd.DataFrame([{"config": c, "factor": c, "value": "", "estimator": e, "parameter": "Cxx", "kind": k,
                        "rms_error": 1.0, "crlb_std": 1.0, "ratio": r, "trials": trials}
                       for c, e, r in (("base", "one_step", 1.1), ("base", "iterative", iterative),
                                       ("far", "one_step", 2.0), ("far", "iterative", iterative))
                       for k in ("scale", "misalignment")])
    ipopt = pd.DataFrame([{"max_diff_in_se": 0.01}])
    fom = pd.DataFrame([{"session": "a", "calibration": "accelcal", "bias": "own_bias", "rms_deg": ours_fom},
                        {"session": "a", "calibration": "imutk_run", "bias": "own_bias", "rms_deg": 0.3},
                        {"session": "b", "calibration": "accelcal", "bias": "own_bias", "rms_deg": 0.1},
                        {"session": "b", "calibration": "imutk_published", "bias": "own_bias", "rms_deg": 0.2}])
    peer = pd.DataFrame([{"session": "xsens", "peer": "factory", "parameter": "K_x", "ours": 4780.0,
                          "peer_value": 4778.0}])
    imucal = pd.DataFrame([{"calibration": c, "parameter": "s_x", "diff_in_se": d}
                           for c, d in (("accelcal", 0.0), ("imucal", 2.0 if ours_fom < 0.3 else 4.0))])
    return integ, mc, ipopt, fom, peer, imucal


def test_verdicts_follow_the_tables():
    good = claims(*_tables(0.2)).set_index("claim_id").verdict
    bad = claims(*_tables(0.4)).set_index("claim_id").verdict
    assert good["figure_of_merit_vs_imutk"] == "reproduced"
    assert bad["figure_of_merit_vs_imutk"] == "not_reproduced"
    assert good["imucal_agrees"] == "reproduced" and bad["imucal_agrees"] == "not_reproduced"
    assert good["one_step_not_enough"] == "reproduced" and good["iterative_efficient"] == "reproduced"
    assert good["xsens_data_sheet"] == "reproduced"  # 2 counts in 4778: 0.04 %
    from accelcal_repro.claims import validate_rows

    validate_rows(claims(*_tables(0.2)))  # the ledger's rules (paper key gyro)


def test_monte_carlo_rules_need_the_trials_that_let_them_fail():
    """Below the trials a rule needs its verdict is not_testable_at_this_scale (the CI's 3
    trials); from there on it follows the numbers, either way."""
    from accelcal_repro.gyro.stage import ratio_rule_minimum

    assert ratio_rule_minimum(0.2).needed == 23 and ratio_rule_minimum(0.5).needed == 4
    few = claims(*_tables(0.2, trials=3)).set_index("claim_id").verdict
    assert {few[c] for c in ("iterative_efficient", "one_step_enough_at_base", "one_step_not_enough")} == {
        "not_testable_at_this_scale"}
    enough = claims(*_tables(0.2, trials=23, iterative=1.3)).set_index("claim_id").verdict
    assert enough["iterative_efficient"] == "not_reproduced" and enough["one_step_enough_at_base"] == "reproduced"


def test_stability_excess_is_one_for_sessions_that_agree_within_their_errors():
    p = pd.DataFrame([{"session": s, "parameter": "s_x", "unit": "ppm", "value": v, "se": 10.0}
                      for s, v in (("fork_data1", 100.0), ("fork_data2", 110.0), ("fork_data3", 90.0))])
    st = stability(p)
    assert 0.9 < st.excess.iloc[0] < 1.1
    p.loc[0, "value"] = 400.0
    assert stability(p).excess.iloc[0] > 10
