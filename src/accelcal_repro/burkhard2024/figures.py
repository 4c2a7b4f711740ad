"""Figures of the Burkhard stage: every panel of Fig. 1, the compute time and the LLS limit.

Each function takes the stage's tables (:func:`accelcal_repro.montecarlo.summarize` output,
the timing summaries, the limit table) and the experiment it draws, and returns a
Figure; :func:`accelcal.plotting.save_figure` writes it.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from accelcal.plotting import RC as _RC, style
from accelcal.registry import model_of
from .claims import PAPER_NONORTH_RANGE_PCT, PAPER_SPEEDUP
from .grid import Experiment, select

PAPER_RANGE_COLOR = "0.92"
RC = {**_RC, "axes.titlesize": 8.5}


def _kw(method: str, **extra) -> dict:
    st = style(method)
    kw = {"color": st["color"], "marker": st["marker"], "label": st["label"], "ms": 4, "lw": 1.1, "mfc": "none"}
    kw.update(extra)
    return kw


def _crlb_line(ax, d: pd.DataFrame, x: str, col: str, label: str, ls: str = "--", scale: float = 1.0) -> None:
    b = d.dropna(subset=[col]).groupby(x)[col].mean()
    if len(b):
        ax.plot(b.index, scale * b.values, ls=ls, color="k", lw=1.1, label=label, zorder=1)


def _paper_span(ax, lo: float, hi: float) -> None:
    ax.axvspan(lo, hi, color=PAPER_RANGE_COLOR, zorder=0, lw=0)


def _symlog_g(ax, g_errors) -> None:
    pos = sorted(g for g in g_errors if g > 0)
    ax.set_xscale("symlog", linthresh=pos[0] if pos else 1e-6, linscale=0.6)
    ax.set_xlim(-0.0 if not pos else 0, max(pos) * 1.6 if pos else 1)
    ax.set_xlabel("error in the assumed g [m/s²] (symlog: 0 at the left)")


def plot_fig1a(summary: pd.DataFrame, exp: Experiment, efficiency: Experiment, paper_range=(1e-7, 1e-3)):
    """Fig. 1(a): RMS bias error vs noise (24 poses, data with M ≠ I) with the full-model
    CRLB; (b) efficiency RMS / CRLB: full methods on the same data against the full-model
    bound, bias-only methods on data with M = I against the bias-only bound."""
    a = select(summary, exp)
    eff = select(summary, efficiency)
    with plt.rc_context(RC):
        fig, (ax, axr) = plt.subplots(1, 2, figsize=(7.6, 3.6), layout="constrained")
        if len(a) and (a["noise_std"].min() < paper_range[0] or a["noise_std"].max() > paper_range[1]):
            _paper_span(ax, *paper_range)  # grey: the paper's range, where the grid goes beyond it
        _crlb_line(ax, a[a["model"] == "full"], "noise_std", "bias_crlb_rms", "CRLB, full model")
        for m in exp.methods:
            d = a[a["method"] == m].sort_values("noise_std")
            ax.plot(d["noise_std"], d["bias_rms"], **_kw(m, ls="-" if model_of(m) == "full" else "--"))
        ax.set(xscale="log", yscale="log", xlabel="noise std per axis [m/s²]", ylabel="RMS bias error [m/s²]",
               title=f"(a) bias error, {exp.n_poses[0]} poses, data M ≠ I")
        ax.legend(loc="upper left", fontsize=7)
        ax.text(0.98, 0.03, "bias-only methods are misspecified here:\nno bound applies to them",
                transform=ax.transAxes, ha="right", va="bottom", fontsize=6.5)
        rows = [(a, m, "M ≠ I, full bound") for m in exp.methods if model_of(m) == "full"]
        rows += [(eff, m, "M = I, bias-only bound") for m in efficiency.methods]
        lo_hi = []
        for k, (t, m, what) in enumerate(rows):
            d = t[t["method"] == m].sort_values("noise_std")
            dodge = 10 ** (0.05 * (k - (len(rows) - 1) / 2))
            axr.errorbar(d["noise_std"] * dodge, d["bias_ratio"], yerr=d["bias_ratio_se"], capsize=2,
                         elinewidth=0.7, **_kw(m, label=f"{style(m)['label']} ({what})"))
            lo_hi += list(d["bias_ratio"] - d["bias_ratio_se"]) + list(d["bias_ratio"] + d["bias_ratio_se"])
        axr.axhline(1.0, color="k", ls="--", lw=1)
        lo_hi = np.array(lo_hi, float)
        lo_hi = lo_hi[np.isfinite(lo_hi)]
        axr.set_ylim(min(0.8, lo_hi.min() - 0.05) if len(lo_hi) else 0.8,
                     max(1.2, lo_hi.max() + 0.05) if len(lo_hi) else 1.2)
        axr.set(xscale="log", xlabel="noise std per axis [m/s²]", ylabel="RMS bias error / CRLB (± 1 s.e.)",
                title="(b) RMS / CRLB of each model")
        n = int(min(a["n_valid"].min(), eff["n_valid"].min())) if len(a) and len(eff) else 0
        axr.legend(loc="upper left", fontsize=6.3, title=f"≥ {n} valid trials per point", title_fontsize=6.5)
    return fig


def plot_fig1b(summary: pd.DataFrame, exp: Experiment):
    """Fig. 1(b): RMS bias error vs number of poses (every method, data with M ≠ I) with
    the full-model CRLB; (b) the relative scale-factor and non-orthogonality errors of the
    full methods ("all entities")."""
    b = select(summary, exp)
    with plt.rc_context(RC):
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(7.6, 3.6), layout="constrained")
        _crlb_line(ax, b[b["model"] == "full"], "n_poses", "bias_crlb_rms", "CRLB, full model")
        for m in exp.methods:
            d = b[b["method"] == m].sort_values("n_poses")
            ax.errorbar(d["n_poses"], d["bias_rms"], yerr=d["bias_rms_se"], capsize=2, elinewidth=0.7,
                        **_kw(m, ls="-" if model_of(m) == "full" else "--"))
        ax.set(xscale="log", yscale="log", xlabel="number of poses", ylabel="RMS bias error [m/s²]",
               title=f"(a) bias error, σ = {exp.noise_std[0]:g} m/s², M ≠ I")
        ax.legend(loc="upper right", fontsize=7)
        for m in (m for m in exp.methods if model_of(m) == "full"):
            d = b[b["method"] == m].sort_values("n_poses")
            ax2.plot(d["n_poses"], 100 * d["scale_rel_rms"], **_kw(m, label=f"{style(m)['label']}: scale factor"))
            ax2.plot(d["n_poses"], 100 * d["nonorth_rel_rms"],
                     **_kw(m, ls=":", label=f"{style(m)['label']}: non-orthogonality"))
        ax2.set(xscale="log", yscale="log", xlabel="number of poses", ylabel="RMS relative error [%]",
                title="(b) scale factor, non-orthogonality")
        ax2.legend(loc="upper right", fontsize=6.5)
    return fig


def _plot_vs_g(ax, s: pd.DataFrame, exp: Experiment, methods, col: str, scale: float = 1.0) -> None:
    for m in methods:
        d = s[s["method"] == m].sort_values("g_error")
        if len(d):
            ls = "-" if model_of(m) == "bias" else ":"
            ax.plot(d["g_error"], scale * d[col], **_kw(m, ls=ls, lw=1.4 if model_of(m) == "bias" else 0.9))


def plot_fig1c(summary: pd.DataFrame, exp: Experiment, title: str = "(c)", data_label: str = "M ≠ I"):
    """Fig. 1(c) (and 1(e) with ``exp`` on data with M = I): RMS bias error vs error in the
    assumed g; bias-only LLS/NLLS (solid), full LLS/NLLS where run (dotted), and the
    bias-only CRLB where it applies (M = I data)."""
    s = select(summary, exp)
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(5.4, 3.8), layout="constrained")
        _crlb_line(ax, s[(s["model"] == "bias") & (s["g_error"] >= 0)], "g_error", "bias_crlb_rms",
                   "CRLB, bias-only model (known g)")
        _plot_vs_g(ax, s, exp, [m for m in ("bias_lls", "bias_nlls", "full_lls", "full_nlls") if m in exp.methods],
                   "bias_rms")
        ax.set_yscale("log")
        _symlog_g(ax, exp.g_error)
        ax.set_ylabel("RMS bias error [m/s²]")
        ax.set_title(f"{title} bias error vs error in g ({exp.n_poses[0]} poses, σ = {exp.noise_std[0]:g} m/s², "
                     f"data {data_label})", fontsize=8.5)
        ax.legend(loc="upper left", fontsize=7)
    return fig


def plot_fig1d(summary: pd.DataFrame, exp: Experiment, g: float):
    """Fig. 1(d): (a) RMS scale-factor error of full LLS and NLLS vs error in the assumed g,
    with the error a pure g mismatch causes (``sqrt(3) δg / g``) and the CRLB at g error 0;
    (b) the RMS relative non-orthogonality error (paper: 1 %–2 %, not plotted there)."""
    s = select(summary, exp)
    methods = [m for m in ("full_lls", "full_als", "full_nlls") if m in exp.methods]
    with plt.rc_context(RC):
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(7.6, 3.6), layout="constrained")
        _plot_vs_g(ax, s, exp, methods, "scale_rms", scale=1e6)
        pos = np.array(sorted(x for x in exp.g_error if x > 0))
        if len(pos):
            ax.plot(pos, 1e6 * np.sqrt(3) * pos / g, color="0.5", lw=3, alpha=0.4, label="√3 δg / g (g mismatch alone)",
                    zorder=0)
        c0 = s[(s["g_error"] == 0) & (s["method"] == "full_nlls")]["scale_crlb_rms"]
        if len(c0):
            ax.axhline(1e6 * float(c0.iloc[0]), color="k", ls="--", lw=1, label="CRLB at g error 0")
        ax.set_yscale("log")
        _symlog_g(ax, exp.g_error)
        ax.set(ylabel="RMS scale-factor error ||ŝ - s|| [ppm]",
               title=f"(a) scale factor, {exp.n_poses[0]} poses, σ = {exp.noise_std[0]:g} m/s²")
        ax.legend(loc="upper left", fontsize=6.8)
        lo, hi = PAPER_NONORTH_RANGE_PCT
        ax2.axhspan(lo, hi, color=PAPER_RANGE_COLOR, label="paper: 1 %–2 %", zorder=0)
        _plot_vs_g(ax2, s, exp, methods, "nonorth_rel_rms", scale=100)
        _symlog_g(ax2, exp.g_error)
        top = np.nanmax(100 * s["nonorth_rel_rms"]) if len(s) else hi
        ax2.set_ylim(0, max(2.5, 1.3 * top))
        ax2.set(ylabel="RMS ||θ̂ - θ|| / ||θ|| [%]", title="(b) non-orthogonality (relative)")
        ax2.legend(loc="lower left", fontsize=6.8)
    return fig


def plot_timing(timing_summary: pd.DataFrame, mc_timing: pd.DataFrame | None = None, interleave: str = "block",
                headline_n: int = 24):
    """Compute time: (a) median wall time per problem vs pose count for every method
    (bars: IQR; the compiled kernels solid, the numpy reference implementations dotted;
    dashed: batched closed forms per problem), (b) the speed-ups NLLS/LLS (median of paired
    per-problem ratios, bars: IQR) with the paper's values, and the ratio per Monte Carlo
    trial (batched closed form, loops for NLLS) where available."""
    t = timing_summary if "backend" in timing_summary else timing_summary.assign(backend="")
    single = t[(t["mode"] == "single") & (t["interleave"] == interleave)]
    batch = t[t["mode"] == "batch"]

    def backends(d, m):
        """(backend, line style, label suffix) of the rows of method ``m``: compiled first."""
        bes = sorted(set(d.loc[d["method"] == m, "backend"]), key=lambda b: (b != "numba", b))
        return [(b, "-" if b in ("numba", "", "casadi") or len(bes) == 1 else ":",
                 " (numpy)" if b == "numpy" and len(bes) > 1 else "") for b in bes]

    with plt.rc_context(RC):
        fig, (ax, axs) = plt.subplots(1, 2, figsize=(7.6, 4.6), layout="constrained")
        for m in ("full_lls", "full_als", "full_nlls", "bias_lls", "bias_nlls"):
            for be, ls, suffix in backends(single, m):
                d = single[(single["method"] == m) & (single["backend"] == be)].sort_values("n_poses")
                ax.errorbar(d["n_poses"], 1e6 * d["median_s"],
                            yerr=[1e6 * (d["median_s"] - d["q25_s"]), 1e6 * (d["q75_s"] - d["median_s"])],
                            capsize=2, elinewidth=0.7, **_kw(m, ls=ls, label=style(m)["label"] + suffix))
        for m in ("full_lls_batch", "bias_lls_batch"):
            for be, ls, suffix in backends(batch, m):
                d = batch[(batch["method"] == m) & (batch["backend"] == be)].sort_values("n_poses")
                ax.plot(d["n_poses"], 1e6 * d["median_s"], **_kw(m, ls="--" if ls == "-" else ":", marker="D", ms=3,
                                                                  label=style(m)["label"] + suffix))
        ax.set(xscale="log", yscale="log", xlabel="number of poses", ylabel="wall time per problem [µs]",
               title=f"(a) time per problem ({interleave}-interleaved)")
        ax.legend(fontsize=5.5, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
        for m, base in (("full_lls", "full_nlls"), ("bias_lls", "bias_nlls"), ("full_als", "full_nlls")):
            for be, ls, suffix in backends(single, m):
                d = single[(single["method"] == m) & (single["backend"] == be)].sort_values("n_poses")
                lab = f"{style(base)['label']} / {style(m)['label']}{suffix}"
                axs.errorbar(d["n_poses"], d["speedup_median"],
                             yerr=[d["speedup_median"] - d["speedup_q25"], d["speedup_q75"] - d["speedup_median"]],
                             capsize=2, elinewidth=0.7, **_kw(m, ls=ls, label=lab))
            if m in PAPER_SPEEDUP:
                axs.axhline(PAPER_SPEEDUP[m], color=style(m)["color"], ls=":", lw=1.2,
                            label=f"paper ≈{PAPER_SPEEDUP[m]:g}× ({'full' if model_of(m) == 'full' else 'bias-only'})")
        if mc_timing is not None and len(mc_timing):
            mt = mc_timing.pivot_table(index="n_poses", columns="method", values="per_trial_s")
            for m, base in (("full_lls", "full_nlls"), ("bias_lls", "bias_nlls")):
                if m in mt and base in mt:
                    r = (mt[base] / mt[m]).dropna()
                    axs.plot(r.index, r.values, ls="none", marker="*", ms=7, color=style(m)["color"], mfc="none",
                             label=f"per Monte Carlo trial ({'full' if model_of(m) == 'full' else 'bias-only'}, batched)")
        axs.axvline(headline_n, color="0.6", lw=0.8)
        axs.set(xscale="log", yscale="log", xlabel="number of poses", ylabel="speed-up NLLS / closed form",
                title="(b) speed-up NLLS / closed form")
        axs.legend(fontsize=5.5, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    return fig


#: Upper end of the RMS / CRLB axes of the limit figure; larger values are written as numbers.
LIMIT_YMAX = 3.0


def plot_lls_limit(limit: pd.DataFrame, onsets: pd.DataFrame | None = None):
    """Beyond the paper: RMS / CRLB of full LLS, ALS and NLLS vs noise, one row per pose
    count, one column per quantity (bias, scale factor, non-orthogonality); the onset
    where LLS becomes measurably worse than NLLS and the bound is marked."""
    d = limit[limit["data_model"] == "full"]
    ns = sorted(d["n_poses"].unique())
    qs = [q for q in ("bias", "scale", "nonorth") if q in set(d["quantity"])]
    names = {"bias": "bias", "scale": "scale factor", "nonorth": "non-orthogonality"}
    with plt.rc_context(RC):
        fig, axes = plt.subplots(len(ns), len(qs), figsize=(7.6, 1.9 + 1.75 * len(ns)), layout="constrained",
                                 squeeze=False, sharex=True)
        for i, n in enumerate(ns):
            for j, q in enumerate(qs):
                ax = axes[i, j]
                t = d[(d["n_poses"] == n) & (d["quantity"] == q)].sort_values("noise_std")
                for short, m in (("lls", "full_lls"), ("als", "full_als"), ("nlls", "full_nlls")):
                    if f"{short}_crlb" not in t:
                        continue
                    y, se = t[f"{short}_crlb"].to_numpy(float), t[f"{short}_crlb_se"].to_numpy(float)
                    off = y > LIMIT_YMAX  # a few diverged solves blow the RMS up: mark, do not scale to them
                    ax.errorbar(t["noise_std"][~off], y[~off], yerr=se[~off], capsize=1.5, elinewidth=0.6,
                                **_kw(m, ms=3.5))
                    for x, v in zip(t["noise_std"][off], y[off]):
                        ax.annotate(f"{style(m)['label']}\n{v:.2g} ↑", (x, 0.97), xycoords=("data", "axes fraction"),
                                    ha="right", va="top", fontsize=6, color=style(m)["color"])
                ax.axhline(1.0, color="k", ls="--", lw=0.9)
                lo, hi = ax.get_ylim()
                ax.set_ylim(min(lo, 0.9), min(max(hi, 1.1), LIMIT_YMAX))
                if onsets is not None and len(onsets):
                    o = onsets[(onsets["data_model"] == "full") & (onsets["n_poses"] == n) & (onsets["quantity"] == q)]
                    if len(o) and np.isfinite(o["onset_noise"].iloc[0]):
                        ax.axvline(o["onset_noise"].iloc[0], color="C3", lw=1, alpha=0.6)
                ax.set_xscale("log")
                if i == 0:
                    ax.set_title(names[q])
                if j == 0:
                    ax.set_ylabel(f"{n} poses\nRMS / CRLB")
                if i == len(ns) - 1:
                    ax.set_xlabel("noise std [m/s²]")
        axes[0, 0].legend(fontsize=6.5, loc="upper left")
        fig.suptitle("Where the algebraic LLS leaves NLLS and the bound (red line: LLS measurably worse than both)",
                     fontsize=8.5)
    return fig


FIGURES: Mapping[str, str] = {
    "burkhard2024_fig1a": "bias error vs noise, and RMS / CRLB",
    "burkhard2024_fig1b": "bias error vs number of poses",
    "burkhard2024_fig1c": "bias error vs error in g (M ≠ I)",
    "burkhard2024_fig1d": "scale-factor and non-orthogonality error vs error in g",
    "burkhard2024_fig1e": "bias error vs error in g (M = I)",
    "burkhard2024_timing": "compute time vs pose count",
    "burkhard2024_lls_limit": "where LLS leaves NLLS and the CRLB",
}

__all__ = ["FIGURES", "plot_fig1a", "plot_fig1b", "plot_fig1c", "plot_fig1d", "plot_lls_limit", "plot_timing"]
