"""The paper's qualitative conclusions as checks on the result tables.

Each check takes the summary tables of the Monte Carlo (:func:`accelcal_repro.montecarlo.summarize`
and :func:`accelcal_repro.montecarlo.compare_methods`, or the timing summary) and the experiment
it is about, applies a rule whose thresholds come from the config, and returns a
:class:`Check`: the number behind the verdict, whether the rule holds, and the numbers
per grid level for the ledger's evidence.  The claims ledger
(:mod:`accelcal_repro.burkhard2024.claims`) and the tests call the same functions, so a test
that feeds them a table from a deliberately wrong estimator shows that the ledger's
verdict would flip.

A grid level that is missing or has no valid trial makes a check fail (its number is
NaN): a verdict is never drawn from fewer levels than the experiment has.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal.registry import model_of

from ..montecarlo import min_poses
from ..timing import preferred_backend
from .grid import Experiment, select


@dataclass(frozen=True)
class Check:
    """Outcome of one rule: ``value`` (the number reported), ``passed`` and ``detail``."""

    value: float
    passed: bool
    detail: str

    def __bool__(self) -> bool:
        return bool(self.passed) and math.isfinite(self.value)


def _fmt(x: float, spec: str = ".3g") -> str:
    return "nan" if not np.isfinite(x) else format(x, spec)


def in_range(values: pd.Series, lo: float, hi: float) -> pd.Series:
    """Mask of the noise levels in the closed interval [lo, hi] (relative tolerance 1e-9)."""
    return (values >= lo * (1 - 1e-9)) & (values <= hi * (1 + 1e-9))


def _levels(table: pd.DataFrame, exp: Experiment, noise_range: Sequence[float] | None = None) -> pd.DataFrame:
    t = select(table, exp)
    if noise_range is not None:
        t = t[in_range(t["noise_std"], *noise_range)]
    return t


def _expected_levels(exp: Experiment, noise_range=None) -> list[float]:
    lv = sorted(exp.noise_std)
    if noise_range is not None:
        lo, hi = noise_range
        lv = [s for s in lv if lo * (1 - 1e-9) <= s <= hi * (1 + 1e-9)]
    return lv


def _pair(comparisons: pd.DataFrame, exp: Experiment, method: str, reference: str, noise_range=None) -> pd.DataFrame:
    c = _levels(comparisons, exp, noise_range)
    return c[(c["method"] == method) & (c["reference"] == reference)].sort_values(["noise_std", "g_error"])


# --------------------------------------------------------------------------- Fig. 1(a)
def full_lls_equals_nlls(summary: pd.DataFrame, comparisons: pd.DataFrame, exp: Experiment,
                         noise_range: Sequence[float], rel_tol: float, efficiency_tol: float, z: float) -> Check:
    """Fig. 1(a): full LLS ≈ full NLLS, and both good.

    Rule: at every noise level of ``exp`` in ``noise_range`` the paired RMS bias error
    ratio full LLS / full NLLS is within ``rel_tol`` of 1, and both RMS errors are at most
    ``1 + efficiency_tol`` times the CRLB (plus ``z`` standard errors of the ratio).
    Value: the largest ``|LLS/NLLS - 1|`` (%).
    """
    levels = _expected_levels(exp, noise_range)
    pair = _pair(comparisons, exp, "full_lls", "full_nlls", noise_range).set_index("noise_std")
    s = _levels(summary, exp, noise_range).set_index(["noise_std", "method"])
    worst, ok, parts = 0.0, True, []
    for lv in levels:
        r = pair["bias_ratio"].get(lv, np.nan)
        eff = {m: (s["bias_ratio"].get((lv, m), np.nan), s["bias_ratio_se"].get((lv, m), np.nan))
               for m in ("full_lls", "full_nlls")}
        good = all(e <= 1 + efficiency_tol + z * se for e, se in eff.values())
        worst = max(worst, abs(r - 1)) if np.isfinite(r) else np.nan
        ok &= bool(np.isfinite(r) and abs(r - 1) <= rel_tol and good)
        parts.append(f"{lv:g}: LLS/NLLS {_fmt(r, '.4f')}, RMS/CRLB LLS {_fmt(eff['full_lls'][0], '.2f')} "
                     f"NLLS {_fmt(eff['full_nlls'][0], '.2f')}")
    if not levels:
        worst, ok = np.nan, False
    return Check(100 * worst, ok, "; ".join(parts))


def bias_lls_better_than_nlls(comparisons: pd.DataFrame, exp: Experiment, noise_range: Sequence[float],
                              z: float) -> Check:
    """Fig. 1(a): bias-only LLS better than bias-only NLLS (data with M ≠ I).

    Rule: at every noise level in ``noise_range`` the paired ratio RMS(bias-only LLS) /
    RMS(bias-only NLLS) of the bias error plus ``z`` standard errors is below 1.
    Value: the largest ratio over the levels.
    """
    levels = _expected_levels(exp, noise_range)
    pair = _pair(comparisons, exp, "bias_lls", "bias_nlls", noise_range).set_index("noise_std")
    worst, ok, parts = -np.inf, bool(levels), []
    for lv in levels:
        r, se = pair["bias_ratio"].get(lv, np.nan), pair["bias_ratio_se"].get(lv, np.nan)
        worst = max(worst, r) if np.isfinite(r) else np.nan
        ok &= bool(np.isfinite(r) and r + z * se < 1)
        parts.append(f"{lv:g}: {_fmt(r, '.3f')} ± {_fmt(se, '.1g')}")
    return Check(float(worst) if levels else np.nan, ok, "; ".join(parts))


# --------------------------------------------------------------------------- max relative errors
def max_relative_errors(summary: pd.DataFrame, exp: Experiment, noise_range: Sequence[float],
                        methods: Sequence[str] = ("full_lls", "full_nlls")) -> pd.DataFrame:
    """Largest RMS relative scale-factor and non-orthogonality error [%] over the noise
    levels in ``noise_range``, per method, and the noise level where it occurs."""
    s = _levels(summary, exp, noise_range)
    n_levels = len(_expected_levels(exp, noise_range))
    rows = []
    for m in methods:
        d = s[s["method"] == m]
        row = {"method": m}
        for q in ("scale", "nonorth"):
            col = d[f"{q}_rel_rms"]
            complete = len(d) == n_levels and col.notna().all() and n_levels > 0
            row[f"{q}_max_pct"] = 100 * float(col.max()) if complete else np.nan
            row[f"{q}_at_noise"] = float(d.loc[col.idxmax(), "noise_std"]) if complete else np.nan
        rows.append(row)
    return pd.DataFrame(rows)


def max_errors_match_paper(summary: pd.DataFrame, exp: Experiment, noise_range: Sequence[float],
                           paper_scale_pct: float, paper_nonorth_pct: float, factor: float) -> Check:
    """'Max errors across the noise range ≈ 0.5 % (scale factor) and ≈ 1 % (non-orthogonality)'.

    Reading: the error of one calibration relative to the true value,
    ``||ŝ - s|| / ||s||`` and ``||θ̂ - θ|| / ||θ||``, RMS over the Monte Carlo trials, at the
    noise level where it is largest.  Rule: for full LLS and full NLLS both maxima lie
    within a factor ``factor`` of the paper's values.  Value: the larger of the two
    measured/paper ratios, farthest from 1 (log scale).
    """
    t = max_relative_errors(summary, exp, noise_range)
    ratios, parts = [], []
    for _, r in t.iterrows():
        rs, rn = r["scale_max_pct"] / paper_scale_pct, r["nonorth_max_pct"] / paper_nonorth_pct
        ratios += [rs, rn]
        parts.append(f"{r['method']}: scale {_fmt(r['scale_max_pct'], '.3g')}% (at {_fmt(r['scale_at_noise'], 'g')}), "
                     f"non-orth. {_fmt(r['nonorth_max_pct'], '.3g')}% (at {_fmt(r['nonorth_at_noise'], 'g')})")
    ratios = np.array(ratios, float)
    worst = float(ratios[np.argmax(np.abs(np.log(ratios)))]) if len(ratios) and np.isfinite(ratios).all() else np.nan
    ok = bool(np.isfinite(worst) and np.all((ratios >= 1 / factor) & (ratios <= factor)))
    return Check(worst, ok, "; ".join(parts))


def errors_same_for_lls_and_nlls(comparisons: pd.DataFrame, exp: Experiment, noise_range: Sequence[float],
                                 rel_tol: float) -> Check:
    """'… the same for both methods': paired RMS scale-factor and non-orthogonality errors
    of full LLS and full NLLS within ``rel_tol`` at every noise level.  Value: the
    largest ``|LLS/NLLS - 1|`` (%) of the two quantities."""
    levels = _expected_levels(exp, noise_range)
    pair = _pair(comparisons, exp, "full_lls", "full_nlls", noise_range).set_index("noise_std")
    worst, parts = (0.0 if levels else np.nan), []
    for lv in levels:
        rs, rn = pair["scale_ratio"].get(lv, np.nan), pair["nonorth_ratio"].get(lv, np.nan)
        d = max(abs(rs - 1), abs(rn - 1))
        worst = max(worst, d) if np.isfinite(d) else np.nan
        parts.append(f"{lv:g}: scale {_fmt(rs, '.4f')}, non-orth. {_fmt(rn, '.4f')}")
    return Check(100 * worst, bool(np.isfinite(worst) and worst <= rel_tol), "; ".join(parts))


# --------------------------------------------------------------------------- Fig. 1(b)
def decreases_with_poses(summary: pd.DataFrame, exp: Experiment, factor: float, z: float) -> Check:
    """Fig. 1(b): the estimation error decreases with the number of poses, for every
    entity (bias for every method; scale factor and non-orthogonality for the full ones).

    Rule: for every method and entity, the RMS error at the largest pose count is at most
    ``1/factor`` of the RMS at the smallest pose count the method accepts, and no step to
    the next pose count raises it by more than ``z`` combined standard errors.
    Value: the smallest first/last ratio over methods and entities.
    """
    s = _levels(summary, exp)
    drops, ok, parts = [], True, []
    for m in exp.methods:
        d = s[s["method"] == m].sort_values("n_poses")
        expected = [n for n in sorted(exp.n_poses) if n >= min_poses(m)]
        for q in (("bias",) if model_of(m) == "bias" else ("bias", "scale", "nonorth")):
            rms, se = d[f"{q}_rms"].to_numpy(float), d[f"{q}_rms_se"].to_numpy(float)
            if d["n_poses"].tolist() != expected or len(rms) < 2 or not np.isfinite(rms).all():
                drops.append(np.nan)
                parts.append(f"{m} {q}: incomplete")
                continue
            drop = rms[0] / rms[-1]
            rises = [(int(a), int(b)) for a, b, r0, r1, s0, s1 in
                     zip(d["n_poses"][:-1], d["n_poses"][1:], rms[:-1], rms[1:], se[:-1], se[1:])
                     if r1 - r0 > z * np.hypot(s0, s1)]
            drops.append(drop)
            ok &= bool(drop >= factor and not rises)
            parts.append(f"{m} {q}: {expected[0]}→{expected[-1]} poses {drop:.3g}×"
                         + (f", rises at {rises}" if rises else ""))
    worst = float(min(drops)) if drops and np.isfinite(drops).all() else np.nan
    return Check(worst, ok and np.isfinite(worst), "; ".join(parts))


# --------------------------------------------------------------------------- Fig. 1(c)-(e)
def _by_g(summary: pd.DataFrame, exp: Experiment, method: str, col: str) -> pd.Series:
    d = _levels(summary, exp)
    d = d[d["method"] == method]
    return d.set_index("g_error")[col].sort_index().reindex(sorted(exp.g_error))


def lls_flat_nlls_diverges(summary: pd.DataFrame, exp: Experiment, flat_tol: float, factor: float) -> Check:
    """Fig. 1(c) (data with M ≠ I) and 1(e) (M = I): bias-only NLLS diverges with the error
    in the assumed g, bias-only LLS stays low and constant.

    Rule: the RMS bias error of bias-only LLS stays within ``flat_tol`` (relative) of its
    value at g error 0 at every g error; bias-only NLLS's RMS at the largest g error is at
    least ``factor`` times its value at g error 0 and at least ``factor`` times bias-only
    LLS's there.  Value: RMS(NLLS) / RMS(LLS) at the largest g error.
    """
    lls, nlls = _by_g(summary, exp, "bias_lls", "bias_rms"), _by_g(summary, exp, "bias_nlls", "bias_rms")
    if 0.0 not in lls.index or len(lls) < 2 or lls.isna().any() or nlls.isna().any():
        return Check(np.nan, False, "g error 0 or a level missing (the rule compares with g error 0)")
    flat = float((lls / lls[0.0] - 1).abs().max())
    grow = float(nlls.iloc[-1] / nlls[0.0])
    apart = float(nlls.iloc[-1] / lls.iloc[-1])
    detail = (f"bias-only LLS RMS {_fmt(lls[0.0])} m/s² at g error 0, largest change {100 * flat:.3g}%; "
              f"bias-only NLLS {_fmt(nlls[0.0])} → {_fmt(nlls.iloc[-1])} m/s² at g error {lls.index[-1]:g} m/s² "
              f"({grow:.3g}×); NLLS/LLS there {apart:.3g}× (per g error: "
              + ", ".join(f"{g:g}: {_fmt(a)}/{_fmt(b)}" for g, a, b in zip(lls.index, nlls, lls)) + ")")
    return Check(apart, flat <= flat_tol and grow >= factor and apart >= factor, detail)


def scale_error_sensitive_to_g(summary: pd.DataFrame, exp: Experiment, factor: float) -> Check:
    """Fig. 1(d): the scale-factor error is highly sensitive to the error in g, for both
    full LLS and full NLLS.

    Rule: for both methods, the RMS scale-factor error at the largest g error is at least
    ``factor`` times its value at g error 0.  Value: the smaller of the two growth factors.
    """
    grows, parts = [], []
    for m in ("full_lls", "full_nlls"):
        v = _by_g(summary, exp, m, "scale_rms")
        rel = _by_g(summary, exp, m, "scale_rel_rms")
        if 0.0 not in v.index or len(v) < 2 or v.isna().any():
            return Check(np.nan, False, f"{m}: g error 0 or a level missing")
        grows.append(float(v.iloc[-1] / v[0.0]))
        parts.append(f"{m}: RMS ||ŝ - s|| {1e6 * v[0.0]:.3g} → {1e6 * v.iloc[-1]:.3g} ppm "
                     f"({_fmt(100 * rel[0.0])}% → {_fmt(100 * rel.iloc[-1])}% of ||s||) from g error 0 to "
                     f"{v.index[-1]:g} m/s²")
    worst = min(grows)
    return Check(worst, worst >= factor, "; ".join(parts))


def nonorth_error_in_range(summary: pd.DataFrame, exp: Experiment, range_pct: Sequence[float],
                           factor: float) -> Check:
    """Fig. 1(d) text: the non-orthogonality error 'has a range of 1 %–2 %' (not plotted).

    Reading: RMS of ``||θ̂ - θ|| / ||θ||`` over the trials.  Rule: for full LLS and full
    NLLS at every g error it lies in ``[range_pct[0] / factor, range_pct[1] * factor]``.
    Value: the largest of these RMS values (%).
    """
    lo, hi = range_pct[0] / factor, range_pct[1] * factor
    vals, parts = [], []
    for m in ("full_lls", "full_nlls"):
        v = 100 * _by_g(summary, exp, m, "nonorth_rel_rms")
        vals += v.tolist()
        parts.append(f"{m}: {_fmt(v.min())}–{_fmt(v.max())}% over g errors {v.index.min():g}–{v.index.max():g} m/s²")
    vals = np.array(vals, float)
    if not len(vals) or not np.isfinite(vals).all():
        return Check(np.nan, False, "; ".join(parts) or "no rows")
    return Check(float(vals.max()), bool(np.all((vals >= lo) & (vals <= hi))), "; ".join(parts))


# --------------------------------------------------------------------------- compute time
def speedup(timing_summary: pd.DataFrame, method: str, n_poses: int, interleave: str, min_ratio: float,
            backend: str | None = None) -> Check:
    """Speed-up of an LLS over its NLLS baseline: the median of the paired per-problem
    ratios t_NLLS / t_LLS at ``n_poses`` (``interleave`` timings), of the ``backend``
    (default: the library's default, the compiled kernels if they were timed).  Rule:
    ≥ ``min_ratio``."""

    t = timing_summary
    if "backend" in t:
        backend = backend if backend is not None else preferred_backend(t, method)
        t = t[t["backend"] == backend]
    sel = t[(t["mode"] == "single") & (t["method"] == method) & (t["interleave"] == interleave)
            & (t["n_poses"] == n_poses)]
    if len(sel) != 1:
        return Check(np.nan, False, f"timing summary has {len(sel)} rows for {method} ({interleave}, {n_poses} poses)")
    r = sel.iloc[0]
    which = f" [{backend}]" if backend else ""
    detail = (f"median paired ratio {r['baseline']}/{method}{which} = {r['speedup_median']:.1f}x "
              f"(IQR {r['speedup_q25']:.1f}-{r['speedup_q75']:.1f}x, n={int(r['n_timings'])}; "
              f"median {1e6 * r['median_s']:.0f} us vs {1e6 * r['median_s'] * r['speedup_of_medians']:.0f} us)")
    return Check(float(r["speedup_median"]), bool(r["speedup_median"] >= min_ratio), detail)


__all__ = [
    "Check",
    "bias_lls_better_than_nlls",
    "decreases_with_poses",
    "errors_same_for_lls_and_nlls",
    "full_lls_equals_nlls",
    "in_range",
    "lls_flat_nlls_diverges",
    "max_errors_match_paper",
    "max_relative_errors",
    "nonorth_error_in_range",
    "scale_error_sensitive_to_g",
    "speedup",
]
