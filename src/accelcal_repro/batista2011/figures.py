"""Figures of the Batista et al. (2011) reproduction (matplotlib, Agg backend).

Each function takes the tidy tables of :mod:`accelcal_repro.batista2011.montecarlo` and returns a
Figure; :func:`accelcal.plotting.save_figure` writes it (PNG + PDF, deterministic).
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from accelcal.plotting import RC  # noqa: E402
from accelcal.batista.calibration import PARAMETERS  # noqa: E402
from accelcal.batista.model import euler_to_rotation  # noqa: E402
from .trajectory import stepped_euler_series  # noqa: E402

AXES = "xyz"
COMP_COLORS = ("C0", "C1", "C2")
DATA_LABELS = {"quadratic": "data with the paper's F2", "linear": "data with F2 = 0"}


def _wide(df: pd.DataFrame, value: str) -> pd.DataFrame:
    return df.pivot(index="t", columns="state", values=value)


def plot_trajectories(design, filter_attitude, constant_attitude=None):
    """The attitudes the simulations use (the paper shows its own only as Figs. 1-3).

    (a) Euler angles of the stepped calibration trajectory (cf. Fig. 1); (b) gravity
    in body coordinates along it (cf. Fig. 2); (c) Euler angles of the filter trajectory
    (cf. Fig. 3); (d) direction of ω along it (and along the fixed-axis trajectory).
    """
    t, eul, _ = stepped_euler_series(design.euler, design.schedule, rate=10.0)
    gb = np.einsum("nji,j->ni", euler_to_rotation(eul), design.g_table)
    with plt.rc_context(RC):
        fig, ax = plt.subplots(2, 2, figsize=(7.6, 5.4), layout="constrained")
        for k, lab in enumerate(("roll φ", "pitch θ", "yaw ψ")):
            ax[0, 0].plot(t, np.rad2deg(eul[:, k]), lw=0.8, label=lab)
            ax[0, 1].plot(t, gb[:, k], lw=0.8, label=f"g_{AXES[k]}")
        wt = design.schedule.window_times()
        ax[0, 1].plot(wt[:, 0], np.zeros(len(wt)), "k|", ms=4, label="4 s data windows")
        ax[0, 0].set(xlabel="t [s]", ylabel="[°]", title=f"(a) calibration attitude, {len(design.euler)} steps")
        ax[0, 1].set(xlabel="t [s]", ylabel="[m/s²]", title="(b) gravity in body frame (calibration)")
        fe = np.rad2deg(filter_attitude.euler)
        for k, lab in enumerate(("roll φ", "pitch θ", "yaw ψ")):
            ax[1, 0].plot(filter_attitude.t, fe[:, k], lw=0.8, label=lab)
        ax[1, 0].set(xlabel="t [s]", ylabel="[°]", title="(c) filter attitude (ω direction changes)")
        w = filter_attitude.omega
        u = w / np.maximum(np.linalg.norm(w, axis=1, keepdims=True), 1e-12)
        for k in range(3):
            ax[1, 1].plot(filter_attitude.t, u[:, k], lw=0.8, color=COMP_COLORS[k], label=f"ω̂_{AXES[k]} (changing)")
        if constant_attitude is not None:
            wc = constant_attitude.omega
            uc = wc / np.maximum(np.linalg.norm(wc, axis=1, keepdims=True), 1e-12)
            for k in range(3):
                ax[1, 1].plot(constant_attitude.t, uc[:, k], lw=1.2, ls="--", color=COMP_COLORS[k],
                              label=f"ω̂_{AXES[k]} (fixed axis)")
        ax[1, 1].set(xlabel="t [s]", ylabel="unit vector", title="(d) direction of ω (body frame)")
        for a in ax.flat:  # room above the curves for the legend
            lo, hi = a.get_ylim()
            a.set_ylim(lo, hi + 0.45 * (hi - lo))
            a.legend(loc="upper center", fontsize=6, ncol=3)
    return fig


def plot_calibration(summary: pd.DataFrame, comparison: pd.DataFrame, mean_claim: float = 1e-9,
                     std_claim: float = 1e-7):
    """Table I Monte Carlo against the CRLB and the paper's claims, and against the full LLS.

    (a) standard deviation of the error of every parameter with its CRLB and the paper's
    1e-7; (b) |mean error| with its Monte Carlo standard error, the estimator's O(σ²)
    bias and the paper's 1e-9; (c) RMS error of the bias ``b`` and of ``M`` for the
    three methods on data with and without the quadratic term.
    """
    s = summary[(summary["method"] == "batista2011") & (summary["data"] == "quadratic")].set_index("parameter")
    s = s.loc[list(PARAMETERS)]
    x = np.arange(len(s))
    labels = [p.replace("F_inv_", "F⁻¹").replace("b_prime_", "b'").replace("g_table_", "ᵀg").replace("f2_", "f2")
              for p in s.index]
    n = int(s["n_runs"].min())
    with plt.rc_context(RC):
        fig = plt.figure(figsize=(7.6, 8.2), layout="constrained")
        gs = fig.add_gridspec(3, 2, height_ratios=[1, 1, 1.05])
        a1, a2 = fig.add_subplot(gs[0, :]), fig.add_subplot(gs[1, :])
        a3, a4 = fig.add_subplot(gs[2, 0]), fig.add_subplot(gs[2, 1])
        a1.bar(x, s["crlb_std"], color="0.8", label="CRLB (same design)")
        a1.plot(x, s["std_error"], "o", color="C0", ms=4, label=f"Monte Carlo std ({n} runs)")
        a1.axhline(std_claim, color="C3", ls="--", lw=1, label=f"paper: std < {std_claim:g}")
        a1.set(yscale="log", ylabel="error std", title="(a) spread of the Table I estimates vs the Cramér–Rao bound")
        a2.plot(x, s["mean_error"].abs(), "o", color="C0", ms=4, label="|Monte Carlo mean error|")
        a2.plot(x, 2 * s["se_mean"], "_", color="C0", ms=14, mew=1.5,
                label="2 s.e. of the mean (Monte Carlo resolution)")
        a2.plot(x, s["asymptotic_bias"].abs(), "s", color="C1", ms=4, mfc="none",
                label="|O(σ²) bias| (expected statistics)")
        a2.axhline(mean_claim, color="C3", ls="--", lw=1, label=f"paper: mean < {mean_claim:g}")
        a2.set(yscale="log", ylabel="|mean error|", title=f"(b) mean error against what {n} runs can resolve")
        for a in (a1, a2):
            a.set_xticks(x, labels, fontsize=7, rotation=60)
            a.set_ylim(top=a.get_ylim()[1] * 20)
            a.legend(loc="upper left", fontsize=6.5, ncol=3)
            for b in (8.5, 11.5, 14.5):
                a.axvline(b, color="k", lw=0.5, alpha=0.4)
        a2.set_ylim(bottom=min(1e-12, 0.3 * mean_claim))
        methods = ["batista2011", "batista2011_linear", "full_lls"]
        for a, q, title in ((a3, "b", "(c) RMS |b̂ - b| [m/s²]"), (a4, "M", "(d) RMS ‖M̂ - M‖_F")):
            w = 0.38
            for j, data in enumerate(("quadratic", "linear")):
                vals = [float(comparison[(comparison["data"] == data) & (comparison["method"] == m)
                                         & (comparison["quantity"] == q)]["rms_norm"].iloc[0]) for m in methods]
                bars = a.bar(np.arange(3) + (j - 0.5) * w, vals, w, label=DATA_LABELS[data],
                             color=("C0", "C2")[j])
                for bar, v in zip(bars, vals):
                    a.text(bar.get_x() + bar.get_width() / 2, v * 1.15, f"{v:.1e}", ha="center", fontsize=5.5,
                           rotation=90, va="bottom")
            a.set_xticks(np.arange(3), ["Table I", "Table I\nno quad.", "full LLS"], fontsize=7)
            a.set(yscale="log", title=title)
            lo = min(comparison.loc[comparison["quantity"] == q, "rms_norm"])
            a.set_ylim(lo / 10, a.get_ylim()[1] * 30)
            a.legend(fontsize=6, loc="upper left")
    return fig


def plot_estimates(example: pd.DataFrame, which: str, title: str, sigma: bool = False):
    """Estimate vs truth of one state block (``'g'`` Fig. 4, ``'b'`` Fig. 5), one run."""
    est, tru, sig = _wide(example, "estimate"), _wide(example, "truth"), _wide(example, "sigma")
    unit = "[m/s²]"
    with plt.rc_context(RC):
        fig, axs = plt.subplots(3, 1, figsize=(7.0, 5.4), sharex=True, layout="constrained")
        for k, ax in enumerate(axs):
            c = f"{which}_{AXES[k]}"
            t = est.index.to_numpy()
            ax.plot(t, est[c], color=COMP_COLORS[k], lw=1.0, label=f"estimate {c}")
            ax.plot(t, tru[c], color="k", lw=0.8, ls="--", label="truth")
            if sigma:
                ax.fill_between(t, est[c] - sig[c], est[c] + sig[c], color=COMP_COLORS[k], alpha=0.15,
                                label="± filter σ", lw=0)
                span = np.abs(tru[c]).max() + 0.05
                ax.set_ylim(-span * 1.3, span * 1.3)
            ax.set_ylabel(f"{c} {unit}")
            ax.legend(loc="upper right", fontsize=6.5, ncol=3)
        axs[0].set_title(title)
        axs[-1].set_xlabel("t [s]")
    return fig


def plot_errors(summary: pd.DataFrame, noise_acc: float, linthresh: float | None = None,
                cost: pd.DataFrame | None = None):
    """Errors of v, g and b (cf. Figs. 6-8): Monte Carlo mean, ±1 std over runs, filter ±σ, one run.

    Symmetric-log y axis (linear within ``±linthresh``) so that the initial errors, the
    convergence and the steady state all show.  ``cost`` (:func:`filter_cost` table)
    adds the filter's cost per step to the title.
    """
    mean, std = _wide(summary, "mean_error"), _wide(summary, "std_error")
    sig, one = _wide(summary, "filter_sigma"), _wide(summary, "run0_error")
    n = int(summary["n_runs"].iloc[0])
    t = mean.index.to_numpy()
    lin = linthresh or noise_acc
    with plt.rc_context(RC):
        fig, axs = plt.subplots(3, 3, figsize=(7.8, 6.4), sharex=True, layout="constrained")
        for i, (blk, unit) in enumerate((("v", "m/s"), ("g", "m/s²"), ("b", "m/s²"))):
            for k in range(3):
                ax = axs[i, k]
                c = f"{blk}_{AXES[k]}"
                ax.plot(t, one[c], color="0.6", lw=0.5, label="one run")
                ax.fill_between(t, mean[c] - std[c], mean[c] + std[c], color=COMP_COLORS[k], alpha=0.3, lw=0,
                                label="mean ± std (runs)")
                ax.plot(t, mean[c], color=COMP_COLORS[k], lw=1.0, label=f"mean of {n} runs")
                ax.plot(t, sig[c], "k--", lw=0.7, label="± filter σ")
                ax.plot(t, -sig[c], "k--", lw=0.7)
                if blk != "v":
                    ax.axhspan(-noise_acc, noise_acc, color="C3", alpha=0.08, lw=0, label="± accel. noise")
                ax.set_yscale("symlog", linthresh=lin if blk != "v" else 10 * lin)
                ax.set_title(f"error {c} [{unit}]", fontsize=8)
                ax.tick_params(labelsize=6.5)
        for ax in axs[-1]:
            ax.set_xlabel("t [s]")
        axs[1, 2].legend(loc="upper right", fontsize=5.5)
        title = f"Filter errors (cf. Figs. 6-8): {n} Monte Carlo runs"
        if cost is not None and len(cost):
            one = cost[cost["runs"] == 1].iloc[0]
            many = cost[cost["runs"] > 1].iloc[0]
            title += (f"; cost {one['us_per_step']:.0f} µs/step (one run, own covariance), "
                      f"{many['us_per_run_step']:.1f} µs per run-step (shared gains, {int(many['runs'])} runs)")
        fig.suptitle(title, fontsize=8)
    return fig


def plot_observability(obs: pd.DataFrame, gramian: pd.DataFrame, axis_label: str):
    """Errors of g and b along and across the rotation axis, changing vs fixed ω direction."""
    with plt.rc_context(RC):
        fig, axs = plt.subplots(2, 2, figsize=(7.6, 5.4), sharex=True, sharey="row", layout="constrained")
        for j, (case, title) in enumerate((("changing", "ω changes direction"),
                                           ("constant", f"ω along a fixed body axis n = {axis_label}"))):
            gm = gramian.set_index("case").loc[case]
            for i, blk in enumerate(("g", "b")):
                ax = axs[i, j]
                for comp, color, lab in ((f"{blk}_axial", "C3", f"{blk}·n (along ω axis)"),
                                         (f"{blk}_perp", "C0", f"|{blk}⊥| (across)")):
                    d = obs[(obs["case"] == case) & (obs["component"] == comp)].sort_values("t")
                    ax.plot(d["t"], d["rms_error"], color=color, lw=1.1, label=f"RMS error {lab}")
                    ax.plot(d["t"], d["filter_sigma"], color=color, lw=0.8, ls="--", label="filter σ")
                ax.set(yscale="log")
                ax.set_ylabel(f"{blk} error [m/s²]")
                if i == 0:
                    ax.set_title(f"{title}\nGramian λmin/λmax = {gm['eig_ratio']:.1e}", fontsize=8)
                ax.text(0.98, 0.95, f"{'gravity' if blk == 'g' else 'bias'}", transform=ax.transAxes, ha="right",
                        va="top", fontsize=8)
        for ax in axs[-1]:
            ax.set_xlabel("t [s]")
        handles = [plt.Line2D([], [], color="C3", lw=1.1), plt.Line2D([], [], color="C0", lw=1.1),
                   plt.Line2D([], [], color="k", lw=0.8, ls="--")]
        fig.legend(handles, ["RMS error along the axis n (g·n, b·n)", "RMS error across it (|g⊥|, |b⊥|)",
                             "filter σ (same colour)"], loc="outside lower center", ncol=3, fontsize=7)
    return fig


__all__ = ["plot_calibration", "plot_errors", "plot_estimates", "plot_observability", "plot_trajectories"]
