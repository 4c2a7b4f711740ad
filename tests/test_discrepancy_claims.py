"""Claims of the discrepancy stage judged on small summary tables: a rule that cannot give
one of its verdicts at the table's sample size makes its claim not_reproducible (with n and
the interval in the reason); a rule that can gives the verdict the intervals say."""

import numpy as np
import pandas as pd
import pytest

from accelcal_repro.discrepancy import claims as DC
from accelcal_repro.discrepancy.benchmark import NONE, OUTLIER
from accelcal_repro.discrepancy.scoring import FPR_RULE, SUMMARY_COLUMNS, clopper_pearson

ALPHA, POWER = 0.05, 0.8
PROFILES = pd.DataFrame({"profile": ["white", "gm"], "wander_over_white": [0.0, 1.0]})
ADIS = pd.DataFrame([{"axis": "all", "observed_ci_low": 1.0, "observed_ci_high": 3.0, "observed_var": 2.0,
                      "reference_var": 2.0, "reference_white_var": 1.0, "pieces": 10, "excess_observed": 1.2}])


def _row(null, profile, effect, metric, k, n, n_ind=None):
    lo, hi = (float(v) for v in clopper_pearson(k, n))
    verdict = ""
    if metric == "false_positive_rate":
        verdict = "pass" if lo <= ALPHA and hi <= 2 * ALPHA else "fail"
    return dict(zip(SUMMARY_COLUMNS, ("benchmark", null, profile, effect, metric, k / n, lo, hi, n,
                                      float(n if n_ind is None else n_ind), ALPHA, verdict,
                                      FPR_RULE if verdict else "")))


def _summary(fpr_colored=(0, 200), fpr_white=((0, 200), (0, 200)), acc=None, outlier=None, pair=None):
    """FPR rows (colored on both profiles, white on white and gm), accuracy rows at 3 MDE:
    ``acc``/``outlier``/``pair`` are ``{profile: (k, n)}`` (default: all named, n 12)."""
    rows = [_row("colored", p, NONE, "false_positive_rate", *fpr_colored) for p in ("white", "gm")]
    rows += [_row("white", p, NONE, "false_positive_rate", *kn) for p, kn in zip(("white", "gm"), fpr_white)]
    for effect, table in (("quadratic", acc), (OUTLIER, outlier), ("quadratic+temperature", pair)):
        for p, (k, n) in (table or {"white": (12, 12), "gm": (12, 12)}).items():
            rows.append(_row("colored", p, effect, "accuracy_at_3mde", k, n))
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def _ledger(summary):
    led = DC.discrepancy_claims(summary, PROFILES, ADIS, alpha=ALPHA, power=POWER, nulls=("colored", "white"))
    return led.set_index("claim_id")


def test_testable_sample_sizes():
    n = np.arange(1, 60)
    ok, hi = DC.testable("power", n, power=POWER)
    assert n[ok].min() == 3 and hi[0] == pytest.approx(0.975)      # 0/2 -> 0.842 >= 0.8, 0/3 -> 0.708
    ok, hi = DC.testable("fpr_upper", n, alpha=ALPHA)
    assert n[ok].min() == 36 and hi[5] == pytest.approx(0.459, abs=1e-3)   # 0/35 -> 0.100003 > 0.1
    ok, lo = DC.testable("fpr_lower", n, alpha=ALPHA)
    assert n[ok].min() == 2 and lo[0] == pytest.approx(0.025)
    with pytest.raises(ValueError):
        DC.testable("nonsense", n)


def test_power_claims_at_one_recording_per_row_are_not_reproducible():
    """n 1, no success: the upper end 0.975 reaches the power, so the old rule said reproduced."""
    one = {"white": (0, 1), "gm": (0, 1)}
    led = _ledger(_summary(acc=one, outlier=one, pair=one))
    for cid in ("naming_at_3mde_every_profile", "outlier_pose_named", "two_effects_named"):
        r = led.loc[cid]
        assert r.verdict == "not_reproducible", r
        assert r.evidence == ("not testable at this scale: n 1 per row, the exact 95 % interval's upper end is 0.975 "
                              ">= power 0.8 even with no success")
        assert "not reproducible at this scale" in r.claim


def test_power_claims_decidable_rows_get_the_verdict_of_their_intervals():
    led = _ledger(_summary(acc={"white": (12, 12), "gm": (12, 12)}, outlier={"white": (12, 12), "gm": (2, 12)},
                           pair={"white": (0, 1), "gm": (12, 12)}))
    assert led.loc["naming_at_3mde_every_profile", "verdict"] == "reproduced"
    r = led.loc["outlier_pose_named"]                       # 2/12: upper end 0.48 < 0.8
    assert r.verdict == "not_reproduced" and "gm/outlier_pose 0.17" in r.evidence
    r = led.loc["two_effects_named"]                        # the n-1 row is left out, the n-12 one judged
    assert r.verdict == "reproduced" and r.reproduced_value == "min 1.00"
    assert "left out" in r.evidence and "white/quadratic+temperature (n 1)" in r.evidence
    # the left-out row cannot rescue a failing one either
    led = _ledger(_summary(pair={"white": (1, 1), "gm": (0, 12)}))
    assert led.loc["two_effects_named", "verdict"] == "not_reproduced"


def test_fpr_claims_at_six_recordings_are_not_reproducible():
    """0 of 6: the upper end 0.459 exceeds 2 alpha, so the old rule said not_reproduced whatever the loop did."""
    led = _ledger(_summary(fpr_colored=(0, 6), fpr_white=((0, 6), (6, 6))))
    for cid in ("fpr_colored_null_every_profile", "fpr_white_null_white_noise"):
        r = led.loc[cid]
        assert r.verdict == "not_reproducible", r
        assert r.evidence == ("not testable at this scale: n 6 per profile, the exact 95 % interval's upper end is "
                              "0.459 > 2 alpha 0.1 even with no false positive")
    # the lower-end rule is decidable at 6: 6/6 on the wander profile -> lower end 0.54 > alpha
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "reproduced"


def test_fpr_claims_decidable():
    led = _ledger(_summary(fpr_colored=(6, 200), fpr_white=((9, 200), (0, 200))))
    assert led.loc["fpr_colored_null_every_profile", "verdict"] == "reproduced"
    assert led.loc["fpr_white_null_white_noise", "verdict"] == "reproduced"
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "not_reproduced"   # 0/200 on gm
    led = _ledger(_summary(fpr_colored=(30, 200), fpr_white=((30, 200), (40, 200))))
    assert led.loc["fpr_colored_null_every_profile", "verdict"] == "not_reproduced"
    assert led.loc["fpr_white_null_white_noise", "verdict"] == "not_reproduced"
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "reproduced"
    # one recording on the wander profile: even 1/1 keeps the lower end at 0.025 <= alpha
    r = _ledger(_summary(fpr_white=((0, 200), (1, 1)))).loc["fpr_white_null_inflated_by_wander"]
    assert r.verdict == "not_reproducible" and "lower end is 0.025 <= alpha 0.05" in r.evidence


def test_sample_size_is_the_intervals_effective_one():
    """Real-noise windows shared by recordings: the interval's n is n_independent, and so is the test's."""
    s = _summary(fpr_colored=(0, 200))
    s.loc[(s.null == "colored") & (s.metric == "false_positive_rate"), "n_independent"] = 20.0
    r = _ledger(s).loc["fpr_colored_null_every_profile"]
    assert r.verdict == "not_reproducible" and "n 20 per profile" in r.evidence
