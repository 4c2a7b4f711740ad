"""Every real gyro session through the gyro loop, and what repeats across sessions of one unit.

Each session of :data:`accelcal_repro.gyro.sessions.SESSIONS` with motions between rests is
read and its poses found as ``accelcal discrepancy`` does (the shared front end), then the
gyro loop runs (:func:`accelcal.discrepancy.gyro_loop.gyro_layer`).

What repeats (:func:`repeat_table`): an effect named on some session of a unit is fitted on
every tested session of that unit (named there or not:
:func:`accelcal.discrepancy.gyro_loop.estimate_effects`), and its estimates are compared
with their standard errors: ``χ² = Σ_sessions Σ_params ((x - x̄_w) / se)²`` on ``(S - 1) k``
degrees of freedom (``x̄_w`` the inverse-variance mean).  An effect *repeats*, a property
of the sensor, when it is named on at least two sessions and its estimates agree
(``p ≥ 0.01``); named once, or estimates that disagree, it is not (a disturbed session, a
misfit of that session's noise).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal import distributions as dist
from accelcal.discrepancy.gyro_loop import estimate_effects, gyro_layer
from accelcal.errors import AccelcalError
from accelcal.gyro.recording import MIN_RESTS
from accelcal.static_auto import find_static_poses

from .sessions import SESSIONS, local_paths, read_session

#: Sessions of one unit (the rest are single sessions of their unit).
UNITS = {"imutk_fork": ("fork_data1", "fork_data2", "fork_data3", "fork_data4"),
         "snu": ("snu_good1", "snu_good2", "snu_good3"), "xsens": ("xsens",)}
#: Estimates that agree across sessions at this level (χ² test) repeat.
AGREE_P = 0.01


def session_results(names=None, n_boot: int = 999, paths=None, noise: str = "common") -> dict:
    """``{session: (GyroLoopResult or None, reason)}`` of every session in ``names`` (default:
    :data:`UNITS`); ``paths`` ``{dataset: {file: path}}`` (default: the shared copy, else a download)."""
    names = list(names or [n for u in UNITS.values() for n in u])
    paths = paths if paths is not None else local_paths(names)
    out = {}
    for n in names:
        spec = SESSIONS[n]
        rec = read_session(spec, paths)
        try:
            poses, _ = find_static_poses(rec, spec.g, {}, max(10, MIN_RESTS))
        except AccelcalError as e:
            out[n] = (None, str(e).splitlines()[0][:160])
            continue
        out[n] = gyro_layer(rec, spec.g, poses, n_boot=n_boot, noise=noise)
    return out


def session_rows(results: dict) -> pd.DataFrame:
    """One row per session: effects named, excess before/after, motions, or why not tested."""
    rows = []
    for n, (res, err) in results.items():
        if res is None:
            rows.append({"session": n, "named": "", "reason": err})
            continue
        first = res.rounds[0]
        est = "; ".join(f"{p} {v:+.3g} ± {s:.2g}" for e in res.estimates.values() for p, (v, s) in e.items())
        rows.append({"session": n, "n_motions": res.n_motions, "named": ",".join(res.named) or "none",
                     "excess_before": res.excess_before, "excess_after": res.excess_after, "estimates": est,
                     "not_identifiable": ",".join(c for c, r in first.items() if r["status"] == "not_identifiable"),
                     **{f"p_{c}": r.get("p_adjusted") for c, r in first.items()}, "reason": ""})
    return pd.DataFrame(rows)


def agreement(estimates: list[dict]) -> tuple[float, int, float]:
    """``(χ², dof, p)`` of one effect's estimates ``[{param: (value, se)}]`` across sessions."""
    chi2, dof = 0.0, 0
    for p in estimates[0]:
        x = np.array([e[p][0] for e in estimates])
        w = 1.0 / np.array([e[p][1] for e in estimates]) ** 2
        mean = np.sum(w * x) / np.sum(w)
        chi2 += float(np.sum(w * (x - mean) ** 2))
        dof += len(x) - 1
    return chi2, dof, float(dist.chi2_sf(chi2, dof)) if dof else float("nan")


def repeat_table(results: dict, units=UNITS) -> pd.DataFrame:
    """Per unit and effect named on any of its sessions: on how many named, the estimates
    on every tested session, their agreement, and whether the effect repeats (module docstring)."""
    out = []
    for unit, names in units.items():
        tested = {n: results[n][0] for n in names if n in results and results[n][0] is not None}
        effects = sorted({e for r in tested.values() for e in r.named})
        for e in effects:
            k = sum(e in r.named for r in tested.values())
            est = {n: estimate_effects(r.motions, [e]).get(e) for n, r in tested.items()}
            est = {n: v for n, v in est.items() if v is not None}
            chi2, dof, p = agreement(list(est.values())) if len(est) > 1 else (float("nan"), 0, float("nan"))
            shown = "; ".join(f"{n}: " + ", ".join(f"{q} {v:+.3g} ± {s:.2g}" for q, (v, s) in x.items())
                              for n, x in est.items())
            out.append({"unit": unit, "effect": e, "sessions_named": k, "sessions_tested": len(tested),
                        "sessions_estimated": len(est), "chi2": chi2, "dof": dof, "p_agree": p,
                        "repeats": bool(k >= 2 and len(est) >= 2 and p >= AGREE_P), "estimates": shown})
    return pd.DataFrame(out, columns=["unit", "effect", "sessions_named", "sessions_tested", "sessions_estimated",
                                      "chi2", "dof", "p_agree", "repeats", "estimates"])


def session_tables(config: dict, paths=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The workflow's real sessions through the loop (config ``gyro.loop.sessions``): rows, repeats."""
    c = config["loop"]
    results = session_results(c["sessions"], n_boot=int(c["benchmark"]["n_boot"]), paths=paths,
                              noise=c.get("noise", "common"))
    return session_rows(results), repeat_table(results)


__all__ = ["AGREE_P", "UNITS", "agreement", "repeat_table", "session_results", "session_rows", "session_tables"]
