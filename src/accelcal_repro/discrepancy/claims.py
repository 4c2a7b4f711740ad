"""Claims-ledger rows of the discrepancy stage: the loop's goals, judged on the benchmark
and on the ADIS16405 reference (``paper = 'discrepancy'``).

Each row's rule is in its claim text; values come from the stage's tables
(results/discrepancy/benchmark/summary.csv, profiles.csv, results/discrepancy/adis/...),
never typed in.  A null hypothesis the library does not have yet makes its rows
``not_reproducible`` with that reason.

The benchmark's rules judge exact (Clopper–Pearson) 95 % intervals, and at a small number
of recordings a rule may be unable to give one of its verdicts whatever the data: the upper
end with no success of 1 is 0.975, which reaches a power of 0.8 (a power rule that cannot
fail), and with no false positive of 6 it is 0.459, above 2α = 0.1 (a false-positive rule
that cannot pass).  Each rule therefore first asks, from a row's sample size alone (its
``n_independent``, the size its interval was computed on), whether the extreme outcome
could still give the other verdict (:func:`testable`); rows where it could not are left out
of the judgement and counted in the evidence, and a claim with no row left is
``not_reproducible`` with the sample size and the interval in its reason.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..claims import COLUMNS, Claim, validate_rows
from .benchmark import NONE, OUTLIER
from .scoring import clopper_pearson

SUMMARY = "results/discrepancy/benchmark/summary.csv"
ADIS_CHECK = "results/discrepancy/adis/session_check_summary.csv"

FPR_COLORED = Claim(
    "discrepancy", "fpr_colored_null_every_profile",
    "Goal: under every noise profile of the benchmark (white, rounding, Gauss-Markov, flicker, "
    "random walk, the Xsens and ADIS16405 fits and the ADIS16405 record itself), the loop with the colored null "
    "names an effect or outlier on at most alpha of effect-free sessions: reproduced iff for every profile the "
    "exact 95% interval reaches down to alpha and its upper end is at most 2 alpha (profiles with too few "
    "recordings for that, where the upper end exceeds 2 alpha even with no false positive, are left out; with none "
    "left the claim is not reproducible at this scale)",
    "FPR <= alpha, upper bound <= 2 alpha")
FPR_WHITE = Claim(
    "discrepancy", "fpr_white_null_inflated_by_wander",
    "Negative control: the loop with the white-noise null names an effect on more than alpha "
    "of effect-free sessions whose noise has slow wander: reproduced iff on at least one wander profile the lower "
    "end of the exact 95% interval of its false-positive rate exceeds alpha (profiles with too few recordings for "
    "that, where the lower end stays at or below alpha even if every recording is a false positive, are left out; "
    "with none left the claim is not reproducible at this scale)",
    "2 of 5 effect-free recordings named bias_drift")
FPR_WHITE_WHITE = Claim(
    "discrepancy", "fpr_white_null_white_noise",
    "On white noise the loop with the white null keeps its false-positive rate at alpha: reproduced iff "
    "the exact 95% interval on the white profile reaches down to alpha and its upper end is at most 2 alpha (not "
    "reproducible at this scale when the upper end exceeds 2 alpha even with no false positive)",
    "FPR <= alpha")
NAMING = Claim(
    "discrepancy", "naming_at_3mde_every_profile",
    "Goal: each effect hidden at 3 times its oracle minimum detectable effect is named first by the "
    "colored-null loop with the design power under every noise profile: reproduced iff for every (profile, "
    "effect) the upper end of the exact 95% interval of the naming accuracy at 3 MDE is at least the power (rows "
    "with too few recordings for the rule to fail, where the upper end reaches the power even with no success, "
    "are left out; with none left the claim is not reproducible at this scale)",
    "power at >= 1 MDE")
OUTLIERS = Claim(
    "discrepancy", "outlier_pose_named",
    "Goal: one pose shifted by 3 times the minimum detectable shift is named outlier_pose at its "
    "pose under every noise profile (colored null): reproduced iff the upper end of the exact 95% interval of that "
    "accuracy is at least the power for every profile (profiles with too few recordings for the rule to fail, "
    "where the upper end reaches the power even with no success, are left out; with none left the claim is not "
    "reproducible at this scale)",
    "named with the pose index")
PAIRS = Claim(
    "discrepancy", "two_effects_named",
    "Goal: two effects hidden at once, each at 3 times its oracle MDE, are both named (in any order, "
    "nothing else) under every noise profile (colored null): reproduced iff the upper end of the exact 95% "
    "interval of that accuracy is at least the power for every profile and pair (rows with too few recordings "
    "for the rule to fail, where the upper end reaches the power even with no success, are left out; with none "
    "left the claim is not reproducible at this scale)",
    "both named")
ADIS_REFERENCE = Claim(
    "discrepancy", "adis_long_tau_terms_predict_wander",
    "Reference for slow bias wander: the stochastic layer's long-tau noise terms, fitted to the Allan deviation of the "
    "2.78 h ADIS16405 record on tau >= 1 s, predict the slow wander of the pose means of calibration-shaped pieces "
    "of the same record: reproduced iff the predicted scatter of the pose means about their session mean (variance, "
    "pooled over axes) lies in the 95% interval of the observed one",
    "the reference for slow bias wander")
ADIS_SHORT = Claim(
    "discrepancy", "short_rests_overpredict_wander",
    "Noise terms named from calibration-length rests (<= 10 s) over-predict the pose-residual excess "
    "(Xsens: 4.28 vs 2.91): reproduced iff, on session-shaped pieces of the ADIS16405 record, the stochastic "
    "layer run on the pieces' own rests predicts a scatter of the pose means above the upper end of the 95% "
    "interval of the observed one",
    "4.28 vs 2.91 (Xsens)")


STABILITY = Claim(
    "batista2011", "sec6b_stability_public_sessions",
    "Sec. VI-B, tested on public sessions of one IMU (IMU-TK fork, data2/3/4): over sessions, scale and "
    "cross-axis terms do not change significantly while the bias changes: reproduced iff every scale factor and "
    "non-orthogonality angle is consistent across the sessions (Cochran's Q on the base model's estimates with "
    "the larger of the rests' and the residuals' standard errors, Holm over the 9 parameters, level alpha) and at "
    "least one bias component is not",
    "qualitative (their unit, tests on different days)")
SESSIONS = "results/discrepancy/sessions/stability.csv"
GAPS = "results/discrepancy/sessions/gaps.csv"
XSENS_GAP = Claim(
    "discrepancy", "xsens_gap_closed",
    "On the Xsens session the pose residuals are 2.5-2.9 times what white noise predicts and the loop "
    "must say what the excess is: reproduced iff the joint model's predicted excess interval contains the observed "
    "one and the session re-simulated with what the loop names puts the measured excess inside the central 95% of "
    "its re-simulated excesses, while the re-simulation before (white noise of the rests) does not",
    "2.5-2.9x, not explained by the rests' terms")


def _xsens_row(excess: pd.DataFrame | None, gaps: pd.DataFrame | None) -> dict:
    if excess is None or gaps is None or not (excess.recording == "xsens_mti").any():
        return XSENS_GAP.not_reproducible("xsens_mti is not in discrepancy.recordings")
    e = excess[excess.recording == "xsens_mti"].iloc[0]
    g = gaps[gaps.recording == "xsens_mti"].set_index("model")
    if not {"before", "after"} <= set(g.index):
        return XSENS_GAP.not_reproducible("the Xsens session was not re-simulated")
    inside = bool(e.excess_predicted_ci_low <= e.excess_observed <= e.excess_predicted_ci_high)
    q_after, q_before = float(g.loc["after", "excess_measured_quantile"]), float(g.loc["before", "excess_measured_quantile"])
    ok = inside and 0.025 <= q_after <= 0.975 and not 0.025 <= q_before <= 0.975
    return XSENS_GAP.judge(float(e.excess_predicted), passed=ok, fmt="predicted excess {:.2f}",
                           evidence=f"{GAPS}: observed excess (excess.csv beside it) {e.excess_observed:.2f}, joint model "
                                    f"{e.excess_predicted:.2f} [{e.excess_predicted_ci_low:.2f}, "
                                    f"{e.excess_predicted_ci_high:.2f}]; re-simulated before: measured at quantile "
                                    f"{q_before:.2f}, RMS ratio {g.loc['before', 'rms_ratio']:.2f}, KS "
                                    f"{g.loc['before', 'ks_distance']:.2f}; after: quantile {q_after:.2f}, RMS ratio "
                                    f"{g.loc['after', 'rms_ratio']:.2f}, KS {g.loc['after', 'ks_distance']:.2f}")


def _stability_row(stability: pd.DataFrame | None) -> dict:
    if stability is None or not len(stability):
        return STABILITY.not_reproducible("no group of sessions of one IMU configured (discrepancy.sessions.same_imu)")
    alt = stability[stability.yardstick == "se_scaled"].set_index("parameter")
    st = stability[stability.yardstick == "se"].set_index("parameter")
    scale = [p for p in st.index if p.startswith(("s_", "theta_"))]
    bias = [p for p in st.index if p.startswith("b_")]
    moved_bias = [p for p in bias if not bool(st.loc[p, "stable"])]
    moved_other = [p for p in scale if not bool(st.loc[p, "stable"])]
    ok = not moved_other and bool(moved_bias)
    return STABILITY.judge(len(moved_other), passed=ok, fmt="{:.0f} scale/angle parameters moved",
                           evidence=f"{SESSIONS}: not stable (Holm-adjusted p < alpha): "
                                    f"{', '.join(moved_bias + moved_other) or 'none'}; bias spread "
                                    + ", ".join(f"{p} {st.loc[p, 'spread']:.3g} ({st.loc[p, 'spread_over_se']:.1f} se)"
                                                for p in bias)
                                    + "; yardstick: the rests' noise inflated by any excess (the residual scatter alone "
                                    f"would call not stable: {', '.join(p for p in alt.index if not bool(alt.loc[p, 'stable'])) or 'none'})")


def _fpr(summary, null):
    return summary[(summary.null == null) & (summary.metric == "false_positive_rate")]


def _unavailable(claim: Claim, null: str) -> dict:
    return claim.not_reproducible(f"the {null} null was not run: this library's discrepancy loop does not have it "
                                  f"yet (benchmark.nulls)")


def sample_sizes(d: pd.DataFrame) -> np.ndarray:
    """The sample size each summary row's interval was computed on: ``n_independent`` (Kish's
    effective size, :func:`accelcal_repro.discrepancy.scoring.effective_n`) where given, else ``n``."""
    n = pd.to_numeric(d["n"], errors="coerce").to_numpy(float)
    if "n_independent" in d:
        ni = pd.to_numeric(d["n_independent"], errors="coerce").to_numpy(float)
        n = np.where(np.isfinite(ni) & (ni > 0), ni, n)
    return n


#: The rules of the benchmark's claims, by what they compare (module docstring).
RULES = ("power", "fpr_upper", "fpr_lower")


def testable(rule: str, n, *, alpha: float = 0.05, power: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
    """Can a row of sample size ``n`` give both verdicts of ``rule``?  ``(mask, bound)``.

    ``power`` (pass iff the upper end of the exact 95 % interval ≥ ``power``): only if no
    success of ``n`` puts the upper end below the power (``bound``: that upper end);
    ``fpr_upper`` (pass needs the upper end ≤ 2α): only if no false positive of ``n`` puts
    it at or below 2α (``bound``: that upper end); ``fpr_lower`` (pass iff the lower end
    > α): only if ``n`` false positives of ``n`` put it above α (``bound``: that lower end).
    The other verdict is reachable at any ``n ≥ 1`` (``n`` successes reach any power, ``n``
    false positives push the upper end to 1, none keep the lower end at 0).
    """
    n = np.asarray(n, float)
    if rule == "power":
        bound = clopper_pearson(np.zeros_like(n), n)[1]
        ok = bound < power
    elif rule == "fpr_upper":
        bound = clopper_pearson(np.zeros_like(n), n)[1]
        ok = bound <= 2 * alpha
    elif rule == "fpr_lower":
        bound = clopper_pearson(n, n)[0]
        ok = bound > alpha
    else:
        raise ValueError(f"unknown rule {rule!r} (known: {', '.join(RULES)})")
    return np.asarray(ok & (n >= 1), bool), bound


def _n_text(n: np.ndarray) -> str:
    lo, hi = float(np.min(n)), float(np.max(n))
    return f"{hi:g}" if lo == hi else f"{lo:g}-{hi:g}"


def _not_testable(claim: Claim, rule: str, n: np.ndarray, bound: np.ndarray, *, alpha: float, power: float,
                  per: str) -> dict:
    """The ``not_reproducible`` row of a claim none of whose rows is :func:`testable` (the bound
    shown is the most favourable one, at the largest ``n``)."""
    b = float(bound[int(np.argmax(n))])
    head = f"not testable at this scale: n {_n_text(n)} per {per}, the exact 95 % interval's"
    if rule == "power":
        why = f"upper end is {b:.3f} >= power {power:g} even with no success"
    elif rule == "fpr_upper":
        why = f"upper end is {b:.3f} > 2 alpha {2 * alpha:g} even with no false positive"
    else:
        why = f"lower end is {b:.3f} <= alpha {alpha:g} even if every recording is a false positive"
    return claim.not_reproducible(f"{head} {why}")


def _left_out(d: pd.DataFrame, keep: np.ndarray, n: np.ndarray, what: str) -> str:
    if keep.all():
        return ""
    gone = [f"{r.profile}{'' if r.effect == NONE else '/' + r.effect} (n {k:g})"
            for r, k, ok in zip(d.itertuples(), n, keep) if not ok]
    return f"; left out, not testable at their n ({what}): {len(gone)}: {', '.join(gone)}"


def _fpr_rows(summary, profiles_table, alpha, nulls) -> list[dict]:
    rows = []
    fc = _fpr(summary, "colored")
    if "colored" not in nulls or not len(fc):
        rows.append(_unavailable(FPR_COLORED, "colored"))
    else:
        n_all = sample_sizes(fc)
        keep, bound = testable("fpr_upper", n_all, alpha=alpha)
        if not keep.any():
            rows.append(_not_testable(FPR_COLORED, "fpr_upper", n_all, bound, alpha=alpha, power=np.nan,
                                      per="profile"))
        else:
            out = _left_out(fc, keep, n_all, "upper end above 2 alpha with no false positive")
            fc = fc[keep]
            bad = fc[fc.verdict != "pass"]
            worst = fc.loc[fc.ci_high.idxmax()]
            rows.append(FPR_COLORED.judge(
                float(fc.value.max()), passed=len(bad) == 0, fmt="max {:.3f}",
                evidence=f"{SUMMARY}: {len(fc) - len(bad)}/{len(fc)} profiles pass; highest rate {fc.value.max():.3f} "
                         f"({fc.loc[fc.value.idxmax(), 'profile']}); highest upper bound {worst.ci_high:.3f} "
                         f"({worst.profile}); failing: {', '.join(f'{r.profile} {r.value:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]' for r in bad.itertuples()) or 'none'}"
                         + out))
    fw = _fpr(summary, "white")
    if "white" not in nulls or not len(fw):
        rows += [_unavailable(FPR_WHITE, "white"), _unavailable(FPR_WHITE_WHITE, "white")]
        return rows
    kinds = profiles_table.groupby("profile")["wander_over_white"].mean()
    wander = fw[fw.profile.map(lambda p: kinds.get(p, 0.0) > 0.05)]
    n_w = sample_sizes(wander)
    keep, bound = testable("fpr_lower", n_w, alpha=alpha)
    if len(wander) and not keep.any():
        rows.append(_not_testable(FPR_WHITE, "fpr_lower", n_w, bound, alpha=alpha, power=np.nan,
                                  per="wander profile"))
    else:
        out = _left_out(wander, keep, n_w, "lower end at or below alpha with every recording a false positive")
        wander = wander[keep]
        inflated = wander[wander.ci_low > alpha]
        top = wander.loc[wander.value.idxmax()] if len(wander) else None
        rows.append(FPR_WHITE.judge(
            float(top.value) if top is not None else float("nan"), passed=len(inflated) > 0, fmt="max {:.3f}",
            evidence=f"{SUMMARY}: white null, {len(inflated)}/{len(wander)} wander profiles with the interval above "
                     f"alpha: {', '.join(f'{r.profile} {r.value:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]' for r in inflated.itertuples()) or 'none'}"
                     + out))
    ww = fw[fw.profile == "white"]
    if len(ww):
        r = ww.iloc[0]
        n_ww = sample_sizes(ww.iloc[:1])
        keep, bound = testable("fpr_upper", n_ww, alpha=alpha)
        if not keep[0]:
            rows.append(_not_testable(FPR_WHITE_WHITE, "fpr_upper", n_ww, bound, alpha=alpha, power=np.nan,
                                      per="profile"))
        else:
            rows.append(FPR_WHITE_WHITE.judge(r.value, passed=r.verdict == "pass", fmt="{:.3f}",
                                              evidence=f"{SUMMARY}: white profile, white null: {r.value:.3f} "
                                                       f"[{r.ci_low:.3f}, {r.ci_high:.3f}], n {int(r.n)}"))
    else:
        rows.append(FPR_WHITE_WHITE.not_reproducible("no white profile in the benchmark"))
    return rows


def _accuracy_rows(summary, power, nulls) -> list[dict]:
    if "colored" not in nulls or not len(summary[summary.null == "colored"]):
        return [_unavailable(c, "colored") for c in (NAMING, OUTLIERS, PAIRS)]
    s = summary[summary.null == "colored"]
    out = []
    for claim, sel in ((NAMING, ~s.effect.isin((NONE, OUTLIER)) & ~s.effect.str.contains("+", regex=False)
                        & ~s.effect.str.endswith("_const")),
                       (OUTLIERS, s.effect == OUTLIER), (PAIRS, s.effect.str.contains("+", regex=False))):
        d = s[sel & (s.metric == "accuracy_at_3mde")]
        if not len(d):
            out.append(claim.not_reproducible("no such rows at 3 MDE in the benchmark config"))
            continue
        n_all = sample_sizes(d)
        keep, bound = testable("power", n_all, power=power)
        if not keep.any():
            out.append(_not_testable(claim, "power", n_all, bound, alpha=np.nan, power=power, per="row"))
            continue
        gone = _left_out(d, keep, n_all, "upper end at or above the power with no success")
        d = d[keep]
        bad = d[d.ci_high < power]
        worst = d.loc[d.value.idxmin()]
        out.append(claim.judge(float(d.value.min()), passed=len(bad) == 0, fmt="min {:.2f}",
                               evidence=f"{SUMMARY}: accuracy_at_3mde, {len(d) - len(bad)}/{len(d)} (profile, row) "
                                        f"reach the power; lowest {worst.value:.2f} ({worst.profile}, {worst.effect}, "
                                        f"n {int(worst.n)}); below: {', '.join(f'{r.profile}/{r.effect} {r.value:.2f}' for r in bad.itertuples()) or 'none'}"
                                        + gone))
    return out


def _adis_rows(check: pd.DataFrame) -> list[dict]:
    a = check[check.axis == "all"].iloc[0]
    lo, hi, obs = float(a.observed_ci_low), float(a.observed_ci_high), float(a.observed_var)
    ref = float(a.reference_var)
    rows = [ADIS_REFERENCE.judge(ref / obs, passed=lo <= ref <= hi, fmt="predicted/observed {:.2f}",
                                 evidence=f"{ADIS_CHECK}: {int(a.pieces)} pieces, observed pose-mean scatter (variance "
                                          f"about the session mean) {obs:.3g} [{lo:.3g}, {hi:.3g}] (m/s^2)^2, reference "
                                          f"model {ref:.3g}, its white term alone {a.reference_white_var:.3g}; excess "
                                          f"over the calibration's standard errors {a.excess_observed:.2f}")]
    if "layer_var" in check and np.isfinite(a.get("layer_var", np.nan)):
        lay = float(a.layer_var)
        rows.append(ADIS_SHORT.judge(lay / obs, passed=lay > hi, fmt="predicted/observed {:.1f}",
                                     evidence=f"{ADIS_CHECK}: stochastic layer on the rests of {int(a.layer_pieces)} "
                                              f"pieces (named {a.layer_terms}): {lay:.3g} vs observed {obs:.3g} "
                                              f"[{lo:.3g}, {hi:.3g}]"))
    else:
        rows.append(ADIS_SHORT.not_reproducible("the stochastic layer was run on no piece (adis.layer_pieces = 0)"))
    return rows


def discrepancy_claims(summary: pd.DataFrame, profiles_table: pd.DataFrame, adis_check: pd.DataFrame, *,
                       alpha: float, power: float, nulls, stability: pd.DataFrame | None = None,
                       excess: pd.DataFrame | None = None, gaps: pd.DataFrame | None = None) -> pd.DataFrame:
    """Ledger rows (:data:`accelcal_repro.claims.COLUMNS`) of the discrepancy stage."""
    rows = _fpr_rows(summary, profiles_table, alpha, nulls) + _accuracy_rows(summary, power, nulls)
    rows += _adis_rows(adis_check)
    rows.append(_xsens_row(excess, gaps))
    rows.append(_stability_row(stability))
    return validate_rows(pd.DataFrame(rows, columns=list(COLUMNS)), source="discrepancy claims")


__all__ = ["RULES", "discrepancy_claims", "sample_sizes", "testable"]
