"""Every real session with gyro data: accelcal's calibration, the peers', the figure of merit,
and the session-to-session stability of the gyro parameters.

Tables (tidy, written by :func:`run`):

* ``sessions.csv`` — per session: poses, motions, how the rests were found, χ²/dof, RMS
  motion residual vs the noise, the time base used, g-sensitivity test, warnings, or the
  one-line error of a session that cannot be calibrated; ``sessions_timing.csv`` the
  accelerometer's and the gyro's times (wall times apart: the other tables are
  byte-identical on a rerun);
* ``parameters.csv`` — per session and parameter: ours ± s.e.
  (:func:`accelcal_repro.gyro.peers.compare_parameters` adds the peers and the difference
  in s.e.: ``peer_parameters.csv``);
* ``figure_of_merit.csv`` — per session and calibration (:func:`accelcal_repro.gyro.peers.figure_of_merit`);
* ``imucal_parameters.csv``, ``imucal_figure_of_merit.csv``, ``ctu_parameters.csv`` — the
  Ferraris sessions (:mod:`accelcal_repro.gyro.ferraris_sessions`);
* ``stability.csv`` — per group of sessions of one unit (IMU-TK fork data1-4, SNU good1-3)
  and parameter: mean, scatter between sessions, the median s.e., the χ²/dof of the
  sessions about their weighted mean and its square root, the excess (1: the sessions agree
  within their standard errors); pooled rows ``s_*`` and ``T_*`` sum the χ² and the dof
  of the scales and of the misalignments; ``noise_model`` False: the same sessions
  calibrated with the rest noise alone (the ± before :mod:`accelcal.gyro.noise`), whose
  figure of merit is ``accelcal_rest_noise`` in ``figure_of_merit.csv``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from accelcal.errors import AccelcalError

from .ferraris_sessions import ctu_calibration, imucal_comparison, run_imucal
from .peers import compare_parameters, figure_of_merit, peer_calibrations
from .sessions import CTU, SESSIONS, calibrate_session

GROUPS = {"imutk_fork": ("fork_data1", "fork_data2", "fork_data3", "fork_data4"),
          "snu": ("snu_good1", "snu_good2", "snu_good3")}


def _our_parameters(name: str, g) -> list[dict]:
    m, se = g.model, g.standard_errors
    rows = []
    for a in range(3):
        rows.append({"session": name, "parameter": f"s_{'xyz'[a]}", "unit": "ppm",
                     "value": 1e6 * g.scale_factors[a], "se": 1e6 * se["scale_factors"][a]})
    for i in range(3):
        for j in range(3):
            if i != j:
                rows.append({"session": name, "parameter": f"T_{'xyz'[i]}{'xyz'[j]}", "unit": "mrad",
                             "value": 1e3 * m.T[i, j], "se": 1e3 * se["T"][i, j]})
    for a in range(3):
        rows.append({"session": name, "parameter": f"b_{'xyz'[a]}", "unit": m.raw_unit, "value": m.bias[a],
                     "se": se["bias"][a]})
    return rows


def stability(params: pd.DataFrame, groups=GROUPS) -> pd.DataFrame:
    """Session-to-session scatter of each parameter within each group (module docstring), and
    pooled over the scales (``s_*``) and over the misalignments (``T_*``): their χ² summed,
    over their dof summed (the biases are not pooled: a turn-on bias differs by session)."""
    rows = []
    for group, names in groups.items():
        sub = params[params.session.isin(names)]
        for p, d in sub.groupby("parameter", sort=False):
            if len(d) < 2:
                continue
            w = 1.0 / d.se.to_numpy() ** 2
            mean = float(np.sum(w * d.value) / np.sum(w))
            chi2 = float(np.sum(w * (d.value - mean) ** 2))
            rows.append({"group": group, "parameter": p, "unit": d.unit.iloc[0], "sessions": len(d),
                         "weighted_mean": mean, "scatter_std": float(d.value.std(ddof=1)),
                         "median_se": float(d.se.median()), "excess": math.sqrt(chi2 / (len(d) - 1)),
                         "chi2": chi2, "dof": len(d) - 1, "chi2_per_dof": chi2 / (len(d) - 1)})
    out = pd.DataFrame(rows)
    pooled = []
    for group in dict.fromkeys(out.group) if len(out) else ():
        for kind, prefix in (("s_*", "s_"), ("T_*", "T_")):
            d = out[(out.group == group) & out.parameter.str.startswith(prefix)]
            if len(d):
                chi2, dof = float(d.chi2.sum()), int(d.dof.sum())
                pooled.append({"group": group, "parameter": kind, "unit": d.unit.iloc[0], "sessions": int(d.sessions.max()),
                               "excess": math.sqrt(chi2 / dof), "chi2": chi2, "dof": dof, "chi2_per_dof": chi2 / dof})
    return pd.concat([out, pd.DataFrame(pooled)], ignore_index=True) if pooled else out


def _session_row(name: str, r: dict) -> dict:
    g, q = r["gyro"], r["gyro"].quality
    tb = g.settings.get("time_base", {})
    return {"session": name, "estimator": g.CAL_TYPE, "poses": len(r["poses"]), "motions": q.n_motions,
            "rests": r["static_note"], "chi2_per_dof": q.chi2 / q.dof if q.dof > 0 else np.nan, "excess": q.excess,
            "residual_rms_deg": q.residual_rms_deg if q.dof > 0 else np.nan,
            "predicted_rms_deg": q.predicted_rms_deg, "time_base": tb.get("used", "index"),
            "jitter": tb.get("jitter", np.nan), "g_sensitivity": bool(g.settings.get("g_sensitivity", False)),
            "iterations": g.settings.get("iterations"), "warnings": " | ".join(q.warnings), "error": ""}


def run(out: Path, paths: dict, sessions=tuple(SESSIONS), imutk_run: dict | None = None,
        summaries: dict | None = None) -> dict[str, pd.DataFrame]:
    """Calibrate every session, compare with the peers, and write the tables into ``out``;
    ``summaries``, if given, receives each session's gyro calibration's Summary (for the report).

    ``paths``: ``{dataset: {file: path}}`` (:func:`.sessions.local_paths`, or the workflow's
    manifests); ``imutk_run``: the ``runs`` of ``tools/gyro_peers.py``'s ``imutk.json``, or None.
    A session that cannot be calibrated is a row with its one-line error (a finding)."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    srows, prows, peer_tabs, foms, times, rest_rows = [], [], [], [], [], []
    tabs = {"imucal_parameters": pd.DataFrame(), "imucal_figure_of_merit": pd.DataFrame()}
    for name in sessions:
        spec = SESSIONS[name]
        try:
            r = calibrate_session(spec, paths)
        except AccelcalError as e:  # the command line's one-line refusal, recorded
            srows.append({"session": name, "error": f"{type(e).__name__}: {e}"})
            continue
        srows.append(_session_row(name, r))
        if summaries is not None:
            summaries[name] = r["gyro"].summary()
        times.append({"session": name, "accelerometer_s": r["acc_seconds"], "gyro_s": r["gyro_seconds"]})
        prows += _our_parameters(name, r["gyro"])
        if any(name in g for g in GROUPS.values()):  # the same session with the rest noise alone (before)
            before = calibrate_session(spec, paths, noise_model=False)["gyro"]
            rest_rows += [{**row, "noise_model": False} for row in _our_parameters(name, before)]
            foms.append(figure_of_merit(name, r["rec"], r["poses"], r["acc"], before, {}).query(
                "calibration == 'accelcal'").assign(calibration="accelcal_rest_noise"))
        if r["rec"].rotations:  # a Ferraris session: imucal runs on it (its own accelerometer for everyone)
            p = paths[spec.dataset]
            imucal = run_imucal(p[spec.acc], p[spec.intervals])
            tabs["imucal_parameters"], tabs["imucal_figure_of_merit"] = imucal_comparison(r, imucal)
            continue
        peers = peer_calibrations(spec, r["gyro"].model.raw_unit, paths, imutk_run)
        if peers:
            peer_tabs.append(compare_parameters(name, r["gyro"], peers))
        foms.append(figure_of_merit(name, r["rec"], r["poses"], r["acc"], r["gyro"], peers))
    tabs.update({"sessions": pd.DataFrame(srows), "sessions_timing": pd.DataFrame(times),
                 "parameters": pd.DataFrame(prows),
                 "peer_parameters": pd.concat(peer_tabs, ignore_index=True) if peer_tabs else pd.DataFrame(),
                 "figure_of_merit": pd.concat(foms, ignore_index=True) if foms else pd.DataFrame()})
    rest = pd.DataFrame(rest_rows)
    tabs["stability"] = pd.concat([stability(tabs["parameters"]).assign(noise_model=True)]
                                  + ([stability(rest).assign(noise_model=False)] if len(rest) else []),
                                  ignore_index=True)
    tabs["ctu_parameters"] = ctu_calibration(paths[CTU[0]][CTU[1]])
    tabs = {k: v if len(v.columns) else pd.DataFrame(columns=["none"]) for k, v in tabs.items()}  # a header
    for k, v in tabs.items():
        v.to_csv(out / f"{k}.csv", index=False)
    return tabs


COLORS = {"accelcal": "C0", "accelcal_rest_noise": "0.6", "imutk_run": "C1", "imutk_published": "C3", "factory": "C2",
          "imucal": "C4",
          "accelcal_measured_axes": "C9"}


def figure(fom: pd.DataFrame, imucal_fom: pd.DataFrame | None = None):
    """RMS per-motion misfit [deg] per session and calibration (own bias), and the noise level;
    a calibration whose trust verdict is ``poorly_determined`` is hatched, its reasons written above it."""
    import matplotlib.pyplot as plt

    from accelcal.plotting import RC

    frames = [f for f in (fom, imucal_fom) if f is not None and "rms_deg" in f.columns]  # a table may be empty
    sub = pd.concat([f[f.bias == "own_bias"] if "bias" in f.columns else f.assign(bias="own_bias") for f in frames],
                    ignore_index=True) if frames else pd.DataFrame(columns=["session", "calibration", "rms_deg",
                                                                            "noise_rms_deg"])
    poor = (sub.verdict == "poorly_determined").to_numpy() if "verdict" in sub.columns else np.zeros(len(sub), bool)
    sessions = list(dict.fromkeys(sub.session))
    with plt.rc_context(RC):
        fig, ax = plt.subplots(figsize=(8.0, 3.6), layout="constrained")
        for i, sname in enumerate(sessions):
            d, bad = sub[sub.session == sname], poor[sub.session.to_numpy() == sname]
            width = 0.8 / len(d)
            x = i + (np.arange(len(d)) - (len(d) - 1) / 2) * width
            ax.bar(x, d.rms_deg, width, color=[COLORS.get(c, "0.5") for c in d.calibration],
                   hatch=["////" if b else None for b in bad], edgecolor=["C3" if b else "none" for b in bad],
                   linewidth=0.8)
            if bad.any():  # the reasons once per session, above its highest bar (so no bar covers them)
                why = dict.fromkeys(r for rs in d.reasons[bad] for r in str(rs).split("; "))
                ax.annotate("\n".join(why).replace(" (", "\n("), (x[bad].mean(), d.rms_deg.max()), xytext=(0, 2),
                            textcoords="offset points", ha="center", va="bottom", fontsize=5.5, color="C3", zorder=4)
        noise = sub.groupby("session").noise_rms_deg.first()
        ax.scatter(range(len(sessions)), [noise[s] for s in sessions], marker="_", s=400, color="k", zorder=3,
                   label="noise (rests)")
        handles, labels = ax.get_legend_handles_labels()
        for c in dict.fromkeys(sub.calibration):
            handles.append(plt.Rectangle((0, 0), 1, 1, color=COLORS.get(c, "0.5")))
            labels.append(c.replace("_", " "))
        if poor.any():
            handles.append(plt.Rectangle((0, 0), 1, 1, facecolor="white", edgecolor="C3", hatch="////"))
            labels.append("poorly determined\n(accelcal's trust verdict:\nfew dof or none, little\nrotation per axis; "
                          "reasons\nabove the bar)")
        ax.set_yscale("log")
        ax.margins(y=0.25)
        ax.set_xticks(range(len(sessions)), [s.replace("_", " ") for s in sessions], rotation=20, fontsize=7.5)
        ax.set_ylabel("RMS gravity misfit per motion [deg]")
        ax.legend(handles, labels, fontsize=6.5, loc="upper left", bbox_to_anchor=(1.0, 1.0))
        ax.set_title("gravity at each rest vs the previous rest's carried by the calibrated gyro (Magnus-4)",
                     fontsize=8.5)
    return fig


__all__ = ["GROUPS", "figure", "run", "stability"]
