"""Figures of the discrepancy analysis of one or more recordings (matplotlib; return
Figures, :func:`accelcal.plotting.save_figure` writes them).

* :func:`plot_before_after`: weighted pose residuals before/after, per recording.
* :func:`allan_figure`: measured vs simulated Allan deviation (one row per recording);
  :func:`plot_allan` draws one recording's row.
* :func:`recording_figures`: the CLI's figures for one recording.

matplotlib (the ``plots`` extra) is imported by the functions that draw, not with the
module: :mod:`accelcal.discrepancy` exports :func:`plot_allan` without loading it.

The benchmark's figures (confusion matrix, power) are in
:mod:`accelcal_repro.discrepancy.figures`.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..noise.terms import TERMS
from .stochastic.results import StochasticError, StochasticResult


def plot_allan(fig_or_axes, result: StochasticResult, title: str = "", wander_check: dict | None = None):
    """Measured vs simulated Allan deviation, before and after the named terms, one panel per axis.

    Draws, per axis: the measured ADEV (all rests pooled) with its 68 % interval, the
    longest rest alone (thin grey), the white-only model (dashed) and the final model
    (solid) as theory lines, and the re-simulated rests of both models (open markers),
    with the named terms and the gap before → after in the panel title.

    Parameters
    ----------
    fig_or_axes : matplotlib.figure.Figure or sequence of Axes
        A figure to fill (one row of panels) or one Axes per axis of ``result``.
    result : StochasticResult
    title : str
        Figure title (only when a figure is given).
    wander_check : dict, optional
        ``noise_implication["allan_check"]`` of the report: also draws what the bias wander
        estimated from the pose residuals predicts (white + wander, with the band of its
        95 % interval, green), where the check compared it (markers).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    from matplotlib.figure import Figure

    from ..plotting import RC

    n = len(result.axes)
    with matplotlib.rc_context(RC):
        if isinstance(fig_or_axes, Figure):
            fig = fig_or_axes
            axs = list(np.atleast_1d(fig.subplots(1, n, squeeze=False)[0]))
        else:
            axs = list(fig_or_axes)
            if len(axs) != n:
                raise StochasticError(f"{len(axs)} axes given for {n} result axes")
            fig = axs[0].figure
        for ax, a in zip(axs, result.axes):
            _allan_panel(ax, a)
            wc = (wander_check or {}).get("axes", {}).get(a.axis)
            if wc:
                _wander_band(ax, wc, 10 * np.nanmax(a.adev_measured))
        axs[0].set_ylabel(f"Allan deviation [{result.unit}]")
        axs[0].legend(loc="lower left", fontsize=6.5)
        if isinstance(fig_or_axes, Figure) and title:
            fig.suptitle(title, fontsize=9.5)
    return fig


def _allan_panel(ax, a) -> None:
    """One axis of :func:`plot_allan`: measured ADEV, the longest rest, the white-only and final models."""
    t = a.taus
    yerr = np.abs(np.vstack([a.adev_measured - a.adev_ci[:, 0], a.adev_ci[:, 1] - a.adev_measured]))
    ax.errorbar(t, a.adev_measured, yerr=yerr, fmt="o", color="k", ms=3.5, capsize=2, lw=0.9,
                label="measured (all rests, 68 % CI)", zorder=4)
    if np.any(np.isfinite(a.adev_longest_rest)):
        ax.plot(t, a.adev_longest_rest, color="0.55", lw=0.9, label="measured, longest rest only", zorder=3)
    ax.plot(t, a.adev_model_before, ls="--", color="C0", lw=1.2, label="white only (fit)")
    ax.plot(t, a.adev_resim_before, ls="none", marker="s", mfc="none", color="C0", ms=4,
            label="white only, re-simulated")
    named = " + ".join((TERMS[k].name if k in TERMS else k) for k in a.named) or "none"
    if a.named:
        ax.plot(t, a.adev_model_after, ls="-", color="C3", lw=1.4, label="white + named (fit)")
        ax.plot(t, a.adev_resim_after, ls="none", marker="^", mfc="none", color="C3", ms=4,
                label="white + named, re-simulated")
    ax.set(xscale="log", yscale="log", xlabel="averaging time τ [s]")
    ax.set_title(f"{a.axis}: + {named}\ngap {a.gap_before:.1f} → {a.gap_after:.1f}", fontsize=8.5)


def _wander_band(ax, wc: dict, ceiling: float) -> None:
    """What the bias wander from the poses predicts for the rests' ADEV (``allan_check`` of one axis), green."""
    tw = np.asarray(wc["taus"], float)
    band = np.asarray(wc["adev_predicted_band"], float)
    ax.fill_between(tw, band[:, 0], np.minimum(band[:, 1], ceiling), color="C2",
                    alpha=0.18, lw=0, label="white + bias wander from the poses (95 %)")
    ax.plot(tw, wc["adev_predicted"], color="C2", lw=1.2)
    cmp = np.asarray(wc["compared"], bool)
    ax.plot(tw[cmp], np.asarray(wc["adev_predicted"], float)[cmp], "D", color="C2", ms=3.5,
            mfc="none", label=f"compared: {wc['verdict']}")


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
        # the extra std is the whole noise model's beyond the rests' pose noise (white scale included)
        infl = np.sqrt(1.0 + (np.asarray(implication["extra_residual_std"], float) / s) ** 2)
        if np.any(infl > 1 + 1e-9):
            ax.plot(np.repeat(t, 2), np.ravel(np.column_stack([2 * infl, -2 * infl])), ls="none", marker="_",
                    ms=7, color="C2", label="±2σ of the named noise model (per pose)")
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
    for o in det.get("outliers") or []:  # named outlier poses: left out of the final fit
        i = int(np.argmin(np.abs(t - o["t"])))
        ax.plot(t[i], ra[i], "s", ms=9, mfc="none", color="C3", zorder=5)
        ax.annotate(f"outlier pose {o['pose']}", (t[i], ra[i]), textcoords="offset points", xytext=(6, 6),
                    fontsize=7, color="C3")
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
    from ..plotting import RC, plt

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
    :func:`plot_allan` draws, rebuilt from its ``to_dict()``
    (JSON: null for NaN)."""
    arrays = ("taus", "adev_measured", "adev_ci", "adev_longest_rest", "adev_model_before", "adev_model_after",
              "adev_resim_before", "adev_resim_after")
    axes = []
    for name, a in d["axes"].items():
        named = tuple(k for k in a["named"] if k != "none")
        axes.append(SimpleNamespace(axis=name, named=named, gap_before=a["gap_before"], gap_after=a["gap_after"],
                                    **{k: _as_array(a[k]) for k in arrays}))
    return SimpleNamespace(axes=tuple(axes), unit=d.get("unit", "u"))


def allan_figure(results: dict, wander_checks: dict | None = None):
    """Measured vs simulated Allan deviation, before and after the named noise terms: one
    row per recording (``{name: StochasticResult or its to_dict()}``), one panel per axis,
    drawn by :func:`plot_allan`; ``wander_checks``
    (``{name: noise_implication["allan_check"]}``) adds what the bias wander of the pose
    residuals predicts."""
    from ..plotting import RC, plt

    n = len(results)
    with plt.rc_context(RC):
        fig, axes = plt.subplots(n, 3, figsize=(10.5, 3.4 * n + 0.3), layout="constrained", squeeze=False)
        for row, (name, res) in zip(axes, results.items()):
            res = stochastic_from_report(res) if isinstance(res, dict) else res
            plot_allan(list(row), res, wander_check=(wander_checks or {}).get(name))
            row[0].set_ylabel(f"{name}\nAllan deviation [{res.unit}]")
            for ax in row:  # the named terms can be long: keep the three titles apart
                ax.title.set_fontsize(7)
                ax.title.set_wrap(True)
    return fig


def recording_figures(analysis, title: str) -> list[tuple[str, object]]:
    """The CLI's figures for one recording: ``discrepancy_residuals`` and, if the stochastic
    layer ran, ``discrepancy_allan``."""
    from ..plotting import RC, plt

    rep = analysis.to_dict()
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
        _residual_panel(ax, rep, rep.get("noise_implication"), f"{title}: named {rep['effect']}")
    out = [("discrepancy_residuals", fig)]
    if analysis.stochastic is not None:
        check = (rep.get("noise_implication") or {}).get("allan_check")
        out.append(("discrepancy_allan", allan_figure({title: analysis.stochastic}, {title: check} if check else None)))
    return out


__all__ = ["allan_figure", "plot_allan", "plot_before_after", "recording_figures",
           "stochastic_from_report"]

