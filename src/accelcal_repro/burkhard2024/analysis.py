"""Derived tables of the Burkhard stage: the scale-factor and non-orthogonality errors
across the noise range (several readings of the paper's "about 0.5 % and 1 %"), and
where the algebraic LLS stops being as good as NLLS and the Cramér–Rao bound.

Both work on the tables of :mod:`accelcal_repro.montecarlo` (tidy table, :func:`summarize`,
:func:`compare_methods`); :func:`efficiency` shows that the NLLS baseline, stopped at
the accuracy the problem needs (:func:`accelcal.nlls.solver_tol`), stays on the
Cramér–Rao bound across the noise range, and how many iterations that takes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd

from accelcal.nlls import solver_tol
from accelcal.registry import ESTIMATORS, estimators

from ..montecarlo import AXES, FULL_METHODS, QUANTITIES, rms_and_se
from .checks import in_range
from .grid import Experiment, select


def efficiency(summary: pd.DataFrame, experiments: Iterable[Experiment], g: float) -> pd.DataFrame:
    """Monte Carlo RMS error / Cramér–Rao bound per noise level × method (each quantity,
    with its standard error), the NLLS iteration counts, and IPOPT's tolerance at that
    noise (:func:`accelcal.nlls.solver_tol` for poses on a sphere of radius ``g``),
    over the grid points of ``experiments`` (the Fig. 1(a) noise range: full methods on
    M != I data, bias-only methods on M = I data, where their bounds hold).
    """

    parts = []
    for exp in experiments:
        t = select(summary, exp)
        parts.append(t[t["model"] == exp.data_model])
    t = pd.concat(parts, ignore_index=True).drop_duplicates(["data_model", "n_poses", "noise_std", "g_error", "method"])
    cols = ["data_model", "n_poses", "noise_std", "method", "n_valid"]
    for q in QUANTITIES:
        cols += [f"{q}_ratio", f"{q}_ratio_se"]
    cols += ["iterations_mean", "iterations_max"]
    out = t[cols].sort_values(["data_model", "n_poses", "noise_std", "method"], kind="stable", ignore_index=True)
    stops_at_noise = out["method"].map(lambda m: ESTIMATORS[m].noise_use == "stopping").astype(bool)
    out["ipopt_tol"] = np.where(stops_at_noise, [solver_tol(s, g) for s in out["noise_std"]], np.nan)
    return out


def relative_errors(tidy: pd.DataFrame, exp: Experiment, noise_range: Sequence[float],
                    methods: Sequence[str] = FULL_METHODS) -> pd.DataFrame:
    """Scale-factor and non-orthogonality errors per noise level × method, absolute and
    relative to the true value, in three readings of "the estimation error":

    * ``*_rel_rms_pct`` (the project's reading): RMS over trials of ``||ŝ - s|| / ||s||``
      (resp. θ): the typical error of one calibration, in % of the true value.
    * ``*_rel_median_pct``: median over trials and axes of ``|ŝ_i - s_i| / |s_i|``.
    * ``*_rel_mean_pct``: the largest over the axes of ``|mean over trials of
      (ŝ_i - s_i) / |s_i||``: a systematic error only; it shrinks as 1/sqrt(trials) for
      an unbiased estimator, so it depends on the number of Monte Carlo runs.

    Plus the absolute RMS errors ``scale_rms_ppm`` and ``nonorth_rms_deg`` (norm over the
    three axes) and ``in_paper_range`` (the noise level lies in ``noise_range``).
    """
    t = select(tidy, exp)
    t = t[t["method"].isin(methods) & t["valid"].astype(bool)]
    rows = []
    for (noise, method), d in t.groupby(["noise_std", "method"], sort=True):
        row = {"noise_std": noise, "method": method, "n_valid": len(d)}
        for q, unit, scale in (("scale", "ppm", 1e6), ("nonorth", "deg", np.rad2deg(1.0))):
            err = d[[f"{q}_err_{a}" for a in AXES[q]]].to_numpy(float)
            true = d[[f"true_{q}_{a}" for a in AXES[q]]].to_numpy(float)
            rel_norm = np.linalg.norm(err, axis=1) / np.linalg.norm(true, axis=1)
            rel = err / np.abs(true)
            row[f"{q}_rms_{unit}"] = scale * rms_and_se(d[f"{q}_err_norm"])[0]
            row[f"{q}_rel_rms_pct"] = 100 * rms_and_se(rel_norm)[0]
            row[f"{q}_rel_median_pct"] = 100 * float(np.median(np.abs(rel)))
            row[f"{q}_rel_mean_pct"] = 100 * float(np.max(np.abs(rel.mean(axis=0))))
        rows.append(row)
    out = pd.DataFrame(rows)
    if len(out):
        out.insert(2, "in_paper_range", in_range(out["noise_std"], *noise_range))
    return out


#: The estimators of the limit analysis per data set, by algorithm (``lls``, ``als``, ``nlls``).
LIMIT_METHODS = {dm: {e.algorithm: e.name for e in estimators("accelerometer", model=dm)} for dm in ("full", "bias")}
#: Which comparisons it makes, per data set: (name, method, reference): every estimator
#: against its baseline (``lls_vs_nlls``).
LIMIT_PAIRS = {dm: tuple((f"{e.algorithm}_vs_{ESTIMATORS[e.baseline].algorithm}", e.name, e.baseline)
                         for e in estimators("accelerometer", model=dm) if e.baseline)
               for dm in ("full", "bias")}


def _worse(r: float, se: float, z: float, min_effect: float) -> bool:
    """``r`` (an RMS ratio) is measurably above 1: by more than z standard errors and by
    more than ``min_effect`` (relative)."""
    return bool(np.isfinite(r) and r - 1 > max(z * se, min_effect))


def lls_limit(summary: pd.DataFrame, comparisons: pd.DataFrame, experiments: Iterable[Experiment],
              z: float, min_effect: float) -> pd.DataFrame:
    """Where the algebraic LLS becomes measurably worse than NLLS and the CRLB.

    One row per data set × pose count × noise level × quantity (bias, scale,
    non-orthogonality) of the given experiments (at g error 0): the paired RMS ratios
    LLS/NLLS and ALS/NLLS, each method's RMS / CRLB, their standard errors, the valid
    trial counts, and flags ``*_worse`` (ratio above 1 by more than ``z`` standard errors
    and by more than ``min_effect``).
    """
    rows = []
    for exp in experiments:
        s = select(summary, exp)
        c = select(comparisons, exp)
        s, c = s[s["g_error"] == 0.0], c[c["g_error"] == 0.0]
        dm = exp.data_model
        for (n, noise), d in s.groupby(["n_poses", "noise_std"], sort=True):
            by = d.set_index("method")
            cc = c[(c["n_poses"] == n) & (c["noise_std"] == noise)]
            for q in QUANTITIES:
                if dm == "bias" and q != "bias":
                    continue
                row = {"data_model": dm, "n_poses": n, "noise_std": noise, "quantity": q}
                for short, m in LIMIT_METHODS[dm].items():
                    if m in by.index:
                        row[f"{short}_n_valid"] = int(by.loc[m, "n_valid"])
                        row[f"{short}_crlb"] = by.loc[m, f"{q}_ratio"]
                        row[f"{short}_crlb_se"] = by.loc[m, f"{q}_ratio_se"]
                        row[f"{short}_crlb_worse"] = _worse(row[f"{short}_crlb"], row[f"{short}_crlb_se"], z,
                                                            min_effect)
                for name, m, ref in LIMIT_PAIRS[dm]:
                    p = cc[(cc["method"] == m) & (cc["reference"] == ref)]
                    if len(p):
                        row[name] = float(p[f"{q}_ratio"].iloc[0])
                        row[f"{name}_se"] = float(p[f"{q}_ratio_se"].iloc[0])
                        row[f"{name}_worse"] = _worse(row[name], row[f"{name}_se"], z, min_effect)
                rows.append(row)
    out = pd.DataFrame(rows)
    if len(out):
        out = (out.drop_duplicates(["data_model", "n_poses", "noise_std", "quantity"])
               .sort_values(["data_model", "quantity", "n_poses", "noise_std"], kind="stable", ignore_index=True))
    return out


def limit_onsets(limit: pd.DataFrame) -> pd.DataFrame:
    """Per data set × pose count × quantity, the smallest noise level of the grid at which

    * ``onset_noise``: LLS is measurably worse than both NLLS and the CRLB (the question);
    * ``lls_above_crlb_from``, ``lls_worse_than_nlls_from``, ``nlls_above_crlb_from``,
      ``als_above_crlb_from``, ``als_worse_than_nlls_from``: each condition alone;

    NaN where it never happens up to ``max_noise_checked``.  At ``onset_noise`` also the
    ratios LLS/NLLS, LLS/CRLB, NLLS/CRLB and, for the full model, ALS/NLLS, ALS/CRLB and
    ``als_closes_gap`` (ALS measurably worse than neither NLLS nor the CRLB there).
    An onset at the smallest noise of the grid means "at every noise level": an
    inefficiency of the method, not an effect of the noise.
    """
    def flag(d, col):
        return d[col].fillna(False).astype(bool) if col in d else pd.Series(False, index=d.index)

    def first(d, mask):
        return float(d.loc[mask, "noise_std"].iloc[0]) if mask.any() else np.nan

    rows = []
    for (dm, n, q), d in limit.groupby(["data_model", "n_poses", "quantity"], sort=True):
        d = d.sort_values("noise_std")
        worse = flag(d, "lls_vs_nlls_worse") & flag(d, "lls_crlb_worse")
        row = {"data_model": dm, "n_poses": n, "quantity": q, "min_noise_checked": d["noise_std"].min(),
               "max_noise_checked": d["noise_std"].max(), "onset_noise": first(d, worse),
               "lls_above_crlb_from": first(d, flag(d, "lls_crlb_worse")),
               "lls_worse_than_nlls_from": first(d, flag(d, "lls_vs_nlls_worse")),
               "nlls_above_crlb_from": first(d, flag(d, "nlls_crlb_worse"))}
        if dm == "full":
            row["als_above_crlb_from"] = first(d, flag(d, "als_crlb_worse"))
            row["als_worse_than_nlls_from"] = first(d, flag(d, "als_vs_nlls_worse"))
        if worse.any():
            r = d[worse].iloc[0]
            row.update({"lls_vs_nlls": r.get("lls_vs_nlls"), "lls_crlb": r.get("lls_crlb"),
                        "nlls_crlb": r.get("nlls_crlb")})
            if np.isfinite(r.get("als_vs_nlls", np.nan)):
                row.update({"als_vs_nlls": r["als_vs_nlls"], "als_crlb": r["als_crlb"],
                            "als_closes_gap": not (bool(r["als_vs_nlls_worse"]) or bool(r["als_crlb_worse"]))})
        rows.append(row)
    return pd.DataFrame(rows)


__all__ = ["LIMIT_METHODS", "LIMIT_PAIRS", "efficiency", "limit_onsets", "lls_limit", "relative_errors"]
