"""Figure of a noise report: Allan deviations with the fitted IEEE terms and their intervals.

One row per sensor, one panel per axis: the measured Allan deviation with its error bars
(the report's level, the fitted model's edf), the fitted model, each term it holds as
a thin line, the band the bootstrap fits span (the report's level), and the exported
noise density (τ = 1 s) and random walk (τ = 3 s) as points on their lines; optionally
reference values (a datasheet's white noise and bias stability) as grey dash-dotted lines.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from ..plotting import RC
from .export import exported_values
from .terms import TERMS, exported_term


def noise_figure(report, title: str | None = None, references: dict | None = None,
                 reference_label: str = "datasheet"):
    """The figure (matplotlib ``Figure``) of a :class:`~accelcal.noise.report.NoiseReport`.

    ``references``: ``{sensor: {"white": N, "floor": ADEV}}`` in the sensor's unit, drawn as
    the Allan deviation ``N/√τ`` of a white-noise density and a horizontal level (a bias
    stability), labelled with ``reference_label``.
    """
    sensors = list(report.sensors.values())
    with matplotlib.rc_context(RC):
        fig = Figure(figsize=(11, 3.4 * len(sensors) + 0.5))
        axs = np.atleast_2d(fig.subplots(len(sensors), 3, squeeze=False))
        for row, s in zip(axs, sensors):
            a = s.allan
            grid = np.logspace(np.log10(a.taus[0]), np.log10(a.taus[-1]), 200)
            for j, ax in enumerate(row):
                adev = a.adev[:, j]
                ci = s.adev_interval[:, j]
                ax.errorbar(a.taus, adev, yerr=np.abs(np.vstack([adev - ci[:, 0], ci[:, 1] - adev])), fmt="o",
                            color="k", ms=3, capsize=2, lw=0.8, zorder=5,
                            label=f"measured ({100 * report.level:.0f} % interval)")
                band = _band(s, j, grid, report.level)
                ax.fill_between(grid, band[0], band[1], color="0.6", alpha=0.35, lw=0,
                                label=f"fits of the bootstrap ({100 * report.level:.0f} %)")
                fit = s.fits[j]
                ax.plot(grid, np.sqrt(fit.avar(grid, a.fs)), color="k", lw=1.3, label="fitted model")
                for k, c in zip(fit.term_ids, fit.c):
                    if c > 0:
                        ax.plot(grid, np.sqrt(c * TERMS[k].basis(grid, a.fs)), ls="--" if s.terms[j][k].resolved
                                else ":", lw=0.9, color=TERMS[k].colour, label=TERMS[k].label)
                _references(ax, grid, (references or {}).get(s.sensor, {}), reference_label)
                ex = exported_values(s, j)
                n_exp, k_exp = ex["noise_density"]["value"], ex["random_walk"]["value"]
                ax.plot([1.0], [n_exp], "s", color=exported_term("noise_density").colour, ms=5, mfc="none", zorder=6,
                        label="exported N (at τ = 1 s)")
                ax.plot([3.0], [k_exp], "^", color=exported_term("random_walk").colour, ms=5, mfc="none", zorder=6,
                        label="exported K (at τ = 3 s; an upper bound if not resolved)")
                lo, hi = np.nanmin(ci[:, 0]), np.nanmax(ci[:, 1])
                lo = min(lo / 2, 0.7 * k_exp) if k_exp > 0 else lo / 2
                ax.set(xscale="log", yscale="log", ylim=(lo, hi * 2), xlabel="averaging time τ [s]")
                ax.set_title(f"{s.sensor} {'xyz'[j]} (model misfit {50 * s.model_error[j]:.0f} %)", fontsize=9)
                ax.grid(True, which="both", lw=0.3, alpha=0.5)
            row[0].set_ylabel(f"Allan deviation [{s.unit}]")
        handles = {}
        for ax in axs.flat:
            for h, label in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(label, h)
        fig.suptitle(title or f"{report.source}: {report.duration_s / 3600:.3g} h at {report.fs:.4g} Hz; terms dashed "
                     "where resolved, dotted where only bounded", fontsize=9.5)
        fig.tight_layout(rect=(0, 0.07, 1, 1))
        fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=5, fontsize=7,
                   frameon=False)
    return fig


def _references(ax, grid, ref: dict, label: str) -> None:
    if "white" in ref:
        ax.plot(grid, ref["white"] / np.sqrt(grid), color="0.45", ls="-.", lw=1.0, label=f"{label}: white noise")
    if "floor" in ref:
        ax.axhline(ref["floor"], color="0.2", ls=(0, (9, 3)), lw=1.1, label=f"{label}: bias stability")


def _band(s, j: int, grid, level: float) -> np.ndarray:
    """(2, len(grid)): percentiles of the Allan deviation of the bootstrap's refitted models."""
    boot = s.boot_fits[j]
    basis = np.array([TERMS[k].basis(grid, s.allan.fs) for k in s.fits[j].term_ids])  # the bootstrap's columns
    adev = np.sqrt(boot**2 @ basis)
    return np.percentile(adev, [100 * (0.5 - level / 2), 100 * (0.5 + level / 2)], axis=0)


__all__ = ["noise_figure"]
