"""Claims-ledger rows of the discrepancy stage: the loop's goals, judged on the benchmark
and on the ADIS16405 reference (``paper = 'discrepancy'``).

Each row's rule is in its claim text; values come from the stage's tables
(results/discrepancy/benchmark/summary.csv, profiles.csv, results/discrepancy/adis/...),
never typed in.  A null hypothesis the library does not have yet makes its rows
``not_reproducible`` with that reason.

Every rule first asks whether its sample can give both of its verdicts
(:class:`accelcal_repro.claims.MinimumSample`).  The benchmark's rules judge exact
(Clopper–Pearson) 95 % intervals, and at a small number of recordings a rule may be unable
to give one of its verdicts whatever the data: the upper end with no success of 1 is
0.975, which reaches a power of 0.8 (a power rule that cannot fail below 3 recordings),
and with no false positive of 6 it is 0.459, above 2α = 0.1 (a false-positive rule that
cannot pass below 36).  Each row is asked this from its sample size alone (its
``n_independent``, the size its interval was computed on; exact for fractional sizes:
:func:`testable`).  A claim over every row is ``not_reproduced`` if a testable row fails,
``reproduced`` if every row is testable and passes, and otherwise
``not_testable_at_this_scale`` (an untestable row could still fail it at a larger scale);
a claim over some row is ``reproduced`` if a testable row passes, ``not_reproduced`` if
every row is testable and none passes, and otherwise not testable.  The rules on the
ADIS16405 record and the real sessions need their own samples: two pieces for a t
interval, bootstrap sets enough for the stochastic layer's p-values to fall below α,
re-simulations enough to resolve a central 95 %, two sessions for a heterogeneity test.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pandas as pd

from accelcal import distributions as dist

from ..claims import (COLUMNS, Claim, MinimumSample, Scale, bootstrap_rule_minimum, lower_end_with_all_successes,
                      power_rule_minimum, rank_rule_minimum, rate_lower_rule_minimum, rate_upper_rule_minimum,
                      upper_end_with_no_success, validate_rows)
from .benchmark import NONE, OUTLIER
from .scoring import REFERENCE, clopper_pearson

SUMMARY = "results/discrepancy/benchmark/summary.csv"
ADIS_CHECK = "results/discrepancy/adis/session_check_summary.csv"

FPR_COLORED = Claim(
    "discrepancy", "fpr_colored_null_every_profile",
    "Goal: under every noise profile of the benchmark (white, rounding, Gauss-Markov, flicker, "
    "random walk, the Xsens and ADIS16405 fits and the ADIS16405 record itself), the loop with the wander null "
    "names an effect or outlier on at most alpha of effect-free sessions: reproduced iff for every profile the "
    "exact 95% interval reaches down to alpha and its upper end is at most 2 alpha, on enough effect-free "
    "sessions per profile that the verdict is the loop's and not sampling noise's: a loop whose true rate is 0.035 "
    "fails this rule with probability below 1 % (280 sessions at alpha 0.05: fpr_sessions_needed); a profile with "
    "fewer is not decided, and the claim is then not testable at this scale unless a decided profile fails",
    "FPR <= alpha, upper bound <= 2 alpha")
FPR_WHITE = Claim(
    "discrepancy", "fpr_white_null_inflated_by_wander",
    "Negative control: the loop with the white-noise null names an effect on more than alpha "
    "of effect-free sessions whose noise has slow wander: reproduced iff on at least one wander profile the lower "
    "end of the exact 95% interval of its false-positive rate exceeds alpha (a profile with too few recordings for "
    "that, where the lower end stays at or below alpha even if every recording is a false positive, cannot pass: "
    "then the claim is not testable at this scale unless another profile passes)",
    "2 of 5 effect-free recordings named bias_drift")
FPR_WHITE_WHITE = Claim(
    "discrepancy", "fpr_white_null_white_noise",
    "On white noise the loop with the white null keeps its false-positive rate at alpha: reproduced iff "
    "the exact 95% interval on the white profile reaches down to alpha and its upper end is at most 2 alpha (not "
    "testable at this scale when the upper end exceeds 2 alpha even with no false positive)",
    "FPR <= alpha")
NAMING = Claim(
    "discrepancy", "naming_at_3mde_every_profile",
    "Goal: each effect hidden at 3 times its oracle minimum detectable effect is named first by the "
    "wander-null loop with the design power under every noise profile: reproduced iff for every (profile, "
    "effect) the upper end of the exact 95% interval of the naming accuracy at 3 MDE is at least the power (a row "
    "with too few recordings for the rule to fail, where the upper end reaches the power even with no success, "
    "cannot fail: then the claim is not testable at this scale unless another row fails)",
    "power at >= 1 MDE")
OUTLIERS = Claim(
    "discrepancy", "outlier_pose_named",
    "Goal: one pose shifted by 3 times the minimum detectable shift is named outlier_pose at its "
    "pose under every noise profile (wander null): reproduced iff the upper end of the exact 95% interval of that "
    "accuracy is at least the power for every profile (a profile with too few recordings for the rule to fail, "
    "where the upper end reaches the power even with no success, cannot fail: then the claim is not testable at "
    "this scale unless another profile fails)",
    "named with the pose index")
PAIRS = Claim(
    "discrepancy", "two_effects_named",
    "Goal: two effects hidden at once, each at 3 times its oracle MDE, are both named (in any order, "
    "nothing else) under every noise profile (wander null): reproduced iff the upper end of the exact 95% "
    "interval of that accuracy is at least the power for every profile and pair (a row with too few recordings "
    "for the rule to fail, where the upper end reaches the power even with no success, cannot fail: then the "
    "claim is not testable at this scale unless another row fails)",
    "both named")
ORACLE_AGREEMENT = Claim(
    "discrepancy", "oracle_agreement_every_profile",
    "Goal: on recordings it has not seen, the wander-null loop decides as well as an oracle that knows each "
    "recording's true noise covariance and runs the same nested tests with it (GLS, nothing estimated): under every "
    "noise profile the loop's named set (effects and outlier poses) equals the oracle's on at least 95% of the "
    "recordings: reproduced iff for every profile the upper end of the exact 95% interval of that agreement is at "
    "least 0.95 (a profile with too few recordings for the rule to fail cannot fail: then the claim is not testable "
    "at this scale unless another profile fails)",
    "agreement >= 95% in every profile")
ADIS_REFERENCE = Claim(
    "discrepancy", "adis_long_tau_terms_predict_wander",
    "Reference for slow bias wander: the stochastic layer's long-tau noise terms, fitted to the Allan deviation of the "
    "2.78 h ADIS16405 record on tau >= 1 s, predict the slow wander of the pose means of calibration-shaped pieces "
    "of the same record: reproduced iff the predicted scatter of the pose means about their session mean (variance, "
    "pooled over axes) lies in the 95% interval of the observed one (a t interval over the pieces: not testable "
    "at this scale with fewer than 2 pieces)",
    "the reference for slow bias wander")
ADIS_SHORT = Claim(
    "discrepancy", "short_rests_overpredict_wander",
    "Noise terms named from calibration-length rests (<= 10 s) over-predict the pose-residual excess "
    "(Xsens: 4.28 vs 2.91): reproduced iff, on session-shaped pieces of the ADIS16405 record, the stochastic "
    "layer run on the pieces' own rests predicts a scatter of the pose means above the upper end of the 95% "
    "interval of the observed one (not testable at this scale when the layer's bootstrap has too few sets for a "
    "p-value below its alpha: then it can name no term)",
    "4.28 vs 2.91 (Xsens)")


STABILITY = Claim(
    "batista2011", "sec6b_stability_public_sessions",
    "Sec. VI-B, tested on public sessions of one IMU (IMU-TK fork, data2/3/4): over sessions, scale and "
    "cross-axis terms do not change significantly while the bias changes: reproduced iff every scale factor and "
    "non-orthogonality angle is consistent across the sessions (Cochran's Q on the base model's estimates with "
    "the larger of the rests' and the residuals' standard errors, Holm over the 9 parameters, level alpha) and at "
    "least one bias component is not (not testable at this scale with fewer than 2 sessions)",
    "qualitative (their unit, tests on different days)")
SESSIONS = "results/discrepancy/sessions/stability.csv"
GAPS = "results/discrepancy/sessions/gaps.csv"
XSENS_GAP = Claim(
    "discrepancy", "xsens_gap_closed",
    "On the Xsens session the pose residuals are 2.5-2.9 times what white noise predicts and the loop "
    "must say what the excess is: reproduced iff the joint model's predicted excess interval contains the observed "
    "one and the session re-simulated with what the loop names puts the measured excess inside the central 95% of "
    "its re-simulated excesses, while the re-simulation before (white noise of the rests) does not (not testable at "
    "this scale with fewer re-simulations per model than resolve a central 95%: 39)",
    "2.5-2.9x, not explained by the rests' terms")


#: The stochastic layer's alpha in the ADIS16405 session check (``adis.session_check`` leaves
#: :func:`accelcal.discrepancy.stochastic_layer` at its default).
LAYER_ALPHA = 0.05
#: Minimum samples of the rules on the real sessions and the ADIS16405 record (module docstring).
GAP_RESIMULATIONS = rank_rule_minimum("re-simulations per model")
STABILITY_SESSIONS = MinimumSample(2, "sessions of the IMU", "a heterogeneity test compares at least two sessions")
ADIS_PIECES = MinimumSample(2, "pieces of the record", "a t interval of the observed scatter needs two pieces")
LAYER_PIECES = MinimumSample(1, "pieces with the stochastic layer", "the layer predicts nothing without a piece")


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
    scale = GAP_RESIMULATIONS.at(float(g.loc[["before", "after"], "replicates"].min()))
    return XSENS_GAP.judge(float(e.excess_predicted), passed=ok, fmt="predicted excess {:.2f}", scale=scale,
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
    scale = STABILITY_SESSIONS.at(float(st["sessions"].min()) if "sessions" in st else np.nan)
    scale_params = [p for p in st.index if p.startswith(("s_", "theta_"))]
    bias = [p for p in st.index if p.startswith("b_")]
    moved_bias = [p for p in bias if not bool(st.loc[p, "stable"])]
    moved_other = [p for p in scale_params if not bool(st.loc[p, "stable"])]
    ok = not moved_other and bool(moved_bias)
    return STABILITY.judge(len(moved_other), passed=ok, fmt="{:.0f} scale/angle parameters moved", scale=scale,
                           evidence=f"{SESSIONS}: not stable (Holm-adjusted p < alpha): "
                                    f"{', '.join(moved_bias + moved_other) or 'none'}; bias spread "
                                    + ", ".join(f"{p} {st.loc[p, 'spread']:.3g} ({st.loc[p, 'spread_over_se']:.1f} se)"
                                                for p in bias)
                                    + "; yardstick: the rests' noise inflated by any excess (the residual scatter alone "
                                    f"would call not stable: {', '.join(p for p in alt.index if not bool(alt.loc[p, 'stable'])) or 'none'})")


def _fpr(summary, null):
    return summary[(summary.null == null) & (summary.metric == "false_positive_rate")]


def _fpr_passes(d: pd.DataFrame, alpha: float) -> np.ndarray:
    """The false-positive goal on each row's interval: it reaches down to alpha, its upper end is <= 2 alpha."""
    return ((d.ci_low <= alpha) & (d.ci_high <= 2 * alpha)).to_numpy()


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
RULES = ("power", "fpr_upper", "fpr_lower", "fpr_decided")
#: The false-positive rate a sound loop may have (a little below α = 0.05), and the chance
#: with which such a loop may fail the false-positive rule at the sample size the rule
#: asks for (``fpr_decided``, :func:`fpr_sessions_needed`).
SOUND_RATE_OF_ALPHA, FAIL_RISK = 0.7, 0.01


def fpr_fail_probability(n, alpha: float = 0.05, rate: float | None = None) -> np.ndarray:
    """Probability that a loop whose true false-positive rate is ``rate`` (default 0.7 α:
    0.035) fails the rule "the exact 95 % interval reaches down to α and its upper end is at
    most 2α" on ``n`` effect-free sessions (whole ``n``, array-like).

    The exact interval's ends through the binomial distribution (Clopper–Pearson's duality):
    ``k`` of ``n`` keeps the upper end at or below 2α iff ``P(Bin(n, 2α) ≤ k) ≤ 0.025``, and
    the lower end at or below α iff ``P(Bin(n, α) ≥ k) ≥ 0.025``; both sets are ``0..k_max``."""
    rate = SOUND_RATE_OF_ALPHA * alpha if rate is None else rate
    out = []
    for m in np.atleast_1d(np.asarray(n, int)):
        k = np.arange(m + 1)
        upper_ok = dist.special.bdtr(k, m, 2 * alpha) <= 0.025
        lower_ok = (k == 0) | (dist.special.bdtrc(k - 1, m, alpha) >= 0.025)
        passing = k[upper_ok & lower_ok]
        out.append(1.0 - float(dist.special.bdtr(passing.max(), m, rate)) if passing.size else 1.0)
    return np.asarray(out)


def fpr_sessions_needed(alpha: float = 0.05, rate: float | None = None, risk: float = FAIL_RISK,
                        n_max: int = 2000) -> int:
    """Effect-free sessions per profile at which a loop of true rate ``rate`` (0.7 α) fails the
    false-positive rule with probability below ``risk``, there and at every larger size up to
    ``n_max`` (the exact interval's steps make that probability a sawtooth in ``n``: 255 is
    below 1 %, 258-266 and 279 are not).  280 at α = 0.05."""
    n = np.arange(rate_upper_rule_minimum(2 * alpha, "").needed, n_max + 1)
    bad = n[fpr_fail_probability(n, alpha, rate) >= risk]
    return int(bad.max()) + 1 if bad.size else int(n[0])


def minimum(rule: str, *, alpha: float = 0.05, power: float = 0.8, unit: str = "recordings") -> MinimumSample:
    """The least whole number of recordings with which ``rule`` can give both verdicts
    (:func:`accelcal_repro.claims.power_rule_minimum` and the rate rules)."""
    if rule == "power":
        return power_rule_minimum(power, unit)
    if rule == "fpr_upper":
        return rate_upper_rule_minimum(2 * alpha, unit)
    if rule == "fpr_lower":
        return rate_lower_rule_minimum(alpha, unit)
    if rule == "fpr_decided":
        return MinimumSample(_sessions_needed(alpha), unit,
                             f"with fewer, a loop whose true rate is {SOUND_RATE_OF_ALPHA * alpha:g} fails the rule "
                             f"with probability {FAIL_RISK:g} or more: sampling noise, not the loop, decides")
    raise ValueError(f"unknown rule {rule!r} (known: {', '.join(RULES)})")


def testable(rule: str, n, *, alpha: float = 0.05, power: float = 0.8) -> tuple[np.ndarray, np.ndarray]:
    """Can a row of sample size ``n`` (fractional: an effective size) give both verdicts of
    ``rule``?  ``(mask, bound)``.

    ``power`` (pass iff the upper end of the exact 95 % interval ≥ ``power``): only if no
    success of ``n`` puts the upper end below the power (``bound``: that upper end);
    ``fpr_upper`` (pass needs the upper end ≤ 2α): only if no false positive of ``n`` puts
    it at or below 2α (``bound``: that upper end); ``fpr_lower`` (pass iff the lower end
    > α): only if ``n`` false positives of ``n`` put it above α (``bound``: that lower end).
    The other verdict is reachable at any ``n ≥ 1`` (``n`` successes reach any power, ``n``
    false positives push the upper end to 1, none keep the lower end at 0).  For whole
    ``n`` the mask is ``n >= minimum(rule).needed``.
    """
    minimum(rule, alpha=alpha, power=power)  # the rule's name checked
    n = np.asarray(n, float)
    with np.errstate(invalid="ignore"):
        if rule == "power":
            bound = upper_end_with_no_success(n)
            ok = bound < power
        elif rule == "fpr_upper":
            bound = upper_end_with_no_success(n)
            ok = bound <= 2 * alpha
        elif rule == "fpr_decided":
            bound = fpr_fail_probability(np.clip(np.floor(np.nan_to_num(n)), 1, None), alpha).reshape(n.shape)
            ok = n >= _sessions_needed(alpha)
        else:
            bound = lower_end_with_all_successes(n)
            ok = bound > alpha
    return np.asarray(ok & (n >= 1), bool), bound


@lru_cache(maxsize=8)
def _sessions_needed(alpha: float) -> int:
    return fpr_sessions_needed(alpha)


def _label(r) -> str:
    return f"{r.profile}{'' if r.effect == NONE else '/' + r.effect}"


def _over_rows(claim: Claim, d: pd.DataFrame, passed: np.ndarray, rule: str, *, every: bool, alpha: float,
               power: float, per: str, value: float, fmt: str, evidence: str) -> dict:
    """A claim over the rows ``d`` (every row must pass, or some row must), each row's
    ``passed`` counted only where :func:`testable` (module docstring)."""
    n = sample_sizes(d)
    keep, bound = testable(rule, n, alpha=alpha, power=power)
    passed = np.asarray(passed, bool)
    decided = (keep & ~passed).any() if every else (keep & passed).any()
    scale = minimum(rule, alpha=alpha, power=power, unit=f"recordings per {per}").at(
        float(n[~keep].max()) if (~keep).any() else float(np.min(n, initial=np.nan)),
        testable=decided or bool(keep.all()))
    if not scale.testable:
        which = {"fpr_lower": "lower end", "fpr_decided": "chance that a sound loop fails"}.get(rule, "upper end")
        b = float(bound[~keep][np.argmax(n[~keep])])
        evidence += (f"; not testable ({which} {b:.3f} at the largest such n): "
                     + ", ".join(f"{_label(r)} (n {k:g})" for r, k, ok in zip(d.itertuples(), n, keep) if not ok))
    elif not keep.all():
        evidence += ("; not testable at their n, decided by the others: "
                     + ", ".join(f"{_label(r)} (n {k:g})" for r, k, ok in zip(d.itertuples(), n, keep) if not ok))
    return claim.judge(value, passed=bool(decided) != every, fmt=fmt, evidence=evidence, scale=scale)


def _fpr_rows(summary, profiles_table, alpha, nulls) -> list[dict]:
    rows = []
    fc = _fpr(summary, "wander")
    if "wander" not in nulls or not len(fc):
        rows.append(_unavailable(FPR_COLORED, "wander"))
    else:
        keep = testable("fpr_decided", sample_sizes(fc), alpha=alpha)[0]
        ok = _fpr_passes(fc, alpha)
        bad = fc[keep & ~ok]
        worst = fc.loc[fc.ci_high.idxmax()]
        rows.append(_over_rows(
            FPR_COLORED, fc, ok, "fpr_decided", every=True, alpha=alpha, power=np.nan,
            per="profile", value=float(fc.value.max()), fmt="max {:.3f}",
            evidence=f"{SUMMARY}: {int(keep.sum()) - len(bad)}/{int(keep.sum())} testable profiles pass; highest rate "
                     f"{fc.value.max():.3f} ({fc.loc[fc.value.idxmax(), 'profile']}); highest upper bound "
                     f"{worst.ci_high:.3f} ({worst.profile}); failing: "
                     + (', '.join(f'{r.profile} {r.value:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]'
                                  for r in bad.itertuples()) or 'none')))
    fw = _fpr(summary, "white")
    if "white" not in nulls or not len(fw):
        rows += [_unavailable(FPR_WHITE, "white"), _unavailable(FPR_WHITE_WHITE, "white")]
        return rows
    kinds = profiles_table.groupby("profile")["wander_over_white"].mean()
    wander = fw[fw.profile.map(lambda p: kinds.get(p, 0.0) > 0.05)]
    keep = testable("fpr_lower", sample_sizes(wander), alpha=alpha)[0]
    inflated = wander[keep & (wander.ci_low > alpha)]
    rows.append(_over_rows(
        FPR_WHITE, wander, (wander.ci_low > alpha).to_numpy(), "fpr_lower", every=False, alpha=alpha, power=np.nan,
        per="wander profile", value=float(wander.value.max()) if len(wander) else np.nan, fmt="max {:.3f}",
        evidence=f"{SUMMARY}: white null, {len(inflated)}/{int(keep.sum())} testable wander profiles with the "
                 "interval above alpha: "
                 + (', '.join(f'{r.profile} {r.value:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]'
                              for r in inflated.itertuples()) or 'none')))
    ww = fw[fw.profile == "white"]
    if len(ww):
        r = ww.iloc[0]
        rows.append(_over_rows(FPR_WHITE_WHITE, ww.iloc[:1], _fpr_passes(ww.iloc[:1], alpha), "fpr_upper", every=True,
                               alpha=alpha, power=np.nan, per="profile", value=float(r.value), fmt="{:.3f}",
                               evidence=f"{SUMMARY}: white profile, white null: {r.value:.3f} "
                                        f"[{r.ci_low:.3f}, {r.ci_high:.3f}], n {int(r.n)}"))
    else:
        rows.append(FPR_WHITE_WHITE.not_reproducible("no white profile in the benchmark"))
    return rows


def _accuracy_rows(summary, power, nulls) -> list[dict]:
    if "wander" not in nulls or not len(summary[summary.null == "wander"]):
        return [_unavailable(c, "wander") for c in (NAMING, OUTLIERS, PAIRS)]
    s = summary[summary.null == "wander"]
    out = []
    for claim, sel in ((NAMING, ~s.effect.isin((NONE, OUTLIER)) & ~s.effect.str.contains("+", regex=False)
                        & ~s.effect.str.endswith("_const")),
                       (OUTLIERS, s.effect == OUTLIER), (PAIRS, s.effect.str.contains("+", regex=False))):
        d = s[sel & (s.metric == "accuracy_at_3mde")]
        if not len(d):
            out.append(claim.not_reproducible("no such rows at 3 MDE in the benchmark config"))
            continue
        keep = testable("power", sample_sizes(d), power=power)[0]
        bad = d[keep & (d.ci_high < power)]
        worst = d.loc[d.value.idxmin()]
        out.append(_over_rows(claim, d, (d.ci_high >= power).to_numpy(), "power", every=True, alpha=np.nan,
                              power=power, per="row", value=float(d.value.min()), fmt="min {:.2f}",
                              evidence=f"{SUMMARY}: accuracy_at_3mde, {int(keep.sum()) - len(bad)}/{int(keep.sum())} "
                                       f"testable (profile, row) reach the power; lowest {worst.value:.2f} "
                                       f"({worst.profile}, {worst.effect}, n {int(worst.n)}); below: "
                                       + (', '.join(f'{r.profile}/{r.effect} {r.value:.2f}' for r in bad.itertuples())
                                          or 'none')))
    return out


def _oracle_row(summary: pd.DataFrame, nulls) -> dict:
    d = summary[(summary.null == "wander") & (summary.metric == "oracle_agreement")]
    d = d[d.verdict != REFERENCE]  # real-record profiles: their "oracle" is a fitted model (scoring.REFERENCE_RULE)
    if "wander" not in nulls or not len(d):
        return ORACLE_AGREEMENT.not_reproducible("the benchmark ran no oracle beside the wander null "
                                                 "(discrepancy.benchmark.oracle)")
    target = 0.95
    keep = testable("power", sample_sizes(d), power=target)[0]
    bad = d[keep & (d.ci_high < target)]
    worst = d.loc[d.value.idxmin()]
    return _over_rows(ORACLE_AGREEMENT, d, (d.ci_high >= target).to_numpy(), "power", every=True, alpha=np.nan,
                      power=target, per="profile", value=float(d.value.min()), fmt="min {:.3f}",
                      evidence=f"{SUMMARY}: oracle_agreement, {int(keep.sum()) - len(bad)}/{int(keep.sum())} testable "
                               f"profiles reach 0.95; lowest {worst.value:.3f} [{worst.ci_low:.3f}, {worst.ci_high:.3f}] "
                               f"({worst.profile}, n {int(worst.n)}); below: "
                               + (', '.join(f'{r.profile} {r.value:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]'
                                            for r in bad.itertuples()) or 'none')
                               + "; where they differ: results/discrepancy/benchmark/oracle.csv")


def _adis_rows(check: pd.DataFrame, layer_n_boot: int | None) -> list[dict]:
    a = check[check.axis == "all"].iloc[0]
    lo, hi, obs = float(a.observed_ci_low), float(a.observed_ci_high), float(a.observed_var)
    ref = float(a.reference_var)
    rows = [ADIS_REFERENCE.judge(ref / obs, passed=lo <= ref <= hi, fmt="predicted/observed {:.2f}",
                                 scale=ADIS_PIECES.at(float(a.pieces)),
                                 evidence=f"{ADIS_CHECK}: {int(a.pieces)} pieces, observed pose-mean scatter (variance "
                                          f"about the session mean) {obs:.3g} [{lo:.3g}, {hi:.3g}] (m/s^2)^2, reference "
                                          f"model {ref:.3g}, its white term alone {a.reference_white_var:.3g}; excess "
                                          f"over the calibration's standard errors {a.excess_observed:.2f}")]
    if "layer_var" in check and np.isfinite(a.get("layer_var", np.nan)):
        lay = float(a.layer_var)
        scale = LAYER_PIECES.at(float(a.layer_pieces))
        if scale.testable and layer_n_boot is not None:
            scale = bootstrap_rule_minimum(LAYER_ALPHA, "bootstrap sets of the stochastic layer").at(layer_n_boot)
        rows.append(ADIS_SHORT.judge(lay / obs, passed=lay > hi, fmt="predicted/observed {:.1f}", scale=scale,
                                     evidence=f"{ADIS_CHECK}: stochastic layer on the rests of {int(a.layer_pieces)} "
                                              f"pieces (named {a.layer_terms}): {lay:.3g} vs observed {obs:.3g} "
                                              f"[{lo:.3g}, {hi:.3g}]"))
    else:
        rows.append(ADIS_SHORT.not_reproducible("the stochastic layer was run on no piece (adis.layer_pieces = 0)"))
    return rows


def discrepancy_claims(summary: pd.DataFrame, profiles_table: pd.DataFrame, adis_check: pd.DataFrame, *,
                       alpha: float, power: float, nulls, stability: pd.DataFrame | None = None,
                       excess: pd.DataFrame | None = None, gaps: pd.DataFrame | None = None,
                       layer_n_boot: int | None = None) -> pd.DataFrame:
    """Ledger rows (:data:`accelcal_repro.claims.COLUMNS`) of the discrepancy stage.

    ``layer_n_boot``: the bootstrap sets of the stochastic layer in the ADIS16405 session
    check (``discrepancy.adis.n_boot``); None leaves that rule's minimum unchecked.
    """
    rows = _fpr_rows(summary, profiles_table, alpha, nulls) + _accuracy_rows(summary, power, nulls)
    rows.append(_oracle_row(summary, nulls))
    rows += _adis_rows(adis_check, layer_n_boot)
    rows.append(_xsens_row(excess, gaps))
    rows.append(_stability_row(stability))
    return validate_rows(pd.DataFrame(rows, columns=list(COLUMNS)), source="discrepancy claims")


__all__ = ["GAP_RESIMULATIONS", "LAYER_ALPHA", "RULES", "discrepancy_claims", "fpr_fail_probability",
           "fpr_sessions_needed", "minimum", "sample_sizes", "testable"]
