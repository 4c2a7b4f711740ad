"""Figures of the Tereshkov reproduction (matplotlib, Agg); each returns a Figure.

Write them with :func:`accelcal.plotting.save_figure` (deterministic PNG + PDF).

* :func:`plot_heading` — ``tereshkov_fig2``: heading of simulated field runs (paper Fig. 2).
* :func:`plot_gyro` — ``tereshkov_fig3``: gyro bias estimates vs truth (paper Fig. 3) and
  the Monte Carlo convergence.
* :func:`plot_accel` — ``tereshkov_fig4``: accelerometer bias estimates in the
  artificial-bias test (paper Fig. 4), convergence with and without turns.
* :func:`plot_installation` — ``tereshkov_installation``: installation-angle sweep.
* :func:`plot_comparison` — ``bias_convergence_comparison``: against the Batista (2011) filter.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

try:  # the project's shared style, if present
    from accelcal.plotting import RC as _RC
except ImportError:  # pragma: no cover
    _RC = {"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 7.5}

RC = dict(_RC)
AXIS_COLOR = {"x": "C0", "y": "C3"}
SCENARIO_STYLE = {"field": {"color": "C0", "label": "field runs (straights + turns)"},
                  "straight": {"color": "C1", "label": "straight-only runs"}}


def _mean_abs(df: pd.DataFrame, sensor: str) -> pd.DataFrame:
    d = df[df["sensor"] == sensor]
    g = d.assign(a=d["error"].abs()).groupby("t")
    return pd.DataFrame({"mean_abs": g["a"].mean(), "q90": g["a"].quantile(0.9),
                         "update_time": g["update_time"].mean()}).reset_index()


def _shade_turns(ax, h: pd.DataFrame, thr_dps: float = 3.0):
    turning = np.abs(h["yaw_rate_dps"].to_numpy()) > thr_dps
    t = h["t"].to_numpy()
    edges = np.flatnonzero(np.diff(np.r_[0, turning.astype(int), 0]))
    for a, b in zip(edges[::2], edges[1::2]):
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color="0.85", lw=0, zorder=0)


def plot_heading(headings: pd.DataFrame, turn_rate_dps: float = 3.0):
    """Heading [°] vs time of the example runs, one panel per run (turns shaded)."""
    runs = sorted(headings["run"].unique())
    with plt.rc_context(RC):
        fig, axes = plt.subplots(len(runs), 1, figsize=(7.0, 1.9 * len(runs) + 0.4), sharex=True,
                                 layout="constrained", squeeze=False)
        for k, (ax, run) in enumerate(zip(axes[:, 0], runs)):
            h = headings[headings["run"] == run]
            _shade_turns(ax, h, turn_rate_dps)
            hd = h["heading_deg"].to_numpy()
            jumps = np.abs(np.diff(hd)) > 180
            y = hd.copy()
            y[1:][jumps] = np.nan  # do not draw the wrap-around
            ax.plot(h["t"], y, color="k", lw=1)
            ax.set(ylim=(0, 360), yticks=[0, 90, 180, 270, 360], ylabel="heading [°]",
                   title=f"({chr(97 + k)}) simulated field run {run}: heading (shaded: |yaw rate| > {turn_rate_dps:g} °/s)")
        axes[-1, 0].set_xlabel("time [s]")
    return fig


def _example_panel(ax, d: pd.DataFrame, sensor: str, scale: float, unit: str, title: str,
                   truth_label: str = "truth", truth_col: str = "truth", thin: pd.DataFrame | None = None):
    for axis in ("x", "y"):
        s = d[(d["sensor"] == sensor) & (d["axis"] == axis)]
        if thin is not None:
            s0 = thin[(thin["sensor"] == sensor) & (thin["axis"] == axis)]
            ax.plot(s0["t"], s0["estimate"] * scale, color=AXIS_COLOR[axis], lw=0.7, alpha=0.45)
        ax.plot(s["t"], s["estimate"] * scale, color=AXIS_COLOR[axis], lw=1.1, label=f"{axis} estimate")
        ax.axhline(float(s[truth_col].iloc[0]) * scale, color=AXIS_COLOR[axis], ls="--", lw=1,
                   label=f"{axis} {truth_label}")
    ax.set(xlabel="time [s]", ylabel=f"bias [{unit}]", title=title)
    ax.legend(ncol=2, loc="best")


def _convergence_panel(ax, curves: dict, unit: str, t_paper: float, t_conv: dict, title: str,
                       legend_loc: str = "upper right"):
    for name, c in curves.items():
        st = SCENARIO_STYLE.get(name, {"color": "k", "label": name})
        tc = t_conv.get(name, np.nan)
        settled = f", 95% settled at {tc:.0f} s" if np.isfinite(tc) else ", does not converge"
        ax.plot(c["t"], c["mean_abs"], color=st["color"], lw=1.2, label=st["label"] + settled)
        ax.plot(c["t"], c["q90"], color=st["color"], lw=0.7, ls=":")
        if np.isfinite(tc):
            ax.axvline(tc, color=st["color"], lw=0.9, ls="-.")
    ax.axvline(t_paper, color="k", lw=1.0, ls="--", label=f"paper: ≈{t_paper:g} s")
    ax.set(xlabel="time [s]", ylabel=f"|estimate - truth| [{unit}]", title=title)
    ax.set_yscale("log")
    lo = min(float(c["mean_abs"].min()) for c in curves.values())
    hi = max(float(c["q90"].max()) for c in curves.values())
    ax.set_ylim(lo * 0.5, hi * 6)
    tmax = max(float(c["t"].max()) for c in curves.values())
    ax.set_xlim(0, min(tmax, 4 * t_paper))  # the convergence; the steady state is in the next panel
    ax.legend(loc=legend_loc, title="solid: MC mean |error|, dotted: 90th pct.", title_fontsize=6.5, fontsize=6.5)


def _update_time_panel(ax, c: pd.DataFrame, filt_s: float, unit: str, title: str):
    e0 = float(c["mean_abs"].iloc[0])
    ax.plot(c["update_time"], c["mean_abs"], color="C0", lw=1.2, label="field runs (MC mean |error|)")
    u = np.linspace(0, float(c["update_time"].max()), 200)
    ax.plot(u, e0 * np.exp(-u / filt_s), color="k", ls="--", lw=1,
            label=f"first-order filter, T = {filt_s:g} s")
    ax.axvline(3 * filt_s, color="0.4", lw=0.8, ls=":", label=f"3T = {3 * filt_s:g} s")
    ax.set(xlabel="time spent updating [s] (Monte Carlo mean)", ylabel=f"|estimate - truth| [{unit}]", title=title)
    ax.set_yscale("log")
    ax.set_ylim(float(c["mean_abs"].min()) * 0.3, e0 * 2)
    ax.legend(loc="upper right")


def plot_gyro(field: pd.DataFrame, straight: pd.DataFrame, summary: pd.DataFrame, example_runs=(0, 1),
              paper_conv_s: float = 120.0, filter_s: float = 40.0):
    """Gyro bias estimates of two example runs vs truth, and the Monte Carlo convergence."""
    tconv = {s: float(summary[(summary["scenario"] == s) & (summary["sensor"] == "gyro")]["t_conv"].iloc[0])
             for s in ("field", "straight") if len(summary[summary["scenario"] == s])}
    with plt.rc_context(RC):
        fig, ax = plt.subplots(2, 2, figsize=(7.4, 5.6), layout="constrained")
        for k, run in enumerate(example_runs[:2]):
            _example_panel(ax[0, k], field[field["run"] == run], "gyro", 1.0, "°/s",
                           f"({'ab'[k]}) field run {run}: roll/pitch gyro bias")
        curves = {"field": _mean_abs(field, "gyro"), "straight": _mean_abs(straight, "gyro")}
        _convergence_panel(ax[1, 0], curves, "°/s", paper_conv_s, tconv, "(c) Monte Carlo convergence")
        _update_time_panel(ax[1, 1], curves["field"], filter_s, "°/s", "(d) vs time spent in straight motion")
    return fig


def plot_accel(field: pd.DataFrame, straight: pd.DataFrame, artificial: pd.DataFrame, summary: pd.DataFrame,
               example_run: int = 0, paper_conv_s: float = 300.0, filter_s: float = 40.0):
    """Artificial-bias test (estimates with known added biases), and the convergence of the
    accelerometer estimates in field runs against straight-only runs."""
    tconv = {s: float(summary[(summary["scenario"] == s) & (summary["sensor"] == "accel")]["t_conv"].iloc[0])
             for s in ("field", "straight") if len(summary[summary["scenario"] == s])}
    with plt.rc_context(RC):
        fig, ax = plt.subplots(2, 2, figsize=(7.4, 5.6), layout="constrained")
        art = artificial[(artificial["run"] == example_run)]
        w = art[art["variant"] == "artificial"].copy()
        w["artificial"] = np.where(w["axis"] == "x", w["artificial_x"], w["artificial_y"])
        _example_panel(ax[0, 0], w, "accel", 1.0, "m/s²",
                       f"(a) artificial-bias test, run {example_run} (thin: without)",
                       truth_label="artificial", truth_col="artificial", thin=art[art["variant"] == "plain"])
        # Monte Carlo of the artificial test: estimate - artificial bias
        d = artificial[(artificial["variant"] == "artificial") & (artificial["sensor"] == "accel")].copy()
        d["dev"] = d["estimate"] - np.where(d["axis"] == "x", d["artificial_x"], d["artificial_y"])
        g = d.assign(a=d["dev"].abs()).groupby("t")["a"]
        ax[0, 1].plot(g.mean().index, g.mean().values, color="C2", lw=1.2, label="MC mean |estimate - artificial|")
        ax[0, 1].plot(g.quantile(0.9).index, g.quantile(0.9).values, color="C2", lw=0.7, ls=":",
                      label="90th percentile")
        ax[0, 1].axhline(0.04, color="k", ls="--", lw=1, label="paper: 0.04 m/s² RMS")
        ax[0, 1].set(xlabel="time [s]", ylabel="|estimate - artificial| [m/s²]", yscale="log",
                     title=f"(b) artificial-bias test, {d['run'].nunique()} runs")
        ax[0, 1].legend(loc="upper right")
        curves = {"field": _mean_abs(field, "accel"), "straight": _mean_abs(straight, "accel")}
        _convergence_panel(ax[1, 0], curves, "m/s²", paper_conv_s, tconv,
                           "(c) convergence: turns vs straight only", legend_loc="center right")
        _update_time_panel(ax[1, 1], curves["field"], filter_s, "m/s²", "(d) vs time spent in settled turns")
    return fig


def plot_installation(sweep: pd.DataFrame, gyro_limit: float = 0.02, accel_limit: float = 0.04,
                      max_deg: float = 15.0):
    """Steady-state RMS error vs installation angle, per sensor and mounting kind: against
    the equivalent biases (solid) and, for the accelerometer, the sensor-axis biases
    (dotted); (c) the AHRS tilt error."""
    kinds = list(dict.fromkeys(sweep["kind"]))
    style = {"roll_pitch": ("C0", "o", "roll = pitch = angle"), "yaw": ("C3", "s", "yaw = angle"),
             "all": ("C2", "^", "roll = pitch = yaw = angle")}
    has_ref = "reference" in sweep
    eq = sweep[sweep["reference"] == "equivalent"] if has_ref else sweep
    raw = sweep[sweep["reference"] == "sensor_axes"] if has_ref else sweep.iloc[:0]
    panels = (("gyro", "°/s", gyro_limit, "(a) roll/pitch gyro bias"),
              ("accel", "m/s²", accel_limit, "(b) x/y accelerometer bias"),
              ("attitude", "°", None, "(c) AHRS tilt error"))
    with plt.rc_context(RC):
        fig, axes = plt.subplots(1, 3, figsize=(7.6, 3.5), layout="constrained")
        for ax, (sensor, unit, lim, title) in zip(axes, panels):
            for kind in kinds:
                c, m, lab = style.get(kind, ("k", ".", kind))
                s = eq[(eq["kind"] == kind) & (eq["sensor"] == sensor)].sort_values("angle_deg")
                ax.plot(s["angle_deg"], s["ss_rms"], color=c, marker=m, ms=4, lw=1, label=lab)
                if sensor == "accel" and len(raw):
                    r = raw[(raw["kind"] == kind) & (raw["sensor"] == sensor)].sort_values("angle_deg")
                    if not np.allclose(r["ss_rms"].to_numpy(), s["ss_rms"].to_numpy()):
                        ax.plot(r["angle_deg"], r["ss_rms"], color=c, marker=m, ms=3, lw=0.8, ls=":", mfc="none",
                                label=lab + " (vs sensor-axis biases)")
            if lim is not None:
                ax.axhline(lim, color="k", ls="--", lw=1, label="paper accuracy (0.02 °/s, 0.04 m/s²)")
            ax.axvspan(0, max_deg, color="0.92", lw=0, zorder=0, label=f"up to {max_deg:g}° (paper: 10-15°)")
            ax.set(xlabel="installation angle [°]", ylabel=f"steady-state RMS error [{unit}]", title=title, yscale="log")
        handles, labels = axes[1].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=7)
    return fig




METHOD_STYLE = {"tereshkov": ("C0", "Tereshkov (GNSS specific force + course)"),
                "batista": ("C3", "Batista KF (body velocity; raw gyro)"),
                "batista_ideal_gyro": ("C2", "Batista KF (body velocity; gyro bias removed)")}


def _cost_panel(ax_d, summary: pd.DataFrame, methods: list):
    """(d) of :func:`plot_comparison`: compute cost per filter step, one run and batched."""
    cost = summary.drop_duplicates("method").set_index("method")
    xs = np.arange(len(methods))
    single = [float(cost.loc[m, "us_per_step_single_run"]) for m in methods]
    batched = [float(cost.loc[m, "us_per_run_step_batched"]) for m in methods]
    ax_d.bar(xs - 0.2, single, 0.4, color=[METHOD_STYLE[m][0] for m in methods], label="one run")
    ax_d.bar(xs + 0.2, batched, 0.4, color=[METHOD_STYLE[m][0] for m in methods], alpha=0.45,
             label="per run, runs batched")
    ax_d.set_xticks(xs, [m.replace("_ideal_gyro", "\n(ideal gyro)") for m in methods], fontsize=7)
    ax_d.set(ylabel="wall time per step [µs]", yscale="log", title="(d) compute cost per filter step")
    ax_d.set_ylim(0.5 * min(single + batched), 3 * max(single + batched))
    ax_d.legend(loc="upper right", fontsize=6.5)


def _comparison_table(ax_t, summary: pd.DataFrame, methods: list):
    """The table under :func:`plot_comparison`: settling time, steady-state RMS and cost per method and bias."""
    ax_t.axis("off")
    rows = []
    for m in methods:
        for sensor, unit in (("accel", "m/s²"), ("accel_z", "m/s²"), ("gyro", "°/s")):
            s = summary[(summary["method"] == m) & (summary["sensor"] == sensor)]
            if not len(s):
                continue
            s = s.iloc[0]
            tc = f"{s['t_conv']:.0f} s" if np.isfinite(s["t_conv"]) else "no convergence"
            short = {"tereshkov": "Tereshkov", "batista": "Batista KF, raw gyro",
                     "batista_ideal_gyro": "Batista KF, gyro bias removed"}[m]
            rows.append([short, {"accel": "accel x/y", "accel_z": "accel z", "gyro": "gyro x/y"}[sensor],
                         tc, f"{s['ss_rms']:.4f} {unit}", f"{s['us_per_step_single_run']:.0f}"])
    tab = ax_t.table(cellText=rows, colLabels=["method", "bias", "95% settling", "steady-state RMS",
                                               "µs/step (1 run)"], loc="center", cellLoc="left")
    tab.auto_set_font_size(False)
    tab.set_fontsize(6.5)
    tab.scale(1, 1.15)
    for (r, c_), cell in tab.get_celld().items():
        cell.set_width([0.3, 0.14, 0.18, 0.2, 0.16][c_])


def plot_comparison(table: pd.DataFrame, summary: pd.DataFrame, example_run: int = 0):
    """``bias_convergence_comparison``: accelerometer (x, y) bias error vs time of the three
    methods on the same runs, gyro bias error (Tereshkov only), an example run, and a
    table of convergence time, steady-state RMS and compute cost."""
    methods = [m for m in METHOD_STYLE if m in set(table["scenario"])]
    with plt.rc_context(RC):
        fig = plt.figure(figsize=(7.6, 6.4), layout="constrained")
        gs = fig.add_gridspec(3, 2, height_ratios=[1, 1, 0.62])
        ax_a, ax_b = fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1])
        ax_c, ax_d = fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])
        ax_t = fig.add_subplot(gs[2, :])
        for m in methods:
            col, lab = METHOD_STYLE[m]
            d = table[(table["scenario"] == m) & (table["sensor"] == "accel") & table["axis"].isin(["x", "y"])]
            g = d.assign(a=d["error"].abs()).groupby("t")["a"].mean()
            ax_a.plot(g.index, g.values, color=col, lw=1.2, label=lab)
            ex = d[d["run"] == example_run]
            for axis, ls in (("x", "-"), ("y", "--")):
                e = ex[ex["axis"] == axis]
                ax_c.plot(e["t"], e["estimate"], color=col, lw=1, ls=ls)
        ex = table[(table["scenario"] == methods[0]) & (table["sensor"] == "accel") & (table["run"] == example_run)]
        for axis, ls in (("x", "-"), ("y", "--")):
            tr = ex[ex["axis"] == axis]["truth"]
            if len(tr):
                ax_c.axhline(float(tr.iloc[0]), color="k", lw=0.8, ls=ls)
        gy = table[(table["scenario"] == "tereshkov") & (table["sensor"] == "gyro")]
        g = gy.assign(a=gy["error"].abs()).groupby("t")["a"].mean()
        ax_b.plot(g.index, g.values, color=METHOD_STYLE["tereshkov"][0], lw=1.2, label="Tereshkov")
        ax_b.text(0.97, 0.95, "the Batista model has no gyro bias", transform=ax_b.transAxes, ha="right", va="top",
                  fontsize=7)
        ax_a.set(xlabel="time [s]", ylabel="mean |error| [m/s²]", yscale="log",
                 title="(a) x/y accelerometer bias error (Monte Carlo mean)")
        lo_a, hi_a = ax_a.get_ylim()
        ax_a.set_ylim(lo_a, hi_a * 30)  # room for the legend above the curves
        ax_a.legend(loc="upper right", fontsize=6.5)
        ax_b.set(xlabel="time [s]", ylabel="mean |error| [°/s]", yscale="log", title="(b) roll/pitch gyro bias error")
        ax_c.set(xlabel="time [s]", ylabel="bias [m/s²]",
                 title=f"(c) run {example_run}: x (solid), y (dashed) estimates; truth black")
        _cost_panel(ax_d, summary, methods)
        _comparison_table(ax_t, summary, methods)
    return fig


__all__ = ["plot_accel", "plot_comparison", "plot_gyro", "plot_heading", "plot_installation"]
