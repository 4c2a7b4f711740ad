"""Scoring of the discrepancy benchmark: key + detections → one row per recording and null, rates, summary.

Tables (tidy, the figures and the claims are computed from them):

* :func:`score_cases`: one row per (recording, null hypothesis): the key, the detection and
  ``named`` (an effect or an outlier named), ``correct`` (the outcome a correct detector
  gives: the effect named first; both effects of a pair named, in any order, and nothing
  else; the disturbed pose named as ``outlier_pose`` at its time; ``none``;
  ``not_identifiable`` for the constant temperature), ``detected`` (the injected effect, or
  one of the pair, among the named ones), ``false_positive`` (anything named on an
  effect-free recording: effects and outliers, every round: the loop's family-wise error),
  ``outlier_false`` (an outlier pose named that is not the disturbed one), ``outliers_named``,
  and, beside the oracle's row of the same recording (null ``oracle``: the same tests
  with the true noise covariance, :mod:`.oracle`), ``oracle_named_set`` and
  ``agrees_with_oracle`` (the same effects and the same outlier poses).
* :func:`rates`: per (null, profile, row, size): outcome counts, detection rate and
  accuracy with exact (Clopper–Pearson) 95 % intervals.
* :func:`oracle_differences`: per (null, profile, row): how often the loop's named set is the
  oracle's, and what each names that the other does not.
* :func:`summary`: the findings, one row per (null, profile, row, metric), with verdicts
  where the issue states a goal (rules in the ``rule`` column): ``pass``, ``fail``, or
  ``not_testable_at_this_scale`` where the row's sample cannot give both (the exact
  interval's bound at the extreme count is on the same side of the goal whatever the
  count: :mod:`accelcal_repro.claims`).

Real-noise profiles reuse windows of one record (:mod:`.profiles`): recordings that share a
window are correlated, so their intervals use Kish's effective sample size
``n / (1 + (m₀ − 1) ρ)`` with ``ρ`` the intraclass correlation of the outcome within
windows (ANOVA estimator, clipped to [0, 1]; 1, i.e. one recording per window, when it
cannot be estimated) and ``m₀`` the mean window size (:func:`effective_n`), reported as
``n_independent``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal import distributions as dist
from accelcal.effects import EFFECT_IDS
from accelcal.errors import AccelcalError

from ..claims import NOT_TESTABLE, upper_end_with_no_success
from .benchmark import CONSTANT_TEMPERATURE, ERROR, NONE, NOT_IDENTIFIABLE, OUTLIER

#: The detection rows of the oracle (:mod:`.oracle`).
ORACLE = "oracle"

SUMMARY_COLUMNS = ["section", "null", "profile", "effect", "metric", "value", "ci_low", "ci_high", "n", "n_independent",
                   "target", "verdict", "rule"]
#: Outcomes that name nothing.
NOTHING_NAMED = (NONE, NOT_IDENTIFIABLE, ERROR)


def clopper_pearson(k, n, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Exact binomial interval of ``k`` successes in ``n`` (NaN for ``n = 0``; non-integer ``k`` allowed)."""
    k = np.asarray(k, float)
    n = np.asarray(n, float)
    a = (1 - level) / 2
    with np.errstate(invalid="ignore", divide="ignore"):
        lo = np.where(k > 0, dist.beta_ppf(a, k, n - k + 1), 0.0)
        hi = np.where(k < n, dist.beta_ppf(1 - a, k + 1, n - k), 1.0)
    bad = n <= 0
    return np.where(bad, np.nan, lo), np.where(bad, np.nan, hi)


def effective_n(x, clusters=None) -> float:
    """Kish's effective sample size of the binary outcomes ``x`` grouped by ``clusters``
    (module docstring); ``len(x)`` without clusters (or with negative cluster ids)."""
    x = np.asarray(x, float)
    n = x.size
    if clusters is None or n == 0:
        return float(n)
    c = np.asarray(clusters)
    if np.all(c < 0):
        return float(n)
    ids, inv, m = np.unique(c, return_inverse=True, return_counts=True)
    K = ids.size
    if K <= 1 or K == n:
        return float(K if K <= 1 else n)
    p_k = np.bincount(inv, weights=x) / m
    p = x.mean()
    msb = float(np.sum(m * (p_k - p) ** 2) / (K - 1))
    msw = float(np.sum(m * p_k * (1 - p_k)) / (n - K))
    m0 = (n - np.sum(m ** 2) / n) / (K - 1)
    den = msb + (m0 - 1) * msw
    rho = 1.0 if den <= 0 else float(np.clip((msb - msw) / den, 0.0, 1.0))
    return float(n / (1 + (m0 - 1) * rho))


def interval(x, clusters=None) -> tuple[float, float, float]:
    """Clopper–Pearson 95 % interval of the mean of binary ``x`` on its effective sample size:
    ``(low, high, n_eff)``."""
    x = np.asarray(x, float)
    n = x.size
    if n == 0:
        return float("nan"), float("nan"), 0.0
    ne = effective_n(x, clusters)
    lo, hi = clopper_pearson(x.mean() * ne, ne)
    return float(lo), float(hi), ne


def _outlier_times(det_t) -> list[float]:
    """The mid times of the poses the loop named outliers: the detection's ``outlier_t_detected``,
    ``';'``-joined times as written, or a single number (``pandas.read_csv`` parses a column
    whose cells each hold one time as floats); empty, NaN or None: none."""
    if isinstance(det_t, str):
        return [float(v) for v in det_t.split(";") if v.strip()]
    if isinstance(det_t, (int, float, np.integer, np.floating)) and not isinstance(det_t, bool):
        return [float(det_t)] if np.isfinite(det_t) else []
    return []


def _outlier_located(det_t, true_t: float, tol: float) -> bool:
    if not np.isfinite(true_t):
        return False
    return any(abs(v - true_t) <= tol for v in _outlier_times(det_t))


def score_cases(key: pd.DataFrame, detections: pd.DataFrame, *, outlier_tol_s: float = 3.0) -> pd.DataFrame:
    """One row per (recording, null): key, detection, ``named``, ``correct``, ``detected``, ``false_positive``.

    ``outlier_tol_s``: a named outlier pose is the disturbed one if its mid time is within
    this of the true mid time.
    """
    df = key.merge(detections, on="recording", how="left", validate="one_to_many")
    if df["outcome"].isna().any():
        missing = df.loc[df["outcome"].isna(), "recording"].head(3).tolist()
        raise AccelcalError(f"recordings without a detection row: {missing}")
    effects = df["effects"].fillna("").astype(str)
    named_set = effects.map(lambda s: frozenset(x for x in s.split("+") if x))
    injected = df["effects_injected"].fillna("").map(lambda s: frozenset(x for x in s.split("+") if x and x != NONE))
    df["named"] = ~df["outcome"].isin(NOTHING_NAMED)
    located = [_outlier_located(d, t, outlier_tol_s) for d, t in
               zip(df.get("outlier_t_detected", pd.Series([""] * len(df), index=df.index)), df["outlier_t"])]
    df["outlier_located"] = located
    single = df.truth.isin(EFFECT_IDS)
    pair = df.truth.str.contains("+", regex=False)
    correct = df["outcome"] == df["expected"]
    correct = np.where(pair, named_set == injected, correct)
    correct = np.where(df.truth == OUTLIER, (df["outcome"] == OUTLIER) & df["outlier_located"], correct)
    df["correct"] = correct.astype(bool)
    df["detected"] = np.array([bool(i & s) for i, s in zip(injected, named_set)]) & (single | pair).to_numpy()
    df["false_positive"] = (df["truth"] == NONE) & df["named"]
    df["outliers_named"] = effects.map(lambda s: sum(x == OUTLIER for x in s.split("+")))
    df["outlier_false"] = (df["outliers_named"] - df["outlier_located"].astype(int)) > 0
    return _with_oracle(df)


def _with_oracle(df: pd.DataFrame) -> pd.DataFrame:
    """``oracle_named_set`` and ``agrees_with_oracle`` of every row (module docstring); NaN
    (and False) where the recording has no oracle row."""
    if "named_set" not in df:
        df["named_set"] = ""
    df["named_set"] = df["named_set"].fillna("").astype(str)
    orc = df[df["null"] == ORACLE].set_index("recording")["named_set"]
    df["oracle_named_set"] = df["recording"].map(orc)
    df["agrees_with_oracle"] = df["oracle_named_set"].notna() & (df["named_set"] == df["oracle_named_set"])
    return df


def rates(scores: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Per (null, profile, truth, size): outcome counts, detection rate and accuracy with exact intervals."""
    out = []
    for (null, prof, truth, size), d in scores.groupby(["null", "profile", "truth", "size_mde"], sort=False):
        n = len(d)
        win = d["noise_window"].to_numpy()
        k_det, k_ok = int(d["detected"].sum()), int(d["correct"].sum())
        lo_d, hi_d, _ = interval(d["detected"], win)
        if truth in (NONE, OUTLIER, CONSTANT_TEMPERATURE):  # no effect to detect
            k_det, lo_d, hi_d = np.nan, np.nan, np.nan
        lo_a, hi_a, n_ind = interval(d["correct"], win)
        row = {"null": null, "profile": prof, "truth": truth, "size_mde": size, "n": n, "n_independent": round(n_ind, 1),
               "expected": d["expected"].iloc[0], "detected": k_det, "detection_rate": k_det / n,
               "detection_ci_low": lo_d, "detection_ci_high": hi_d, "correct": k_ok, "accuracy": k_ok / n,
               "accuracy_ci_low": lo_a, "accuracy_ci_high": hi_a, "named": int(d["named"].sum()),
               "errors": int((d["outcome"] == ERROR).sum())}
        for o, c in d["outcome"].value_counts().items():
            row[f"n_{o}"] = int(c)
        out.append(row)
    df = pd.DataFrame(out)
    if len(df):
        order = {t: i for i, t in enumerate((NONE, *EFFECT_IDS))}
        df = df.sort_values(["null", "profile", "truth", "size_mde"],
                            key=lambda c: c.map(lambda v: order.get(v, len(order))) if c.name == "truth" else c,
                            kind="stable").reset_index(drop=True)
        df = df.fillna({c: 0 for c in df.columns if c.startswith("n_")})
    return df


def crossing(sizes, rate, target: float) -> tuple[float, str]:
    """Size (MDE units) where the detection rate first reaches ``target``, linear in
    log(size) between grid points; NaN with a note if the grid does not bracket it."""
    s = np.asarray(sizes, float)
    r = np.asarray(rate, float)
    o = np.argsort(s)
    s, r = s[o], r[o]
    if not len(s):
        return float("nan"), "no data"
    if r[0] >= target:
        return float("nan"), f"reached at the smallest size {s[0]:g}"
    for i in range(1, len(s)):
        if r[i] >= target:
            f = (target - r[i - 1]) / (r[i] - r[i - 1])
            return float(np.exp(np.log(s[i - 1]) + f * (np.log(s[i]) - np.log(s[i - 1])))), ""
    return float("nan"), f"not reached up to size {s[-1]:g}"


def _row(null, prof, effect, metric, value, lo, hi, n, n_ind, target=np.nan, verdict="", rule=""):
    return {"section": "benchmark", "null": null, "profile": prof, "effect": effect, "metric": metric,
            "value": value, "ci_low": lo, "ci_high": hi, "n": n, "n_independent": n_ind, "target": target,
            "verdict": verdict, "rule": rule}


FPR_RULE = ("goal: false-positive rate (effects and outliers, every round together: the family-wise error) <= alpha; "
            "pass iff the exact 95% interval (independent recordings) reaches "
            "down to alpha and its upper end is <= 2 alpha; not_testable_at_this_scale when the upper end exceeds "
            "2 alpha even with no false positive")
ORACLE_RULE = ("goal: the loop's named set (effects and outlier poses) equals the oracle's (the same tests with "
               "the true noise covariance) on >= 95% of the recordings; pass iff the upper end of the exact 95% "
               "interval >= 0.95; not_testable_at_this_scale when it reaches 0.95 even with no agreement")
#: The verdict of the agreement on a real-record profile: not an oracle, so not the goal's.
REFERENCE = "reference_not_oracle"
REFERENCE_RULE = ("not part of the oracle goal: on a real-record profile the 'true' covariance is a model fitted to "
                  "the same record (one realisation of an unknown process), so the agreement compares the loop with "
                  "a reference, not with an oracle; the profile with an oracle is its simulated twin, whose true "
                  "noise is that fitted model (adis_model for adis_real)")
#: The agreement the loop must reach with the oracle.
ORACLE_TARGET = 0.95
ACCURACY_RULE = ("named first at sizes >= 1 oracle MDE (pooled); pass iff the upper end of the exact 95% interval >= "
                 "power; not_testable_at_this_scale when it reaches the power even with no success")


def fpr_verdict(lo: float, hi: float, n_eff: float, alpha: float) -> str:
    """Verdict of the false-positive goal (:data:`FPR_RULE`) on an interval of ``n_eff`` recordings."""
    if not upper_end_with_no_success(n_eff) <= 2 * alpha:
        return NOT_TESTABLE
    return "pass" if lo <= alpha and hi <= 2 * alpha else "fail"


def accuracy_verdict(hi: float, n_eff: float, power: float) -> str:
    """Verdict of the naming goal (:data:`ACCURACY_RULE`) on an interval of ``n_eff`` recordings."""
    if not upper_end_with_no_success(n_eff) < power:
        return NOT_TESTABLE
    return "pass" if hi >= power else "fail"


def _fpr_rows(null, prof, none: pd.DataFrame, alpha: float) -> list[dict]:
    n = len(none)
    win = none["noise_window"].to_numpy()
    fp = none["false_positive"].to_numpy()
    lo, hi, ne = interval(fp, win)
    rows = [_row(null, prof, NONE, "false_positive_rate", fp.mean(), lo, hi, n, round(ne, 1), alpha,
                 fpr_verdict(lo, hi, ne, alpha), FPR_RULE)]
    effects_named = none["effects"].fillna("").astype(str).map(lambda v: any(x and x != OUTLIER for x in v.split("+")))
    for what, sel in (("effect", effects_named), ("outlier", none["outliers_named"] > 0)):
        x = (sel & none["false_positive"]).to_numpy()
        lo, hi, ne = interval(x, win)
        rows.append(_row(null, prof, NONE, f"false_positive_rate_{what}", x.mean(), lo, hi, n, round(ne, 1),
                         rule="share of effect-free recordings where the loop names "
                              + ("an effect" if what == "effect" else "an outlier pose") + " (in any round)"))
    for o in (NOT_IDENTIFIABLE, ERROR):
        x = (none["outcome"] == o).to_numpy()
        lo, hi, ne = interval(x, win)
        rows.append(_row(null, prof, NONE, f"rate_{o}", x.mean(), lo, hi, n, round(ne, 1),
                         rule=f"share of effect-free recordings with outcome {o}"))
    return rows


def _oracle_and_outlier_rows(null, prof, sc: pd.DataFrame) -> list[dict]:
    """Agreement with the oracle (every recording of the profile the null ran on), the false
    outlier rate (an outlier pose named that is not the disturbed one, every row) and the
    outlier power (the disturbed pose named, per size)."""
    rows = []
    win = sc["noise_window"].to_numpy()
    if null != ORACLE and sc["oracle_named_set"].notna().any():
        d = sc[sc["oracle_named_set"].notna()]
        lo, hi, ne = interval(d["agrees_with_oracle"], d["noise_window"].to_numpy())
        real = "profile_kind" in d and bool((d["profile_kind"] == "real").all())
        rows.append(_row(null, prof, "all", "oracle_agreement", float(d["agrees_with_oracle"].mean()), lo, hi, len(d),
                         round(ne, 1), ORACLE_TARGET, REFERENCE if real else accuracy_verdict(hi, ne, ORACLE_TARGET),
                         REFERENCE_RULE if real else ORACLE_RULE))
    lo, hi, ne = interval(sc["outlier_false"], win)
    rows.append(_row(null, prof, "all", "false_outlier_rate", float(sc["outlier_false"].mean()), lo, hi, len(sc),
                     round(ne, 1), rule="share of the recordings (every row) where an outlier pose is named that is not "
                                        "the disturbed one"))
    out = sc[sc.truth == OUTLIER]
    for size, d in out.groupby("size_mde", sort=True):
        lo, hi, ne = interval(d["outlier_located"], d["noise_window"].to_numpy())
        rows.append(_row(null, prof, OUTLIER, f"outlier_power_at_{size:g}mde", float(d["outlier_located"].mean()), lo,
                         hi, len(d), round(ne, 1),
                         rule="the disturbed pose named an outlier (in any round), shift at this size x its MDE"))
    return rows


def oracle_differences(scores: pd.DataFrame) -> pd.DataFrame:
    """Per (null, profile, row, size): recordings, how many the loop and the oracle name the
    same set on, and what the loop names that the oracle does not (``loop_only``) and the
    reverse (``oracle_only``), as ``item: count`` over those recordings."""
    d = scores[(scores["null"] != ORACLE) & scores["oracle_named_set"].notna()]
    out = []
    for (null, prof, truth, size), g in d.groupby(["null", "profile", "truth", "size_mde"], sort=True):
        loop_only, oracle_only = {}, {}
        for a, b in zip(g["named_set"], g["oracle_named_set"]):
            sa, sb = {x for x in a.split("+") if x}, {x for x in str(b).split("+") if x}
            for x in sa - sb:
                key = x.split("@")[0]
                loop_only[key] = loop_only.get(key, 0) + 1
            for x in sb - sa:
                key = x.split("@")[0]
                oracle_only[key] = oracle_only.get(key, 0) + 1
        out.append({"null": null, "profile": prof, "truth": truth, "size_mde": size, "n": len(g),
                    "agree": int(g["agrees_with_oracle"].sum()), "agreement": float(g["agrees_with_oracle"].mean()),
                    "loop_only": "; ".join(f"{k}: {v}" for k, v in sorted(loop_only.items())),
                    "oracle_only": "; ".join(f"{k}: {v}" for k, v in sorted(oracle_only.items()))})
    return pd.DataFrame(out, columns=["null", "profile", "truth", "size_mde", "n", "agree", "agreement", "loop_only",
                                      "oracle_only"])


def summary(scores: pd.DataFrame, rate_table: pd.DataFrame, *, alpha: float, power: float) -> pd.DataFrame:
    """The benchmark's findings, one tidy row per (null, profile, row, metric), with verdicts.

    Rules (stated in ``rule``): the false-positive rate passes when its exact 95 %
    interval reaches down to α and its upper end is at most 2α (the issue's goal ≤ α,
    upper bound ≤ 2α); the naming accuracy of an effect pooled over sizes ≥ 1 MDE passes
    when its interval's upper end is ≥ the configured power (at 1 oracle MDE a test that
    knew the true noise covariance would detect it with that power, larger sizes more
    often).  Each is ``not_testable_at_this_scale`` on fewer recordings than can give both
    verdicts (:func:`fpr_verdict`, :func:`accuracy_verdict`).  Accuracy and detection rate
    at every size are reported without verdict.
    """
    rows = []
    for (null, prof), sc in scores.groupby(["null", "profile"], sort=True):
        none = sc[sc.truth == NONE]
        if len(none):
            rows += _fpr_rows(null, prof, none, alpha)
        rows += _oracle_and_outlier_rows(null, prof, sc)
        rt = rate_table[(rate_table.null == null) & (rate_table.profile == prof)]
        for truth, d in sc[sc.truth != NONE].groupby("truth", sort=False):
            r = rt[rt.truth == truth].sort_values("size_mde")
            for a in r.itertuples():
                rows.append(_row(null, prof, truth, f"accuracy_at_{a.size_mde:g}mde", a.accuracy, a.accuracy_ci_low,
                                 a.accuracy_ci_high, a.n, a.n_independent,
                                 rule="share of the row's recordings with the correct outcome (module docstring)"))
                if truth in EFFECT_IDS or "+" in truth:
                    rows.append(_row(null, prof, truth, f"detection_rate_at_{a.size_mde:g}mde", a.detection_rate,
                                     a.detection_ci_low, a.detection_ci_high, a.n, a.n_independent,
                                     rule="the injected effect (or one of the pair) among the named ones"))
            if truth in EFFECT_IDS:
                big = d[d.size_mde >= 1.0]
                n = len(big)
                lo, hi, ne = interval(big["correct"], big["noise_window"].to_numpy())
                rows.append(_row(null, prof, truth, "accuracy_ge_1mde", big["correct"].mean() if n else np.nan, lo, hi,
                                 n, round(ne, 1), power, accuracy_verdict(hi, ne, power) if n else "", ACCURACY_RULE))
                for target in (0.5, 0.95):
                    v, note = crossing(r.size_mde, r.detection_rate, target)
                    rows.append(_row(null, prof, truth, f"size_at_{int(target * 100)}pct_mde", v, np.nan, np.nan,
                                     int(r.n.sum()), float(r.n_independent.sum()),
                                     rule=note or "linear interpolation in log(size) of the detection rate"))
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def headline(summ: pd.DataFrame, profiles) -> pd.DataFrame:
    """One row per profile (config order): the false-positive rate under each null with its
    interval and verdict, the naming accuracy at each size averaged over the single
    effects, and the accuracy of the pair and outlier rows, under each null (the oracle's
    too); the loop's agreement with the oracle, its false outlier rate and outlier power."""
    rows = []
    for prof in profiles:
        d = summ[summ.profile == prof]
        row = {"profile": prof}
        for null, dn in d.groupby("null", sort=True):
            fp = dn[dn.metric == "false_positive_rate"]
            if len(fp):
                f = fp.iloc[0]
                row.update({f"fpr_{null}": f.value, f"fpr_{null}_ci_low": f.ci_low, f"fpr_{null}_ci_high": f.ci_high,
                            f"fpr_{null}_verdict": f.verdict, f"n_none_{null}": int(f.n)})
            acc = dn[dn.metric.str.startswith("accuracy_at_") & dn.effect.isin(EFFECT_IDS)]
            for metric, a in acc.groupby("metric", sort=True):
                row[f"{metric}_{null}_mean_over_effects"] = float(a.value.mean())
            for what, sel in (("pair", dn.effect.str.contains("+", regex=False)), ("outlier", dn.effect == OUTLIER)):
                for r in dn[sel & dn.metric.str.startswith("accuracy_at_")].itertuples():
                    row[f"{what}_{r.metric}_{null}"] = r.value
            for r in dn[dn.metric.isin(["oracle_agreement", "false_outlier_rate"])
                        | dn.metric.str.startswith("outlier_power_at_")].itertuples():
                row.update({f"{r.metric}_{null}": r.value, f"{r.metric}_{null}_ci_low": r.ci_low,
                            f"{r.metric}_{null}_ci_high": r.ci_high})
                if r.metric == "oracle_agreement":
                    row[f"oracle_agreement_{null}_verdict"] = r.verdict
        rows.append(row)
    return pd.DataFrame(rows)


__all__ = [
    "ACCURACY_RULE",
    "FPR_RULE",
    "NOTHING_NAMED",
    "ORACLE",
    "ORACLE_RULE",
    "REFERENCE",
    "REFERENCE_RULE",
    "ORACLE_TARGET",
    "SUMMARY_COLUMNS",
    "accuracy_verdict",
    "clopper_pearson",
    "crossing",
    "effective_n",
    "fpr_verdict",
    "headline",
    "interval",
    "oracle_differences",
    "rates",
    "score_cases",
    "summary",
]
