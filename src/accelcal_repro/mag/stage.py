"""The ``mag`` stage: every method on every real session, judged by what none of them
optimises — the spread of |m| over the rests (or the rotation) and the spread of the dip
between each rest's field and its vertical — and accelcal's session-to-session scatter
against its standard errors (SNU good1-3)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.discrepancy.mag_loop import field_samples, mag_discrepancy
from accelcal.mag.align import dip_angles
from accelcal.mag.calibrate import calibrate_magnetometer
from accelcal.mag.model import PARAMETERS

from . import peers
from .sessions import FILES, load

METHODS = ("raw", "magneto", "dorveaux", "ck_explorer", "accelcal")
#: The published figures of the peers (tomisuarez2/MagnetometerCalibration README): the
#: spread of |calibrated| after the rest, of the author's parameters and of a plain ellipsoid fit.
PUBLISHED = {("qmc_noisy", "dorveaux_published"): 5.9, ("qmc_filtered", "dorveaux_published"): 3.9,
             ("qmc_noisy", "ellipsoid_published"): 6.4, ("qmc_filtered", "ellipsoid_published"): 3.1}


def _maps(s, published_params=None) -> dict:
    """Each method's correction (a callable raw -> field) on session ``s``; None where it does not apply."""
    ok = np.all(np.isfinite(s.m), axis=1)
    m = s.m[ok]
    out = {"raw": lambda x: np.asarray(x, float)}
    out["magneto"] = peers.magneto(m).apply
    start = int(np.sum(ok[:s.start]))
    out["dorveaux"] = peers.dorveaux(m, start=start).apply
    out["ck_explorer"] = None if s.acc is None else peers.ck_explorer(m, s.acc[ok]).apply
    mc = calibrate_magnetometer(s.m, raw_unit=s.unit, acc_cal=s.acc_cal, poses=s.poses, acc=s.acc)
    out["accelcal"] = mc.apply
    if published_params is not None and s.name.startswith("qmc"):
        out["dorveaux_published"] = peers.published_dorveaux(published_params).apply
    return out, mc


def _spread(h) -> float:
    n = np.linalg.norm(h, axis=1)
    n = n[np.isfinite(n)]
    return float(100 * np.std(n) / np.mean(n))


def session_rows(name: str, data_dir, published_params=None) -> tuple[list[dict], object]:
    s = load(name, data_dir)
    maps, mc = _maps(s, published_params)
    rows = []
    rot = slice(s.start, None)
    for method, f in maps.items():
        if f is None:
            continue
        h_pts = f(s.points(s.m))
        row = {"session": name, "method": method, "n_points": len(h_pts),
               "norm_spread_pct": _spread(h_pts), "norm_spread_rotation_pct": _spread(f(s.m[rot])),
               "dip_spread_deg": np.nan, "dip_mean_deg": np.nan, "notes": s.notes}
        if s.f is not None:
            d = dip_angles(s.f, h_pts)
            row.update(dip_spread_deg=float(np.std(d, ddof=1)), dip_mean_deg=float(np.mean(d)))
        rows.append(row)
    for (sess, method), value in PUBLISHED.items():
        if sess == name:
            rows.append({"session": name, "method": method + "_readme", "n_points": np.nan,
                         "norm_spread_pct": np.nan, "norm_spread_rotation_pct": value, "dip_spread_deg": np.nan,
                         "dip_mean_deg": np.nan, "notes": "the author's README"})
    return rows, mc


def _chi2_dof(x, se) -> float:
    """χ²/dof of the sessions' values about their weighted mean (1: the s.e. explain the scatter)."""
    w = 1.0 / np.asarray(se, float) ** 2
    mu = float(np.sum(w * x) / np.sum(w))
    return float(np.sum(w * (np.asarray(x) - mu) ** 2) / max(len(x) - 1, 1))


def stability(cals: dict) -> pd.DataFrame:
    """Session-to-session scatter of accelcal's parameters against their standard errors:
    ``ratio`` (scatter / RMS s.e.) and ``chi2_dof`` (about the weighted mean; the goal is <= 2)."""
    rows = []
    names = list(cals)
    theta = np.array([cals[n].fit.theta for n in names])
    se = np.array([cals[n].fit.se for n in names])
    for i, p in enumerate(PARAMETERS):
        rows.append({"parameter": p, **{n: theta[k, i] for k, n in enumerate(names)},
                     "scatter": float(np.std(theta[:, i], ddof=1)), "rms_se": float(np.sqrt(np.mean(se[:, i] ** 2))),
                     "ratio": float(np.std(theta[:, i], ddof=1) / np.sqrt(np.mean(se[:, i] ** 2))),
                     "chi2_dof": _chi2_dof(theta[:, i], se[:, i])})
    al = [cals[n].alignment for n in names]
    if all(a is not None for a in al):
        dips = np.array([a.dip_deg for a in al])
        se_d = np.array([a.se_dip_deg for a in al])
        rows.append({"parameter": "dip_deg", **{n: dips[k] for k, n in enumerate(names)},
                     "scatter": float(np.std(dips, ddof=1)), "rms_se": float(np.sqrt(np.mean(se_d**2))),
                     "ratio": float(np.std(dips, ddof=1) / np.sqrt(np.mean(se_d**2))), "chi2_dof": _chi2_dof(dips, se_d)})
    return pd.DataFrame(rows)


def loop_rows(name: str, dirs: dict, *, alpha: float = 0.05, n_boot: int = 199, seed: int = 0) -> list[dict]:
    """The magnetometer loop on one real session: a row per candidate of the first round,
    with what was named, the AR noise model and the excess before and after."""
    s = load(name, dirs[FILES[name][0]])
    samples, _ = field_samples(np.where(np.isfinite(s.m), s.m, 0.0), s.rest_idx, name)
    res = mag_discrepancy(samples, None, alpha=alpha, n_boot=n_boot, seed=seed)
    rows = []
    for c, r in res.rounds[0].items():
        rows.append({"session": name, "candidate": c, "status": r["status"], "F": r.get("F", np.nan),
                     "p_value": r.get("p_value", np.nan), "p_adjusted": r.get("p_adjusted", np.nan),
                     "p_blocks_adjusted": r.get("p_blocks_adjusted", np.nan),
                     "mde": ";".join(f"{x:.3g}" for x in r.get("mde", [])), "window": str(r.get("window", "")),
                     "named": ";".join(res.named) or "none", "excess_before": res.excess_before,
                     "excess_after": res.excess_after, "ar_order": res.noise["order"], "lag1": res.noise["lag1"],
                     "n_samples": res.n_samples})
    return rows


def figure(table: pd.DataFrame):
    """|m| spread and dip spread per session and method (bars)."""
    import matplotlib.pyplot as plt

    t = table[table.method.isin(METHODS)]
    sessions = list(dict.fromkeys(t.session))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    width = 0.8 / len(METHODS)
    for k, method in enumerate(METHODS):
        sub = t[t.method == method].set_index("session").reindex(sessions)
        x = np.arange(len(sessions)) + (k - (len(METHODS) - 1) / 2) * width
        axes[0].bar(x, sub.norm_spread_pct, width, label=method)
        axes[1].bar(x, sub.dip_spread_deg, width, label=method)
    for ax, what in zip(axes, ("|m| spread over the rests / near-g samples [%]",
                               "dip spread between field and vertical [deg]")):
        ax.set_xticks(np.arange(len(sessions)), sessions, rotation=20)
        ax.set_yscale("log")
        ax.set_title(what, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Magnetometer calibrations on real sessions (lower is better; qmc: no accelerometer, no dip)",
                 fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["METHODS", "PUBLISHED", "figure", "loop_rows", "session_rows", "stability"]
