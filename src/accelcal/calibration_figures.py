"""Figures of one calibration (matplotlib; imported only when figures are asked for)."""

from __future__ import annotations

import numpy as np

from .evaluation import residual_sigma
from .plotting import plt
from .quality import RULES, directions


def coverage_figure(cal, title: str = ""):
    """Figure ``calibration_coverage``: where the poses point, and how well they fit.

    Left: the gravity direction of each pose in the sensor frame on an equal-area
    (Mollweide) map, azimuth ``atan2(u_y, u_x)`` against elevation ``asin(u_z)``,
    coloured by its residual in units of the noise the rests predict; the shaded caps
    are the sphere within 30° of a pose (the coverage number).  Right: residual against
    the predicted ±2σ band, pose by pose.
    """

    z = np.asarray(cal.poses["mean"], float)
    u = directions(z, cal.M, cal.bias)
    sigma = residual_sigma(z, cal.poses["mean_std"], cal.M, cal.bias)
    zr = np.asarray(cal.residuals, float) / sigma
    q = cal.quality
    fig = plt.figure(figsize=(9.0, 3.8), layout="constrained")
    ax = fig.add_subplot(1, 2, 1, projection="mollweide")
    lon = np.linspace(-np.pi, np.pi, 361)
    lat = np.linspace(-np.pi / 2, np.pi / 2, 181)
    LON, LAT = np.meshgrid(lon, lat)
    grid = np.stack([np.cos(LAT) * np.cos(LON), np.cos(LAT) * np.sin(LON), np.sin(LAT)], axis=-1)
    near = (grid @ u.T).max(axis=-1) >= np.cos(np.deg2rad(RULES["coverage_deg"]))
    ax.contourf(LON, LAT, near.astype(float), levels=[0.5, 1.5], colors=["C2"], alpha=0.18)
    lim = max(3.0, float(np.nanmax(np.abs(zr))))
    sc = ax.scatter(np.arctan2(u[:, 1], u[:, 0]), np.arcsin(np.clip(u[:, 2], -1, 1)), c=zr, cmap="coolwarm",
                    vmin=-lim, vmax=lim, s=28, edgecolors="k", linewidths=0.5, zorder=3)
    ax.grid(True, lw=0.4, alpha=0.6)
    ax.tick_params(labelsize=7)
    ax.set_title(f"pose directions: {q.distinct_orientations} distinct, {100 * q.coverage:.0f}% of the sphere "
                 "within 30°", fontsize=8.5)
    fig.colorbar(sc, ax=ax, shrink=0.7, label="residual / predicted σ")
    ax2 = fig.add_subplot(1, 2, 2)
    i = np.arange(len(z))
    ax2.bar(i, 4 * sigma * 1e3, bottom=-2 * sigma * 1e3, color="0.85", width=0.8, label="±2σ from the rest noise")
    ax2.plot(i, np.asarray(cal.residuals) * 1e3, "o", ms=4, color="C0", label="residual")
    ax2.axhline(0, color="k", lw=0.6)
    ax2.set_xlabel("pose (time order)")
    ax2.set_ylabel("residual |x| - g [mm/s²]")
    ax2.set_title(f"residuals {q.excess:.3g}× the predicted noise (χ²/dof on {q.dof} dof)"
                  if q.dof > 0 else "residuals (no degree of freedom left)", fontsize=8.5)
    ax2.legend(fontsize=7, frameon=False)
    if title:
        fig.suptitle(f"{title}: {cal.CAL_TYPE}", fontsize=9.5)
    return fig


__all__ = ["coverage_figure"]
