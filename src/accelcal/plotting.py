"""Figures of the reproduction: deterministic, atomically written PNG + PDF.

:func:`save_figure` writes ``<stem>.png`` and ``<stem>.pdf`` with fixed dpi and no
time stamps or software versions in the metadata, so that rerunning a figure gives
byte-identical files; each file is written to a temporary name in the target
directory and renamed, so a figure is never left half written.

The figure functions take the tidy tables of the workflow and return a Figure.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # before pyplot: no display, deterministic raster backend

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

DPI = 150
PNG_METADATA = {"Software": None}
PDF_METADATA = {"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None}

#: One style per method, shared by every figure.
METHOD_STYLE = {
    "full_lls": {"color": "C0", "marker": "o", "label": "full LLS"},
    "full_als": {"color": "C2", "marker": "s", "label": "full ALS"},
    "full_nlls": {"color": "C1", "marker": "x", "label": "full NLLS"},
    "bias_lls": {"color": "C3", "marker": "^", "label": "bias-only LLS"},
    "bias_nlls": {"color": "C4", "marker": "v", "label": "bias-only NLLS"},
    "full_lls_batch": {"color": "C0", "marker": "D", "label": "full LLS (batched)"},
    "bias_lls_batch": {"color": "C3", "marker": "D", "label": "bias-only LLS (batched)"},
}

#: Speed-ups reported by Burkhard et al. (2024), for the annotations.
PAPER_SPEEDUP = {"full_lls": 35, "bias_lls": 20}

RC = {
    "figure.figsize": (7.0, 3.4),
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "legend.fontsize": 7.5,
    "svg.hashsalt": "accelcal",
    "pdf.fonttype": 42,
}


def style(method: str) -> dict:
    return METHOD_STYLE.get(method, {"color": "k", "marker": ".", "label": method})


def _atomic_savefig(fig, path: Path, fmt: str, **kwargs) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        fig.savefig(tmp, format=fmt, dpi=DPI, **kwargs)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def save_figure(fig, stem: str | os.PathLike) -> tuple[Path, Path]:
    """Write ``<stem>.png`` and ``<stem>.pdf`` deterministically and atomically; close ``fig``.

    Returns the two paths.
    """
    stem = Path(stem)
    if stem.suffix in (".png", ".pdf"):
        stem = stem.with_suffix("")
    png, pdf = stem.with_name(stem.name + ".png"), stem.with_name(stem.name + ".pdf")
    try:
        _atomic_savefig(fig, png, "png", metadata=PNG_METADATA)
        _atomic_savefig(fig, pdf, "pdf", metadata=PDF_METADATA)
    finally:
        plt.close(fig)
    return png, pdf


def plot_crlb(summary: pd.DataFrame, methods: Sequence[str] | None = None):
    """Foundation figure: RMS bias error vs noise (log-log, CRLB dashed) and RMS/CRLB.

    ``summary``: :func:`accelcal.montecarlo.summarize_crlb` output.
    """
    methods = list(methods) if methods is not None else list(dict.fromkeys(summary["method"]))
    with plt.rc_context(RC):
        fig, (ax, axr) = plt.subplots(1, 2, figsize=(7.4, 3.4), layout="constrained")
        for model, ls, lab in (("full", "--", "CRLB, full model"), ("bias", ":", "CRLB, bias-only model")):
            d = summary[summary["model"] == model]
            if len(d):
                b = d.groupby("noise_std")["bias_crlb_rms"].mean()
                ax.plot(b.index, b.values, ls=ls, color="k", lw=1.2, label=lab, zorder=1)
        for k, m in enumerate(methods):
            d = summary[summary["method"] == m].sort_values("noise_std")
            dodge = 10 ** (0.04 * (k - (len(methods) - 1) / 2))  # spread the error bars of (b)
            st = style(m)
            kw = {"color": st["color"], "marker": st["marker"], "label": st["label"], "ms": 4, "lw": 1, "mfc": "none"}
            ax.plot(d["noise_std"], d["bias_rms"], **kw)
            se = d["bias_ratio_se"] if "bias_ratio_se" in d else None
            axr.errorbar(d["noise_std"] * dodge, d["bias_ratio"], yerr=se, capsize=2, elinewidth=0.7, **kw)
        ax.set(xscale="log", yscale="log", xlabel="noise std per axis [m/s²]",
               ylabel="RMS bias error [m/s²]", title="(a) bias error vs noise (24 poses)")
        axr.axhline(1.0, color="k", ls="--", lw=1)
        axr.set(xscale="log", xlabel="noise std per axis [m/s²]", ylabel="RMS error / CRLB (± 1 s.e.)",
                title="(b) efficiency: RMS / CRLB")
        se = summary["bias_ratio_se"] if "bias_ratio_se" in summary else 0.0
        lo, hi = np.nanmin(summary["bias_ratio"] - se), np.nanmax(summary["bias_ratio"] + se)
        axr.set_ylim(min(0.8, lo - 0.05), max(1.2, hi + 0.05))
        n = summary["n_valid"].min() if len(summary) else 0
        axr.text(0.02, 0.03, f"≥ {n} valid trials per point", transform=axr.transAxes, fontsize=7)
        ax.legend(loc="upper left")
    return fig


def plot_timing(single: pd.DataFrame, summary: pd.DataFrame, interleave: str = "block"):
    """Foundation figure: per-problem time of LLS vs NLLS (box plot, log scale), the
    batched LLS per-problem time, and the speed-ups annotated.

    ``single``: raw per-problem timings (:func:`accelcal.timing.time_interleaved`);
    ``summary``: :func:`accelcal.timing.summarize_timing`.
    """
    single = single[single["interleave"] == interleave]
    order = [m for m in ("full_lls", "full_nlls", "bias_lls", "bias_nlls") if m in set(single["method"])]
    batch = summary[summary["mode"] == "batch"]
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
        data = [1e6 * single.loc[single["method"] == m, "seconds"].to_numpy() for m in order]
        pos = np.arange(len(order), dtype=float)
        bp = ax.boxplot(data, positions=pos, widths=0.55, whis=(5, 95), showfliers=False, patch_artist=True)
        for patch, m in zip(bp["boxes"], order):
            patch.set(facecolor=style(m)["color"], alpha=0.35)
        for med in bp["medians"]:
            med.set(color="k")
        labels = [style(m)["label"] for m in order]
        bpos = []
        for j, (_, r) in enumerate(batch.iterrows()):
            x = len(order) + j
            bpos.append(x)
            ax.errorbar(x, 1e6 * r["median_s"], yerr=[[1e6 * (r["median_s"] - r["q25_s"])],
                                                       [1e6 * (r["q75_s"] - r["median_s"])]],
                        fmt=style(r["method"])["marker"], color=style(r["method"])["color"], ms=6)
            labels.append(style(r["method"])["label"].replace(" (batched)", "\n(batched)"))
            ax.annotate(f"{r['problems_per_s']:,.0f}/s", (x, 1e6 * r["median_s"]), xytext=(0, 8),
                        textcoords="offset points", ha="center", fontsize=7)
        ax.set_xticks(list(pos) + bpos, labels, fontsize=7.5)
        ax.set_yscale("log")
        ax.set_ylabel("wall time per 24-pose problem [µs]")
        ax.set_title(f"LLS vs NLLS compute time ({interleave}-interleaved, one run; boxes: IQR, whiskers: 5-95%)",
                     fontsize=8.5)
        sel = summary[(summary["mode"] == "single") & (summary["interleave"] == interleave)]
        for m in ("full_lls", "bias_lls"):
            r = sel[sel["method"] == m]
            if len(r) and m in order and r.iloc[0]["baseline"] in order:
                r = r.iloc[0]
                i, j = order.index(m), order.index(r["baseline"])
                y = 1e6 * single.loc[single["method"] == r["baseline"], "seconds"].quantile(0.95) * 1.6
                ax.annotate("", xy=(i, y), xytext=(j, y), arrowprops={"arrowstyle": "<->", "lw": 0.8})
                paper = PAPER_SPEEDUP.get(m)
                note = f"NLLS/LLS = {r['speedup_median']:.1f}×" + (f" (paper ≈{paper}×)" if paper else "")
                ax.text((i + j) / 2, y * 1.15, note, ha="center", va="bottom", fontsize=8)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * 3)
    return fig


__all__ = ["DPI", "METHOD_STYLE", "plot_crlb", "plot_timing", "save_figure", "style"]
