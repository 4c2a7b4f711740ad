"""Figures of the discrepancy workflow (matplotlib; return Figures, :func:`accelcal.plotting.save_figure` writes them).

* :func:`plot_confusion`: benchmark confusion matrix (true effect × outcome).
* :func:`plot_power`: detection rate vs effect size in MDE units, per effect.
* :func:`plot_before_after`: weighted pose residuals before/after, per recording.
* :func:`allan_figure`: measured vs simulated Allan deviation (helper: ``plot_allan``).
* :func:`recording_figures`: the CLI's figures for one recording.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..plotting import RC, plt
from .benchmark import CONSTANT_TEMPERATURE, NONE, NOT_IDENTIFIABLE, crossing
from .effects import EFFECT_IDS

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


def _residual_panel(ax, det: dict, implication: dict | None, title: str):
    p = det["poses"]
    t = np.asarray(p["t"], float)
    s = np.asarray(p["sigma"], float)
    rb = np.asarray(p["residual_before"], float) / s
    ra = np.asarray(p["residual_after"], float) / s
    ax.axhspan(-2, 2, color="0.92", lw=0)
    ax.axhspan(-1, 1, color="0.85", lw=0)
    top = max(4.0, 1.3 * float(np.nanmax(np.abs(np.concatenate([rb, ra])))))
    if implication and implication.get("extra_residual_std"):
        infl = np.sqrt(1 + (np.asarray(implication["extra_residual_std"], float) / s) ** 2)
        if np.any(infl > 1 + 1e-9):
            ax.plot(np.repeat(t, 2), np.ravel(np.column_stack([2 * infl, -2 * infl])), ls="none", marker="_",
                    ms=7, color="C2", label="±2σ incl. the named noise terms (per pose)")
            if 2 * infl.max() > 3 * top:  # the band dwarfs the residuals: symlog keeps both readable
                ax.set_yscale("symlog", linthresh=4.0, linscale=1.5)
            top = max(top, 1.1 * 2 * float(infl.max()))
            if ax.get_yscale() == "symlog":
                ticks = [v for v in (2, 4, 10, 30, 100, 300, 1000, 3000) if v < top]
                ticks = [-v for v in ticks[::-1]] + [0] + ticks
                ax.set_yticks(ticks, [f"{v:g}" for v in ticks])
                ax.minorticks_off()
    named = "+".join(det["effects"]) or "none"
    ax.plot(t, rb, "o", color="C0", ms=4, mfc="none",
            label=f"base model: gap {det['gap_before']:.2f} (noise alone {det['gap_expected_before']:.2f})")
    ax.plot(t, ra, "x", color="C3", ms=4,
            label=f"base + {named}: gap {det['gap_after']:.2f} (noise alone {det['gap_expected_after']:.2f})")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_ylim(-top, top)
    ax.set_xlabel("pose mid time [s]")
    ax.set_ylabel("pose residual / its noise σ_i")
    ax.set_title(title, fontsize=8.5)
    ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False)


def plot_before_after(reports: dict[str, dict]):
    """One panel per recording: weighted pose residuals of the base model (before) and of
    the model with the named effects (after); grey bands ±1σ, ±2σ of the white-noise
    prediction, green ticks ±2σ including the named noise terms (symmetric-log axis when
    that band dwarfs the residuals)."""
    n = len(reports)
    with plt.rc_context(RC):
        fig, axes = plt.subplots(1, n, figsize=(3.8 * n + 0.4, 4.4), layout="constrained", squeeze=False)
        for ax, (name, rep) in zip(axes[0], reports.items()):
            ni = ", ".join(rep["not_identifiable"]) or "-"
            _residual_panel(ax, rep, rep.get("noise_implication"),
                            f"{name}: {rep['n_poses']} poses, named: {rep['effect']}\nnot identifiable: {ni}")
    return fig


def _as_array(v) -> np.ndarray:
    return np.array([np.nan if x is None else x for x in np.ravel(v)], float).reshape(np.shape(v)) \
        if v is not None else np.array([])


def stochastic_from_report(d: dict):
    """The parts of a :class:`~accelcal.discrepancy.stochastic.StochasticResult` that
    :func:`~accelcal.discrepancy.stochastic.plot_allan` draws, rebuilt from its ``to_dict()``
    (JSON: null for NaN)."""
    from types import SimpleNamespace

    arrays = ("taus", "adev_measured", "adev_ci", "adev_longest_rest", "adev_model_before", "adev_model_after",
              "adev_resim_before", "adev_resim_after")
    axes = []
    for name, a in d["axes"].items():
        named = tuple(k for k in a["named"] if k != "none")
        axes.append(SimpleNamespace(axis=name, named=named, gap_before=a["gap_before"], gap_after=a["gap_after"],
                                    **{k: _as_array(a[k]) for k in arrays}))
    return SimpleNamespace(axes=tuple(axes), unit=d.get("unit", "u"))


def allan_figure(results: dict):
    """Measured vs simulated Allan deviation, before and after the named noise terms: one
    row per recording (``{name: StochasticResult or its to_dict()}``), one panel per axis,
    drawn by :func:`accelcal.discrepancy.stochastic.plot_allan`."""
    from .stochastic import plot_allan

    n = len(results)
    with plt.rc_context(RC):
        fig, axes = plt.subplots(n, 3, figsize=(10.5, 3.4 * n + 0.3), layout="constrained", squeeze=False)
        for row, (name, res) in zip(axes, results.items()):
            res = stochastic_from_report(res) if isinstance(res, dict) else res
            plot_allan(list(row), res)
            row[0].set_ylabel(f"{name}\nAllan deviation [{res.unit}]")
            for ax in row:  # the named terms can be long: keep the three titles apart
                ax.title.set_fontsize(7)
                ax.title.set_wrap(True)
    return fig


def recording_figures(analysis, title: str) -> list[tuple[str, object]]:
    """The CLI's figures for one recording: ``discrepancy_residuals`` and, if the stochastic
    layer ran, ``discrepancy_allan``."""
    rep = analysis.to_dict()
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
        _residual_panel(ax, rep, rep.get("noise_implication"), f"{title}: named {rep['effect']}")
    out = [("discrepancy_residuals", fig)]
    if analysis.stochastic is not None:
        out.append(("discrepancy_allan", allan_figure({title: analysis.stochastic})))
    return out


__all__ = ["allan_figure", "plot_before_after", "plot_confusion", "plot_power", "recording_figures",
           "stochastic_from_report"]

