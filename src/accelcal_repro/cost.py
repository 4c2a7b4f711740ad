"""Where the compute time goes: the summary table and the figure of the ``benchmark`` target.

Inputs are the tables of :mod:`accelcal_repro.timing`: the estimator timings
(:func:`~accelcal_repro.timing.summarize_timing` of the burkhard2024 timing job), the
filter costs (:func:`~accelcal_repro.timing.filter_timing`), the first-call times
(:func:`~accelcal_repro.timing.compile_timing`) and the job-seconds per stage
(:func:`~accelcal_repro.timing.stage_job_seconds`).  :func:`headline` picks the numbers
the project sets goals for (24 poses, compiled kernels and numpy reference side by side);
:func:`plot_cost` draws all four.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from accelcal.plotting import RC, style
from accelcal import registry

from .timing import preferred_backend

def _estimator_headlines(goals: Mapping[str, float]) -> list[tuple]:
    """Headline quantities of the registry's estimators: (name, table, selector, column,
    unit, goal key, goal is a minimum).  The time of every estimator on one problem (closed
    forms first, those without a noise level before the others); the speed-up over its
    baseline of each estimator with a goal for it (``<name>_speedup``); the throughput of
    every closed form's batched form (goal ``<name>_batch_per_s``)."""
    timed = sorted(registry.estimators("accelerometer"), key=lambda e: (e.family != "closed_form", e.needs_noise))
    rows = [(f"{e.label}, one problem" + (" (noise known)" if e.noise_use == "correction" else ""), "single",
             e.name, "median_s", "µs", None, None) for e in timed]
    rows += [(f"speed-up {registry.ESTIMATORS[e.baseline].label} / {e.label}", "single", e.name, "speedup_median", "×",
              f"{e.name}_speedup", True) for e in timed if e.baseline and f"{e.name}_speedup" in goals]
    rows += [(f"batched {e.label}", "batch", e.batch_name, "problems_per_s", "problems/s",
              f"{e.batch_name}_per_s" if f"{e.batch_name}_per_s" in goals else None, True)
             for e in timed if e.batch and e.family == "closed_form"]
    return rows


_FILTER_HEADLINES = (
    ("Batista filter (own covariance), one run", "batista", "kalman_filter", "us_per_step", "batista_us_per_step"),
    ("Batista shared-gain Monte Carlo, per run", "batista", "shared_gain", "us_per_run_step", None),
    ("Tereshkov estimator, one run", "tereshkov", "(1 run)", "us_per_step", "tereshkov_us_per_step"),
    ("Tereshkov estimator batched, per run", "tereshkov", "runs)", "us_per_run_step", None),
)


def headline(estimators: pd.DataFrame, filters: pd.DataFrame, compile_times: pd.DataFrame, stages: pd.DataFrame,
             goals: Mapping[str, float], n_poses: int = 24, interleave: str = "block") -> pd.DataFrame:
    """One row per quantity and implementation: ``quantity, backend, value, unit, goal,
    meets_goal`` (NaN / empty where the project sets no goal).  Estimator times at
    ``n_poses`` (``interleave`` timings) and throughputs; filter cost per step; first-call
    time summed over the kernels (cold and cached); job-seconds per stage.  Throughputs
    and filter costs also from CPU time (``(CPU time)`` rows): on an idle machine the two
    agree, on a loaded one a call of milliseconds waits for a core and only its CPU time
    measures the code."""
    rows = []
    t = estimators if "backend" in estimators else estimators.assign(backend="")
    for name, mode, method, col, unit, goal, at_least in _estimator_headlines(goals):
        d = t[(t["mode"] == mode) & (t["method"] == method) & (t["n_poses"] == n_poses)]
        if mode == "single":
            d = d[d["interleave"] == interleave]
        for _, r in d.sort_values("backend", key=lambda b: b != preferred_backend(t, method)).iterrows():
            value = 1e6 * r[col] if unit == "µs" else r[col]
            judged = r["backend"] == preferred_backend(t, method)
            rows.append(_row(name, r["backend"], value, unit, goals.get(goal) if goal else None, at_least, judged))
            if mode == "batch" and np.isfinite(r.get("problems_per_cpu_s", np.nan)):
                rows.append(_row(f"{name} (CPU time)", r["backend"], r["problems_per_cpu_s"], unit,
                                 goals.get(goal) if goal else None, at_least, judged))
    for name, flt, impl, col, goal in _FILTER_HEADLINES:
        d = filters[(filters["filter"] == flt) & filters["implementation"].str.contains(impl, regex=False)]
        default = "numba" if "numba" in set(d["backend"]) else "numpy"
        for _, r in d.sort_values("backend", key=lambda b: b != default).iterrows():
            rows.append(_row(name, r["backend"], r[col], "µs", goals.get(goal) if goal else None, False,
                             r["backend"] == default))
            cpu = r.get("cpu_seconds", np.nan)
            if np.isfinite(cpu):
                rows.append(_row(f"{name} (CPU time)", r["backend"], r[col] * cpu / r["seconds"], "µs",
                                 goals.get(goal) if goal else None, False, r["backend"] == default))
    if len(compile_times):
        kern = compile_times[~compile_times["call"].str.startswith("import")]
        rows.append(_row("first calls of the compiled kernels, empty cache (compilation)", "numba",
                         kern["cold_s"].sum(), "s", None, None, False))
        rows.append(_row("first calls of the compiled kernels, disk cache", "numba", kern["cached_s"].sum(), "s",
                         None, None, False))
    for _, r in stages.iterrows():
        rows.append(_row(f"stage {r['stage']}: {int(r['jobs'])} jobs, CPU seconds", "", r["cpu_s"], "s", None, None,
                         False))
        rows.append(_row(f"stage {r['stage']}: {int(r['jobs'])} jobs, wall seconds", "", r["s"], "s", None, None,
                         False))
    return pd.DataFrame(rows, columns=["quantity", "backend", "value", "unit", "goal", "meets_goal"])


def _row(name, backend, value, unit, goal, at_least, judged) -> dict:
    """A headline row; the goal is judged on the default implementation only."""
    met = ""
    if goal is not None and judged and np.isfinite(value):
        met = "yes" if (value >= goal if at_least else value <= goal) else "no"
    return {"quantity": name, "backend": backend, "value": float(value), "unit": unit,
            "goal": float(goal) if goal is not None else np.nan, "meets_goal": met}


def plot_cost(estimators: pd.DataFrame, filters: pd.DataFrame, compile_times: pd.DataFrame, stages: pd.DataFrame,
              interleave: str = "block"):
    """(a) Time per problem vs pose count of every estimator, one problem at a time
    (markers) and batched (per problem, dashed), compiled kernels solid, numpy reference
    dotted; (b) cost per step of the filters; (c) first-call time of each compiled kernel
    with an empty and with a filled disk cache; (d) job-seconds per workflow stage."""
    from matplotlib.lines import Line2D

    t = estimators if "backend" in estimators else estimators.assign(backend="")
    with plt.rc_context({**RC, "axes.titlesize": 8.5}):
        fig, axes = plt.subplots(2, 2, figsize=(9.5, 8.0), layout="constrained")
        ax = axes[0, 0]
        single = t[(t["mode"] == "single") & (t["interleave"] == interleave)]
        batch = t[t["mode"] == "batch"]
        methods = []
        timed = registry.estimators("accelerometer")
        for m, rows, batched in [(e.name, single, False) for e in timed] + \
                                [(e.batch_name, batch, True) for e in timed if e.batch and e.family == "closed_form"]:
            for be in sorted(set(rows.loc[rows["method"] == m, "backend"])):
                d = rows[(rows["method"] == m) & (rows["backend"] == be)].sort_values("n_poses")
                st = style(m)
                ax.plot(d["n_poses"], 1e6 * d["median_s"], ls=_line(be, batched), marker=st["marker"],
                        color=st["color"], ms=3.5 if batched else 4, mfc="none" if not batched else st["color"],
                        lw=1.0)
                if m not in methods:
                    methods.append(m)
        handles = [Line2D([], [], color=style(m)["color"], marker=style(m)["marker"], ls="none",
                          mfc=style(m)["color"] if m.endswith("_batch") else "none", label=style(m)["label"])
                   for m in methods]
        handles += [Line2D([], [], color="0.3", ls=_line(be, b), label=lab) for be, b, lab in (
            ("numba", False, "compiled (numba)"), ("numpy", False, "numpy reference"),
            ("casadi", False, "CasADi/IPOPT"), ("numba", True, "batched, compiled"),
            ("numpy", True, "batched, numpy"))]
        ax.legend(handles=handles, fontsize=5.5, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.14))
        ax.set(xscale="log", yscale="log", xlabel="number of poses", ylabel="wall time per problem [µs]",
               title="(a) estimators: time per problem")
        _barh(axes[0, 1], [(f"{r['filter']}: {r['implementation']}", r["backend"],
                            r["us_per_step"] if r["runs"] == 1 else r["us_per_run_step"]) for _, r in filters.iterrows()],
              "µs per step (per run for the batched rows)", "(b) filters: cost per step")
        kern = compile_times
        _barh(axes[1, 0], [(r["call"], "empty cache", r["cold_s"]) for _, r in kern.iterrows()]
              + [(r["call"], "disk cache", r["cached_s"]) for _, r in kern.iterrows()],
              "first-call time in a fresh process [s]", "(c) compiled kernels: first call", colors=("C3", "C2"))
        _barh(axes[1, 1], [(r["stage"], "wall", r["s"]) for _, r in stages.iterrows()]
              + [(r["stage"], "CPU", r["cpu_s"]) for _, r in stages.iterrows()],
              "seconds, summed over the stage's jobs", "(d) workflow stages: job-seconds of the last run",
              colors=("C7", "C0"))
    return fig


def _line(backend: str, batched: bool):
    """Line style of an implementation: solid compiled/CasADi, dotted numpy; dashed batched."""
    if batched:
        return "--" if backend == "numba" else (0, (1, 2.5))
    return ":" if backend == "numpy" else "-"


def _barh(ax, items, xlabel: str, title: str, colors=("C0", "C1")) -> None:
    """Grouped horizontal bars: ``items`` = (row label, group, value)."""
    if not items:
        ax.text(0.5, 0.5, "not measured", ha="center", va="center", transform=ax.transAxes)
        ax.set(title=title, xticks=[], yticks=[])
        return
    labels = list(dict.fromkeys(i[0] for i in items))
    groups = list(dict.fromkeys(i[1] for i in items))
    h = 0.8 / len(groups)
    values = {(i[0], i[1]): i[2] for i in items}
    for k, grp in enumerate(groups):
        ys = [j + (k - (len(groups) - 1) / 2) * h for j in range(len(labels))]
        vs = [values.get((lab, grp), np.nan) for lab in labels]
        ax.barh(ys, vs, height=h, color=colors[k % len(colors)], label=grp)
        for y, v in zip(ys, vs):
            if np.isfinite(v):
                ax.text(v, y, f" {v:.3g}", va="center", fontsize=5.5)
    ax.set_yticks(range(len(labels)), labels, fontsize=6)
    ax.invert_yaxis()
    positive = [v for v in values.values() if np.isfinite(v) and v > 0]
    if positive and max(positive) / min(positive) > 50:
        ax.set_xscale("log")
    ax.set(xlabel=xlabel, title=title)
    ax.margins(x=0.15)
    ax.legend(fontsize=6, loc="best")


__all__ = ["headline", "plot_cost"]
