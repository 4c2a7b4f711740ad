"""Figures of the discrepancy benchmark (matplotlib; return Figures,
:func:`accelcal.plotting.save_figure` writes them).

* :func:`plot_confusion`: benchmark confusion matrix (true effect × outcome).
* :func:`plot_power`: detection rate vs effect size in MDE units, per effect.

The figures of one recording's analysis (before/after residuals, Allan deviation) are in
:mod:`accelcal.discrepancy.figures`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.discrepancy.effects import EFFECT_IDS
from accelcal.plotting import RC, plt

from .benchmark import CONSTANT_TEMPERATURE, NONE, NOT_IDENTIFIABLE, crossing

#: Display names.
LABELS = {NONE: "none", NOT_IDENTIFIABLE: "not identifiable", CONSTANT_TEMPERATURE: "temperature\n(T constant)",
          "error": "error", "quadratic": "quadratic", "cubic": "cubic", "bias_drift": "bias drift",
          "temperature": "temperature", "temperature_scale": "temperature\nscale"}
COLORS = {e: f"C{i}" for i, e in enumerate(EFFECT_IDS)}


def plot_confusion(scores: pd.DataFrame, size_mde: float, alpha: float):
    """Rows: true effect (``none``, each effect at ``size_mde``, constant temperature);
    columns: outcome.  Cells: fraction of the row's recordings (count in brackets)."""
    d = scores[(scores.truth == NONE) | np.isclose(scores.size_mde, size_mde) | (scores.truth == CONSTANT_TEMPERATURE)]
    rows = [r for r in (NONE, *EFFECT_IDS, CONSTANT_TEMPERATURE) if r in set(d.truth)]
    cols = [c for c in (*EFFECT_IDS, NONE, NOT_IDENTIFIABLE) if True]
    if (d.outcome == "error").any():
        cols.append("error")
    C = np.zeros((len(rows), len(cols)))
    N = np.zeros(len(rows), int)
    for i, r in enumerate(rows):
        dr = d[d.truth == r]
        N[i] = len(dr)
        for j, c in enumerate(cols):
            C[i, j] = (dr.outcome == c).sum()
    F = C / np.maximum(N, 1)[:, None]
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(7.2, 4.6), layout="constrained")
        im = ax.imshow(F, cmap="Blues", vmin=0, vmax=1, aspect="auto")
        for i in range(len(rows)):
            for j in range(len(cols)):
                if C[i, j] > 0:
                    ax.text(j, i, f"{F[i, j]:.2f}\n({int(C[i, j])})", ha="center", va="center", fontsize=7,
                            color="w" if F[i, j] > 0.6 else "k")
            exp = {NONE: NONE, CONSTANT_TEMPERATURE: NOT_IDENTIFIABLE}.get(rows[i], rows[i])
            if exp in cols:
                j = cols.index(exp)
                ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, ec="C3", lw=1.5))
        ax.set_xticks(range(len(cols)), [LABELS.get(c, c) for c in cols], fontsize=7.5)
        ax.set_yticks(range(len(rows)), [f"{LABELS.get(r, r)}  (n={n})" for r, n in zip(rows, N)], fontsize=7.5)
        ax.set_xlabel("outcome of the discrepancy loop (effect named first, none, or not identifiable)")
        ax.set_ylabel(f"hidden effect (size {size_mde:g} × its MDE)")
        ax.grid(False)
        fpr = float(F[rows.index(NONE), [cols.index(e) for e in EFFECT_IDS if e in cols]].sum()) if NONE in rows else np.nan
        ax.set_title(f"Benchmark confusion matrix (red: expected outcome); false-positive rate {fpr:.3f} "
                     f"(α = {alpha:g})", fontsize=8.5)
        fig.colorbar(im, ax=ax, shrink=0.8, label="fraction of the row")
    return fig


def plot_power(rate_table: pd.DataFrame, power: float, alpha: float, fpr: float | None = None):
    """Detection rate (injected effect named first) vs size in MDE units, exact 95 % intervals;
    dotted: 50 % and 95 %, with the interpolated sizes marked; the configured power at 1 MDE."""
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(7.2, 4.0), layout="constrained")
        effects = [e for e in EFFECT_IDS if e in set(rate_table.truth)]
        for k, e in enumerate(effects):
            r = rate_table[rate_table.truth == e].sort_values("size_mde")
            dodge = 1 + 0.015 * (k - (len(effects) - 1) / 2)
            yerr = np.vstack([r.detection_rate - r.detection_ci_low, r.detection_ci_high - r.detection_rate])
            ax.errorbar(r.size_mde * dodge, r.detection_rate, yerr=yerr, color=COLORS[e], marker="o", ms=4, lw=1,
                        capsize=2, label=f"{LABELS[e].replace(chr(10), ' ')} (n={int(r.n.min())}/size)")
            for target, mk in ((0.5, "v"), (0.95, "^")):
                s, _ = crossing(r.size_mde, r.detection_rate, target)
                if np.isfinite(s):
                    ax.plot(s, target, marker=mk, color=COLORS[e], ms=7, mfc="none")
        x0 = float(rate_table.size_mde[rate_table.size_mde > 0].min()) / 1.6
        if fpr is not None and np.isfinite(fpr):
            ax.plot([x0], [fpr], marker="s", color="k", ls="none",
                    label=f"effect-free recordings (size 0): any effect named ({fpr:.3f})")
        for y in (0.5, 0.95):
            ax.axhline(y, color="0.4", ls=":", lw=0.9)
        ax.axhline(alpha, color="C3", ls="--", lw=0.8, label=f"α = {alpha:g}")
        ax.plot([1.0], [power], marker="*", color="k", ms=10, ls="none",
                label=f"design power at 1 MDE ({power:g})")
        ax.set_xscale("log")
        ticks = sorted(set(rate_table.size_mde[rate_table.size_mde > 0]))
        ax.set_xticks([x0, *ticks], ["0", *(f"{t:g}" for t in ticks)])
        ax.set_xlim(x0 / 1.25, max(ticks) * 1.25)
        ax.minorticks_off()
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel("size of the hidden effect [× its minimum detectable effect along its direction]")
        ax.set_ylabel("detection rate (named first), exact 95% CI")
        ax.set_title("Detection power of the discrepancy loop (▽ 50 %, △ 95 % detection, interpolated)", fontsize=9)
        ax.legend(loc="lower right", fontsize=7)
    return fig


__all__ = ["COLORS", "LABELS", "plot_confusion", "plot_power"]
