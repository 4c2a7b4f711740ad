"""Claims of the discrepancy stage judged on small summary tables: a rule that cannot give
one of its verdicts at the table's sample size makes its claim not_testable_at_this_scale
(with the n it has and needs in the evidence); a rule that can gives the verdict the
intervals say, and can fail."""

import inspect

import numpy as np
import pandas as pd
import pytest

from accelcal.discrepancy import stochastic_layer
from accelcal_repro.claims import NOT_TESTABLE
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


def _summary(fpr_colored=(0, 280), fpr_white=((0, 200), (0, 200)), acc=None, outlier=None, pair=None):
    """FPR rows (wander null on both profiles, white on white and gm), accuracy rows at 3 MDE:
    ``acc``/``outlier``/``pair`` are ``{profile: (k, n)}`` (default: all named, n 12)."""
    rows = [_row("wander", p, NONE, "false_positive_rate", *fpr_colored) for p in ("white", "gm")]
    rows += [_row("white", p, NONE, "false_positive_rate", *kn) for p, kn in zip(("white", "gm"), fpr_white)]
    for effect, table in (("quadratic", acc), (OUTLIER, outlier), ("quadratic+temperature", pair)):
        for p, (k, n) in (table or {"white": (12, 12), "gm": (12, 12)}).items():
            rows.append(_row("wander", p, effect, "accuracy_at_3mde", k, n))
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def _ledger(summary, **kw):
    led = DC.discrepancy_claims(summary, PROFILES, kw.pop("adis", ADIS), alpha=ALPHA, power=POWER,
                                nulls=("wander", "white"), **kw)
    return led.set_index("claim_id")


def test_testable_sample_sizes():
    assert [DC.minimum(r, alpha=ALPHA, power=POWER).needed for r in DC.RULES] == [3, 36, 2, 280]
    for rule in DC.RULES:  # for whole n, exactly n >= the rule's minimum
        n = np.arange(1, 60)
        assert np.array_equal(DC.testable(rule, n, alpha=ALPHA, power=POWER)[0],
                              n >= DC.minimum(rule, alpha=ALPHA, power=POWER).needed)
    n = np.arange(1, 60)
    ok, hi = DC.testable("power", n, power=POWER)
    assert n[ok].min() == 3 and hi[0] == pytest.approx(0.975)      # 0/2 -> 0.842 >= 0.8, 0/3 -> 0.708
    ok, hi = DC.testable("fpr_upper", n, alpha=ALPHA)
    assert n[ok].min() == 36 and hi[5] == pytest.approx(0.459, abs=1e-3)   # 0/35 -> 0.100003 > 0.1
    ok, lo = DC.testable("fpr_lower", n, alpha=ALPHA)
    assert n[ok].min() == 2 and lo[0] == pytest.approx(0.025)
    with pytest.raises(ValueError):
        DC.testable("nonsense", n)


def test_fpr_sessions_decided_by_the_loop():
    """The wander null's rule needs enough sessions that a sound loop (true rate 0.035) fails it
    with probability below 1 %: 280 at alpha 0.05 (279 gives 0.0102, 200 gives 0.050; 255 is
    below 1 % but 258 is not: the exact interval's steps), checked against Clopper-Pearson
    directly and by simulation."""
    assert DC.fpr_sessions_needed(ALPHA) == 280 and "280 sessions" in DC.FPR_COLORED.claim
    p = DC.fpr_fail_probability([200, 255, 258, 279, 280, 400], ALPHA)
    assert p[0] == pytest.approx(0.0502, abs=1e-3) and p[1] < 0.01 < p[2] and p[3] > 0.01 > p[4] > p[5]
    k = np.random.default_rng(1).binomial(280, 0.035, 200_000)
    lo, hi = clopper_pearson(k, 280)
    assert np.mean((lo > ALPHA) | (hi > 2 * ALPHA)) == pytest.approx(p[4], abs=1e-3)
    ok, bound = DC.testable("fpr_decided", [279.0, 279.5, 280.0], alpha=ALPHA)
    assert ok.tolist() == [False, False, True] and bound[0] == pytest.approx(p[3])


def test_power_claims_at_one_recording_per_row_are_not_testable():
    """n 1, no success: the upper end 0.975 reaches the power, so the rule without a minimum said reproduced."""
    one = {"white": (0, 1), "gm": (0, 1)}
    led = _ledger(_summary(acc=one, outlier=one, pair=one))
    for cid in ("naming_at_3mde_every_profile", "outlier_pose_named", "two_effects_named"):
        r = led.loc[cid]
        assert r.verdict == NOT_TESTABLE, r
        assert r.evidence.startswith("results/discrepancy/benchmark/summary.csv: not testable at this scale: n 1 "
                                     "(recordings per row), needs n >= 3: with fewer, the exact 95 % interval's upper "
                                     "end reaches the power 0.8 even with no success"), r.evidence
        assert "(upper end 0.975 at the largest such n): white/" in r.evidence
        assert r.reproduced_value == "min 0.00" and "not testable at this scale" in r.claim
    # two recordings: 0/2 still reaches 0.842; three: 0/3 gives 0.708 and the rule fails
    two, three = {"white": (0, 2), "gm": (0, 2)}, {"white": (0, 3), "gm": (0, 3)}
    assert _ledger(_summary(outlier=two)).loc["outlier_pose_named", "verdict"] == NOT_TESTABLE
    assert _ledger(_summary(outlier=three)).loc["outlier_pose_named", "verdict"] == "not_reproduced"


def test_power_claims_decidable_rows_get_the_verdict_of_their_intervals():
    led = _ledger(_summary(acc={"white": (12, 12), "gm": (12, 12)}, outlier={"white": (12, 12), "gm": (2, 12)},
                           pair={"white": (0, 1), "gm": (12, 12)}))
    assert led.loc["naming_at_3mde_every_profile", "verdict"] == "reproduced"
    r = led.loc["outlier_pose_named"]                       # 2/12: upper end 0.48 < 0.8
    assert r.verdict == "not_reproduced" and "gm/outlier_pose 0.17" in r.evidence
    r = led.loc["two_effects_named"]    # the n-12 row passes, but the n-1 row could still fail at a larger n
    assert r.verdict == NOT_TESTABLE and r.reproduced_value == "min 0.00"
    assert "white/quadratic+temperature (n 1)" in r.evidence
    # a testable row that fails decides a claim over every row, whatever the untestable ones
    r = _ledger(_summary(pair={"white": (1, 1), "gm": (0, 12)})).loc["two_effects_named"]
    assert r.verdict == "not_reproduced" and "decided by the others: white/quadratic+temperature (n 1)" in r.evidence


def test_fpr_claims_at_six_recordings_are_not_testable():
    """0 of 6: the upper end 0.459 exceeds 2 alpha, so the rule without a minimum said not_reproduced whatever
    the loop did; 0 of 36 reaches 0.097 and the rule passes, 2 of 36 fails it."""
    led = _ledger(_summary(fpr_colored=(0, 6), fpr_white=((0, 6), (6, 6))))
    for cid in ("fpr_colored_null_every_profile", "fpr_white_null_white_noise"):
        r = led.loc[cid]
        assert r.verdict == NOT_TESTABLE, r
        needs = ("needs n >= 280: with fewer, a loop whose true rate is 0.035 fails the rule with probability 0.01 or"
                 if cid.startswith("fpr_colored") else "needs n >= 36: with fewer, the exact 95 % interval's upper "
                                                        "end exceeds 0.1 even with no event")
        assert f"not testable at this scale: n 6 (recordings per profile), {needs}" in r.evidence, r.evidence
        assert ("(chance that a sound loop fails 1.000 at the largest such n)" if cid.startswith("fpr_colored")
                else "(upper end 0.459 at the largest such n)") in r.evidence
    # the lower-end rule is decidable at 6: 6/6 on the wander profile -> lower end 0.54 > alpha
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "reproduced"
    led = _ledger(_summary(fpr_colored=(0, 35), fpr_white=((0, 36), (0, 36))))
    assert led.loc["fpr_colored_null_every_profile", "verdict"] == NOT_TESTABLE
    assert led.loc["fpr_white_null_white_noise", "verdict"] == "reproduced"
    # the wander null's rule asks for the sessions that let the loop, not sampling noise, decide
    r = _ledger(_summary(fpr_colored=(2, 36))).loc["fpr_colored_null_every_profile"]
    assert r.verdict == NOT_TESTABLE and "needs n >= 280" in r.evidence
    assert _ledger(_summary(fpr_colored=(30, 280))).loc["fpr_colored_null_every_profile",
                                                        "verdict"] == "not_reproduced"


def test_fpr_claims_decidable():
    led = _ledger(_summary(fpr_colored=(9, 280), fpr_white=((9, 200), (0, 200))))
    assert led.loc["fpr_colored_null_every_profile", "verdict"] == "reproduced"
    assert led.loc["fpr_white_null_white_noise", "verdict"] == "reproduced"
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "not_reproduced"   # 0/200 on gm
    led = _ledger(_summary(fpr_colored=(30, 280), fpr_white=((30, 200), (40, 200))))
    assert led.loc["fpr_colored_null_every_profile", "verdict"] == "not_reproduced"
    assert led.loc["fpr_white_null_white_noise", "verdict"] == "not_reproduced"
    assert led.loc["fpr_white_null_inflated_by_wander", "verdict"] == "reproduced"
    # one recording on the wander profile: even 1/1 keeps the lower end at 0.025 <= alpha
    r = _ledger(_summary(fpr_white=((0, 200), (1, 1)))).loc["fpr_white_null_inflated_by_wander"]
    assert r.verdict == NOT_TESTABLE and "(lower end 0.025 at the largest such n): gm (n 1)" in r.evidence
    assert "needs n >= 2" in r.evidence
    # 2 of 2 lifts the lower end to 0.158 > alpha: testable from n 2, and 0 of 2 fails it
    assert _ledger(_summary(fpr_white=((0, 200), (2, 2)))).loc["fpr_white_null_inflated_by_wander",
                                                                "verdict"] == "reproduced"
    assert _ledger(_summary(fpr_white=((0, 200), (0, 2)))).loc["fpr_white_null_inflated_by_wander",
                                                                "verdict"] == "not_reproduced"


def test_sample_size_is_the_intervals_effective_one():
    """Real-noise windows shared by recordings: the interval's n is n_independent, and so is the test's."""
    s = _summary(fpr_colored=(0, 576))
    s.loc[(s.null == "wander") & (s.metric == "false_positive_rate"), "n_independent"] = 200.0
    r = _ledger(s).loc["fpr_colored_null_every_profile"]
    assert r.verdict == NOT_TESTABLE and "n 200 (recordings per profile)" in r.evidence
    # an effective size between whole numbers: exact (0 of 35.2 puts the upper end at 0.0995 <= 0.1)
    assert DC.testable("fpr_upper", [35.0, 35.2], alpha=ALPHA)[0].tolist() == [False, True]
    s.loc[(s.null == "wander") & (s.metric == "false_positive_rate"), "n_independent"] = 480.5
    assert _ledger(s).loc["fpr_colored_null_every_profile", "verdict"] == "reproduced"


def test_a_claim_over_some_profile_is_decided_by_one_testable_pass():
    """fpr_white_null_inflated_by_wander asks for at least one wander profile above alpha: a
    testable one that passes decides it; with the only testable one failing, the untestable one
    could still pass at a larger scale."""
    profiles = pd.DataFrame({"profile": ["white", "gm", "rw"], "wander_over_white": [0.0, 1.0, 1.0]})
    base = _summary()
    for gm, rw, verdict in (((6, 6), (1, 1), "reproduced"), ((0, 6), (1, 1), NOT_TESTABLE),
                            ((0, 6), (0, 6), "not_reproduced")):
        rows = [_row("white", "rw", NONE, "false_positive_rate", *rw)]
        s = pd.concat([base, pd.DataFrame(rows, columns=SUMMARY_COLUMNS)], ignore_index=True)
        s.loc[(s.null == "white") & (s.profile == "gm") & (s.metric == "false_positive_rate"),
              ["value", "ci_low", "ci_high", "n", "n_independent"]] = (
            [gm[0] / gm[1], *map(float, clopper_pearson(*gm)), gm[1], float(gm[1])])
        led = DC.discrepancy_claims(s, profiles, ADIS, alpha=ALPHA, power=POWER, nulls=("wander", "white"))
        assert led.set_index("claim_id").loc["fpr_white_null_inflated_by_wander", "verdict"] == verdict, (gm, rw)


def _adis(pieces=10, layer_pieces=1, layer_var=4.0):
    return ADIS.assign(pieces=pieces, layer_pieces=layer_pieces, layer_var=layer_var, layer_terms="none")


def test_adis_rules_need_two_pieces_and_a_bootstrap_that_can_name_a_term():
    led = _ledger(_summary(), adis=_adis(pieces=1, layer_var=2.5), layer_n_boot=19)
    r = led.loc["adis_long_tau_terms_predict_wander"]
    assert r.verdict == NOT_TESTABLE and "n 1 (pieces of the record), needs n >= 2" in r.evidence
    r = led.loc["short_rests_overpredict_wander"]   # 19 sets: the smallest p-value 1/20 is not below 0.05
    assert r.verdict == NOT_TESTABLE and "n 19 (bootstrap sets of the stochastic layer), needs n >= 20" in r.evidence
    led = _ledger(_summary(), adis=_adis(pieces=2, layer_var=2.5), layer_n_boot=20)
    assert led.loc["adis_long_tau_terms_predict_wander", "verdict"] == "reproduced"      # 2.0 in [1, 3]
    assert led.loc["short_rests_overpredict_wander", "verdict"] == "not_reproduced"       # 2.5 not above 3
    led = _ledger(_summary(), adis=_adis(pieces=2, layer_var=4.0).assign(reference_var=5.0), layer_n_boot=20)
    assert led.loc["adis_long_tau_terms_predict_wander", "verdict"] == "not_reproduced"
    assert led.loc["short_rests_overpredict_wander", "verdict"] == "reproduced"
    assert _ledger(_summary(), adis=_adis(layer_pieces=0), layer_n_boot=199).loc[
        "short_rests_overpredict_wander", "verdict"] == NOT_TESTABLE


def test_layer_alpha_is_the_stochastic_layers_default():
    """The ADIS check runs the layer at its default alpha; the claim's minimum uses the same."""
    assert DC.LAYER_ALPHA == inspect.signature(stochastic_layer).parameters["alpha"].default


EXCESS = pd.DataFrame([{"recording": "xsens_mti", "excess_observed": 2.9, "excess_predicted": 3.0,
                        "excess_predicted_ci_low": 1.9, "excess_predicted_ci_high": 4.0}])


def _gaps(replicates, q_before=1.0, q_after=0.4):
    return pd.DataFrame([{"recording": "xsens_mti", "model": m, "replicates": replicates,
                          "excess_measured_quantile": q, "rms_ratio": 1.0, "ks_distance": 0.1}
                         for m, q in (("before", q_before), ("after", q_after))])


def test_xsens_gap_needs_re_simulations_that_resolve_a_central_95_percent():
    """With 5 re-simulations, 'beyond all of them' (quantile 1) passes for 'outside the central
    95 %' though it happens with probability 1/3 under the model: not testable below 39."""
    r = _ledger(_summary(), excess=EXCESS, gaps=_gaps(5)).loc["xsens_gap_closed"]
    assert r.verdict == NOT_TESTABLE and "n 5 (re-simulations per model), needs n >= 39" in r.evidence
    assert _ledger(_summary(), excess=EXCESS, gaps=_gaps(38)).loc["xsens_gap_closed", "verdict"] == NOT_TESTABLE
    assert _ledger(_summary(), excess=EXCESS, gaps=_gaps(39)).loc["xsens_gap_closed", "verdict"] == "reproduced"
    bad = _ledger(_summary(), excess=EXCESS, gaps=_gaps(39, q_before=0.5)).loc["xsens_gap_closed"]
    assert bad.verdict == "not_reproduced"


def _stability(sessions, moved=("b_z",)):
    params = ["b_x", "b_y", "b_z", "s_x", "s_y", "s_z", "theta_xy", "theta_xz", "theta_yz"]
    return pd.DataFrame([{"parameter": p, "sessions": sessions, "stable": p not in moved, "spread": 0.1,
                          "spread_over_se": 1.0, "yardstick": y} for y in ("se", "se_scaled") for p in params])


def test_stability_needs_two_sessions_and_can_fail():
    r = _ledger(_summary(), stability=_stability(1)).loc["sec6b_stability_public_sessions"]
    assert r.verdict == NOT_TESTABLE and "n 1 (sessions of the IMU), needs n >= 2" in r.evidence
    led = _ledger(_summary(), stability=_stability(2))
    assert led.loc["sec6b_stability_public_sessions", "verdict"] == "reproduced"
    led = _ledger(_summary(), stability=_stability(2, moved=("b_z", "s_x")))
    assert led.loc["sec6b_stability_public_sessions", "verdict"] == "not_reproduced"
