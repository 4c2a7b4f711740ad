"""Figures of the measured-data stage (matplotlib, Agg; saved with :func:`accelcal.plotting.save_figure`).

* ``measured_static_detection`` — each recording (nominally converted to m/s² so the
  three share a unit) with the detected rests shaded: fitted ones coloured, the others
  grey, and the initial rest (the noise reference) hatched.
* ``measured_calibration`` — every parameter with its interval, by estimator and
  recording: bias as the deviation from a reference estimator (in mm/s² through the
  nominal sensitivity; the reference value in the file unit is in the tick label),
  sensitivity as the deviation from nominal in %, non-orthogonality in degrees; for the
  imucal session imucal's Ferraris values are shown as the peer.
* ``measured_residuals`` — per-pose residuals against time (full and bias-only models
  apart: they differ by orders of magnitude) with the noise-predicted ±2σ per pose and
  the leave-one-pose-out errors, and against orientation (the fitted gravity direction
  in the sensor frame, coloured by the residual).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.plotting import RC, style
from accelcal.registry import model_of
from .sources import source

#: Display names of the recordings.
TITLES = {"xsens_mti": "Xsens MTi (IMU-TK)", "mpu6050": "MPU-6050", "imucal_ferraris": "imucal Ferraris session",
          **{f"imutk_fork_{d}": f"IMU-TK fork {d}" for d in ("data2", "data3", "data4")},
          "fxos8700_sample1": "FXOS8700 data_sample", "fxos8700_sample2": "FXOS8700 data_sample2"}
PEER_STYLE = {"color": "k", "marker": "*", "label": "imucal Ferraris (peer)"}
RESID_STYLE = {"color": "C5", "marker": "P", "label": "bias-only LLS residuals (implied scale)"}


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _title(rec: str) -> str:
    return TITLES.get(rec, rec)


def _figure_legend(fig, axes, ncol: int = 4, extra=()) -> None:
    """One legend below the panels with every distinct label of ``axes`` (none inside a panel)."""
    seen = {}
    for ax in list(axes):
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if not lab.startswith("_") and lab not in seen:
                seen[lab] = h
    for h in extra:
        seen.setdefault(h.get_label(), h)
    fig.legend(list(seen.values()), list(seen), loc="outside lower center", ncol=ncol, fontsize=7, frameon=False)


def plot_static_detection(recordings: dict[str, tuple[np.ndarray, np.ndarray]], poses: pd.DataFrame):
    """Figure ``measured_static_detection``.

    Parameters
    ----------
    recordings : dict
        ``{name: (t, acc)}`` in the file unit (converted here with the nominal conversion).
    poses : DataFrame
        The gathered poses table (``recording, pose, label, t_start, t_end, used``).
    """
    plt = _plt()
    names = list(recordings)
    with plt.rc_context(RC):
        fig, axes = plt.subplots(len(names), 1, figsize=(7.4, 2.3 * len(names)), layout="constrained",
                                 squeeze=False)
        for ax, name in zip(axes[:, 0], names):
            t, acc = recordings[name]
            a = source(name).conversion.to_si(acc)
            for k, c in enumerate(("C0", "C1", "C2")):
                ax.plot(t, a[:, k], color=c, lw=0.5, label=f"a{'xyz'[k]}", rasterized=True)
            p = poses[poses.recording == name]
            for r in p.itertuples():
                ax.axvspan(r.t_start, r.t_end, color="C2" if r.used else "0.6", alpha=0.25 if r.used else 0.35, lw=0)
                if not str(r.label).startswith("rest"):
                    ax.text(0.5 * (r.t_start + r.t_end), 1.0, r.label, transform=ax.get_xaxis_transform(),
                            ha="center", va="bottom", fontsize=6.5)
            ref = p.iloc[0]
            if ref.noise_reference != "known_intervals":
                ax.axvspan(ref.reference_t_start, ref.reference_t_end, hatch="///", edgecolor="C3", facecolor="none",
                           lw=0.6)
            n, u = len(p), int(p.used.sum())
            found = {"known_intervals": "known static intervals (logged blocks)",
                     "quietest_stretch": "rests detected (no initial rest: noise from the quietest 2 s)"}
            ax.set_title(f"{_title(name)}: {n} {found.get(ref.noise_reference, 'rests detected')}, {u} used as poses",
                         fontsize=8.5, loc="left", pad=10 if (~p.label.str.startswith("rest")).any() else 4)
            ax.set_ylabel("nominal m/s²")
            ax.set_xlim(t[0], t[-1])
            ax.set_ylim(-14, 14)
        axes[-1, 0].set_xlabel("time [s]")
        from matplotlib.patches import Patch

        _figure_legend(fig, axes[:1, 0], ncol=6, extra=(
            Patch(color="C2", alpha=0.25, label="rest used as pose"),
            Patch(color="0.6", alpha=0.35, label="rest not used"),
            Patch(facecolor="none", edgecolor="C3", hatch="///", label="noise reference of the detection")))
    return fig


def _reference(params_r: pd.DataFrame) -> str:
    ests = list(dict.fromkeys(params_r.estimator))
    for e in ("full_lls", "bias_lls"):
        if e in ests:
            return e
    return ests[0]


def _bias_panel(ax, p, rec, ests, ref, cpu, pe, dodge):
    """Bias: deviation from the reference estimator, mm/s² through the nominal sensitivity."""
    refv = p[(p.estimator == ref) & p.parameter.str.startswith("bias")].set_index("parameter")["value"]
    unit = p.unit.iloc[0]
    for k, e in enumerate(ests):
        d = p[(p.estimator == e) & p.parameter.str.startswith("bias")]
        x = np.array(["xyz".index(s[-1]) for s in d.parameter]) + dodge(k)
        dev = (d.value.to_numpy() - refv[d.parameter].to_numpy()) / cpu * 1e3
        lo = (d.value.to_numpy() - d.ci_low.to_numpy()) / cpu * 1e3
        hi = (d.ci_high.to_numpy() - d.value.to_numpy()) / cpu * 1e3
        st = style(e)
        ax.errorbar(x, dev, yerr=[lo, hi], fmt=st["marker"], color=st["color"], ms=4, capsize=2,
                    elinewidth=0.8, mfc="none", label=st["label"])
    if pe is not None:
        d = pe[(pe.tool == "imucal") & (pe.parameter == "bias")]
        dev = (d.value.to_numpy() - refv[[f"bias_{a}" for a in d.axis]].to_numpy()) * 1e3
        ax.plot(np.arange(3) + dodge(len(ests)), dev, ls="none", ms=7, **PEER_STYLE)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xticks(range(3), [f"b{a}\n{refv.get(f'bias_{a}', np.nan):.6g}" for a in "xyz"], fontsize=7)
    via = "\n(counts via nominal sensitivity)" if unit == "counts" else ""
    ax.set_ylabel(f"bias − {style(ref)['label']} [mm/s²]{via}", fontsize=7)
    ax.set_xlabel(f"{style(ref)['label']} value [{unit.replace('^2', '²')}]", fontsize=6.5, labelpad=1)
    ax.set_title(f"{_title(rec)}: bias", fontsize=8, loc="left")


def _not_estimated(ax):
    ax.text(0.5, 0.5, "not estimated\n(bias-only model)", transform=ax.transAxes, ha="center",
            va="center", fontsize=8, color="0.4")


def _sensitivity_panel(ax, p, full, cpu, pe, dodge):
    """Sensitivity relative to the nominal one, with imucal's and the bias-only residuals' scale factors."""
    for k, e in enumerate(full):
        d = p[(p.estimator == e) & p.parameter.str.startswith("sens")]
        x = np.array(["xyz".index(s[-1]) for s in d.parameter]) + dodge(k)
        v = 100 * (d.value.to_numpy() / cpu - 1)
        lo = 100 * (d.value.to_numpy() - d.ci_low.to_numpy()) / cpu
        hi = 100 * (d.ci_high.to_numpy() - d.value.to_numpy()) / cpu
        st = style(e)
        ax.errorbar(x, v, yerr=[lo, hi], fmt=st["marker"], color=st["color"], ms=4, capsize=2,
                    elinewidth=0.8, mfc="none")
    if pe is not None:
        d = pe[(pe.tool == "imucal") & (pe.parameter == "scale_factor")]
        ax.plot(np.arange(3) + dodge(0), 100 * d.value.to_numpy(), ls="none", ms=7, **PEER_STYLE)
        d = pe[(pe.method == "bias_lls residuals") & (pe.parameter == "scale_factor")]
        ax.plot(np.arange(3) + dodge(1), 100 * d.value.to_numpy(), ls="none", ms=5, mfc="none",
                **RESID_STYLE)
    if not full and pe is None:
        _not_estimated(ax)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xticks(range(3), [f"{a}" for a in "xyz"])
    ax.set_ylabel("sensitivity / nominal − 1 [%]", fontsize=7.5)
    ax.set_title("sensitivity vs nominal", fontsize=8, loc="left")


def _nonorth_panel(ax, p, full, pe, dodge):
    """Non-orthogonality angles, with imucal's."""
    names = ("nonorth_xy", "nonorth_zx", "nonorth_zy")
    for k, e in enumerate(full):
        d = p[(p.estimator == e) & p.parameter.isin(names)]
        x = np.array([names.index(s) for s in d.parameter]) + dodge(k)
        st = style(e)
        ax.errorbar(x, d.value, yerr=[d.value - d.ci_low, d.ci_high - d.value], fmt=st["marker"],
                    color=st["color"], ms=4, capsize=2, elinewidth=0.8, mfc="none")
    if pe is not None:
        d = pe[(pe.tool == "imucal") & (pe.parameter == "nonorth")]
        ax.plot(np.arange(3) + dodge(0), d.value.to_numpy(), ls="none", ms=7, **PEER_STYLE)
    if not full and pe is None:
        _not_estimated(ax)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xticks(range(3), ["θxy", "θzx", "θzy"])
    ax.set_ylabel("non-orthogonality [deg]", fontsize=7.5)
    ax.set_title("non-orthogonality", fontsize=8, loc="left")


def plot_calibration(params: pd.DataFrame, peer: pd.DataFrame | None = None, nominal_sens: dict | None = None):
    """Figure ``measured_calibration``: rows recordings, columns bias / sensitivity / non-orthogonality.

    Parameters
    ----------
    params : DataFrame
        The gathered parameter table.
    peer : DataFrame, optional
        ``peer_imucal.csv`` (section-list poses are shown on the imucal row).
    nominal_sens : dict, optional
        ``{recording: (3,) nominal sensitivity}``; default: the nominal conversions.
    """
    plt = _plt()
    recs = list(dict.fromkeys(params.recording))
    with plt.rc_context(RC):
        fig, axes = plt.subplots(len(recs), 3, figsize=(7.6, 2.35 * len(recs)), layout="constrained",
                                 squeeze=False)
        for row, rec in enumerate(recs):
            p = params[params.recording == rec]
            conv = source(rec).conversion
            cpu = np.asarray(conv.counts_per_unit, float) if nominal_sens is None else nominal_sens[rec]
            ests = list(dict.fromkeys(p.estimator))
            ref = _reference(p)
            pe = None
            if peer is not None and rec == "imucal_ferraris" and len(peer):
                pe = peer[(peer.poses == "section_list")]
            n_series = len(ests) + (2 if pe is not None else 0)
            width = 0.7

            def dodge(k):
                return (k - (n_series - 1) / 2) * width / max(n_series, 1)

            full = [e for e in ests if p[p.estimator == e].parameter.str.startswith("sens").any()]
            _bias_panel(axes[row, 0], p, rec, ests, ref, cpu, pe, dodge)
            _sensitivity_panel(axes[row, 1], p, full, cpu, pe, dodge)
            _nonorth_panel(axes[row, 2], p, full, pe, dodge)
        for ax in axes.ravel():
            ax.set_xlim(-0.6, 2.6)
        _figure_legend(fig, axes.ravel(), ncol=4)
    return fig


def _orientation_panel(fig, ax, d: pd.DataFrame):
    """The reference estimator's residuals against the pose's orientation (azimuth, elevation)."""
    refe = _reference(d)
    x = d[d.estimator == refe]
    lon = np.degrees(np.arctan2(x.u_y, x.u_x))
    lat = np.degrees(np.arcsin(np.clip(x.u_z, -1, 1)))
    lim = float(np.nanmax(np.abs(1e3 * x.residual))) or 1.0
    sc = ax.scatter(lon, lat, c=1e3 * x.residual, cmap="coolwarm", vmin=-lim, vmax=lim, s=28,
                    edgecolors="k", linewidths=0.4)
    cb = fig.colorbar(sc, ax=ax, shrink=0.9, pad=0.01)
    cb.set_label(f"residual [mm/s²]\n{style(refe)['label']}", fontsize=6.5)
    cb.ax.tick_params(labelsize=6.5)
    ax.set(xlim=(-190, 190), ylim=(-97, 97))
    ax.set_xticks([-180, -90, 0, 90, 180])
    ax.set_yticks([-90, -45, 0, 45, 90])
    ax.set_xlabel("azimuth atan2(uy, ux) [deg]", fontsize=7)
    ax.set_ylabel("elevation asin(uz) [deg]", fontsize=7)
    ax.set_title("residual vs orientation", fontsize=8, loc="left")


def plot_residuals(pose_errors: pd.DataFrame):
    """Figure ``measured_residuals``: per recording, residuals of the full and the bias-only
    models against time, and the reference estimator's residuals against orientation."""
    plt = _plt()
    recs = list(dict.fromkeys(pose_errors.recording))
    with plt.rc_context(RC):
        fig, axes = plt.subplots(len(recs), 3, figsize=(7.8, 2.4 * len(recs)), layout="constrained",
                                 squeeze=False, gridspec_kw={"width_ratios": [1.15, 1.15, 1.0]})
        for row, rec in enumerate(recs):
            d = pose_errors[pose_errors.recording == rec]
            ests = list(dict.fromkeys(d.estimator))
            for col, prefix in ((0, "full"), (1, "bias")):
                ax = axes[row, col]
                es = [e for e in ests if model_of(e) == prefix]
                if not es:
                    ax.text(0.5, 0.5, "full model not identifiable\n(6 orientations < 10 poses)"
                            if prefix == "full" else "no bias-only fit", transform=ax.transAxes,
                            ha="center", va="center", fontsize=7.5, color="0.4")
                    ax.set_title(f"{_title(rec)}: {prefix} model", fontsize=8, loc="left")
                    ax.set_xticks([])
                    ax.set_yticks([])
                    continue
                ref = d[d.estimator == es[0]]
                ax.errorbar(ref.t_mid, np.zeros(len(ref)), yerr=2e3 * ref.sigma_pred, fmt="none", ecolor="0.55",
                            elinewidth=4, alpha=0.45, label="±2σ from pose noise")
                for e in es:
                    x = d[d.estimator == e]
                    st = style(e)
                    ax.plot(x.t_mid, 1e3 * x.residual, ls="none", marker=st["marker"], color=st["color"], ms=3.5,
                            mfc="none", label=st["label"])
                if np.isfinite(ref.lopo_error).any():
                    ax.plot(ref.t_mid, 1e3 * ref.lopo_error, ls="none", marker="_", color="k", ms=6, mew=1.2,
                            label="leave-one-pose-out error (first estimator of the panel)")
                else:
                    ax.text(0.02, 0.03, "leave-one-pose-out impossible (n − 1 < 10)", transform=ax.transAxes,
                            fontsize=6.5, color="0.3")
                ax.axhline(0, color="k", lw=0.6)
                ax.set_ylabel("residual [mm/s²]", fontsize=7.5)
                ax.set_title(f"{_title(rec)}: {prefix} model", fontsize=8, loc="left")
            axes[-1, 0].set_xlabel("time [s]")
            axes[-1, 1].set_xlabel("time [s]")

            _orientation_panel(fig, axes[row, 2], d)
        _figure_legend(fig, axes[:, :2].ravel(), ncol=4)
    return fig


__all__ = ["plot_calibration", "plot_residuals", "plot_static_detection"]
