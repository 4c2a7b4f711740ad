"""Which integrator: the scale-factor bias each induces, vs rotation rate and sample rate.

Simulated hand motions between rests (:func:`accelcal.gyro.simulate.random_motion`: a
total angle split over three simultaneously turning axes, minimum-jerk profiles,
staggered, so the rotation axis moves) with their exact rotation.  Each is sampled at
``fs`` (noise-free, instantaneous rates) and integrated by every method of
:data:`accelcal.gyro.integrate.METHODS`.  The rotation error of motion ``i`` is
``e_i = log(R_trueᵀ R_method)``.  A calibration absorbs the part of it along the
motion's own rotation as a scale error: the least-squares common scale ``s`` with
``e_i + s d_i ≈ 0``, ``d_i = ∂φ_i/∂s`` (the derivative of the end rotation with respect
to a common scale factor, :func:`accelcal.gyro.integrate.integrate_intervals` with ``C =
(1 + s) I``), is the *scale-factor bias* the integrator induces::

    s = -Σ d_i·e_i / Σ d_i·d_i

(linear: the errors are small).  Also tabulated: the RMS relative angle error
``|e_i| / θ_i``.

Tidy table columns: ``method, rate_dps, fs_hz, angle_deg, n_motions, scale_bias,
abs_scale_bias_ppm, rel_angle_rms_ppm``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.gyro.integrate import METHODS, integrate_intervals, integrate_sequential, log_so3
from accelcal.gyro.simulate import random_motion

DEFAULTS = {"rates_dps": (30.0, 60.0, 120.0, 250.0, 500.0, 1000.0), "fs_hz": (50.0, 100.0, 200.0, 500.0),
            "angle_deg": 120.0, "n_motions": 20, "seed": 24}


def _motions(seed: int, n: int, angle_deg: float, rate_dps: float):
    rng = np.random.default_rng(seed)
    return [random_motion(rng, angle_deg, rate_dps) for _ in range(n)]


def _sampled(motions, fs: float):
    """All motions in one array, each with one rest sample before and after: rates, starts, stops."""
    chunks, starts, stops, pos = [], [], [], 0
    for mo in motions:
        k = int(np.ceil(mo.duration * fs)) + 1
        w = mo.rates(np.arange(k) / fs)
        chunks += [np.zeros((1, 3)), w, np.zeros((1, 3))]
        starts.append(pos)
        stops.append(pos + k + 1)
        pos += k + 2
    return np.concatenate(chunks), np.array(starts), np.array(stops)


def scale_bias_row(method: str, rate_dps: float, fs: float, *, angle_deg: float, n_motions: int, seed: int) -> dict:
    motions = _motions(seed, n_motions, angle_deg, rate_dps)
    w, starts, stops = _sampled(motions, fs)
    h = 1.0 / fs
    R_true = np.array([mo.rotation() for mo in motions])
    R = integrate_sequential(w, h, starts, stops, method)
    e = log_so3(np.swapaxes(R_true, -1, -2) @ R)
    d = integrate_intervals(w, h, starts, stops, "magnus4", raw=w).dphi_dC @ np.eye(3).reshape(9)
    s = -float(np.sum(d * e) / np.sum(d * d))
    theta = np.linalg.norm(log_so3(R_true), axis=1)
    return {"method": method, "rate_dps": rate_dps, "fs_hz": fs, "angle_deg": angle_deg, "n_motions": n_motions,
            "scale_bias": s, "abs_scale_bias_ppm": 1e6 * abs(s),
            "rel_angle_rms_ppm": 1e6 * float(np.sqrt(np.mean((np.linalg.norm(e, axis=1) / theta) ** 2)))}


def integrator_study(rates_dps=DEFAULTS["rates_dps"], fs_hz=DEFAULTS["fs_hz"], *, angle_deg=DEFAULTS["angle_deg"],
                     n_motions=DEFAULTS["n_motions"], seed=DEFAULTS["seed"], methods=METHODS) -> pd.DataFrame:
    """The tidy table of the module docstring: one row per method, rate and sample rate
    (the same motions for every method and sample rate at one rate)."""
    rows = [scale_bias_row(m, r, fs, angle_deg=angle_deg, n_motions=n_motions, seed=seed)
            for r in rates_dps for fs in fs_hz for m in methods]
    return pd.DataFrame(rows)


def choose(table: pd.DataFrame, max_deg_per_sample: float = 5.0) -> str:
    """The method with the smallest median RMS angle error over the cells of the study at
    hand-motion rates (at most ``max_deg_per_sample`` degrees per sample: 500 deg/s at 100 Hz)."""
    sub = table[table.rate_dps / table.fs_hz <= max_deg_per_sample]
    return str(sub.groupby("method").rel_angle_rms_ppm.median().idxmin())


LABELS = {"euler_sum": "plain sum (imucal)", "euler": "Euler (quaternion)", "rk4": "RK4 (IMU-TK)",
          "coning": "coning (2-sample)", "magnus4": "Magnus-4, cubic"}
COLORS = {"euler_sum": "C3", "euler": "C1", "rk4": "C0", "coning": "C2", "magnus4": "C4"}
#: RK4 and the coning form interpolate the rate linearly and nearly coincide: dashed and solid.
LINES = {"euler_sum": "-", "euler": "-", "rk4": "--", "coning": "-", "magnus4": "-"}


def figure(table: pd.DataFrame):
    """Top: |scale-factor bias| [ppm]; bottom: RMS relative angle error [ppm]; vs rotation
    rate, one column per sample rate, one line per method."""
    import matplotlib.pyplot as plt

    from accelcal.plotting import RC

    fss = sorted(table.fs_hz.unique())
    with plt.rc_context(RC):
        fig, axes = plt.subplots(2, len(fss), figsize=(2.0 * len(fss) + 1.2, 5.6), sharey="row", sharex=True,
                                 layout="constrained", squeeze=False)
        for col, fs in enumerate(fss):
            sub = table[table.fs_hz == fs]
            for row, (key, floor) in enumerate((("abs_scale_bias_ppm", 1e-4), ("rel_angle_rms_ppm", 1e-3))):
                ax = axes[row, col]
                for m in LABELS:
                    s = sub[sub.method == m].sort_values("rate_dps")
                    if len(s):
                        ax.loglog(s.rate_dps, np.maximum(s[key], floor), marker="o", ls=LINES[m], ms=3,
                                  color=COLORS[m], label=LABELS[m], lw=1.6 if m == "rk4" else 1.0, zorder=3)
                ax.axhline(100, color="0.5", lw=0.8, ls=":")
            axes[0, col].set_title(f"{fs:g} Hz")
            axes[1, col].set_xlabel("peak rate [deg/s]")
            rates = sorted(table.rate_dps.unique())
            for ax in axes[:, col]:
                ax.set_xticks(rates, [f"{r:g}" for r in rates], rotation=45 if len(rates) > 4 else 0)
                ax.minorticks_off()
        axes[0, 0].set_ylabel("|scale-factor bias| [ppm]")
        axes[1, 0].set_ylabel("RMS angle error / angle [ppm]")
        handles, labels = axes[1, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=min(3, len(labels)), fontsize=7)  # fits 2 columns of panels
        fig.suptitle(f"integration error on {int(table.n_motions.iloc[0])} simulated motions of "
                     f"{table.angle_deg.iloc[0]:g} deg about moving axes\n(dotted: 100 ppm; RK4 and coning "
                     "overlap)", fontsize=8.5)
    return fig


__all__ = ["DEFAULTS", "choose", "figure", "integrator_study", "scale_bias_row"]
