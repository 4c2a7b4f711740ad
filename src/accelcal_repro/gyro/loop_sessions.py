"""Every real gyro session through the gyro loop, and what repeats across sessions of one unit.

Each session of :data:`accelcal_repro.gyro.sessions.SESSIONS` with motions between rests is
read and its poses found as ``accelcal discrepancy`` does (the shared front end), then the
gyro loop runs (:func:`accelcal.discrepancy.gyro_loop.gyro_layer`).  An effect named on
every session of a unit is a property of the sensor; one named on some sessions only is
not (a disturbed session, a misfit of that session's noise): :func:`repeats` says which.
"""

from __future__ import annotations

import pandas as pd

from accelcal.discrepancy.gyro_loop import gyro_layer
from accelcal.errors import AccelcalError
from accelcal.gyro.recording import MIN_RESTS
from accelcal.static_auto import find_static_poses

from .sessions import SESSIONS, local_paths, read_session

#: Sessions of one unit (the rest are single sessions of their unit).
UNITS = {"imutk_fork": ("fork_data1", "fork_data2", "fork_data3", "fork_data4"),
         "snu": ("snu_good1", "snu_good2", "snu_good3"), "xsens": ("xsens",)}


def session_rows(names=None, n_boot: int = 999) -> pd.DataFrame:
    """One row per session: effects named, excess before/after, motions, or why not tested."""
    names = list(names or [n for u in UNITS.values() for n in u])
    paths = local_paths(names)
    rows = []
    for n in names:
        spec = SESSIONS[n]
        rec = read_session(spec, paths)
        try:
            poses, _ = find_static_poses(rec, spec.g, {}, max(10, MIN_RESTS))
        except AccelcalError as e:
            rows.append({"session": n, "named": "", "reason": str(e).splitlines()[0][:160]})
            continue
        res, err = gyro_layer(rec, spec.g, poses, n_boot=n_boot)
        if res is None:
            rows.append({"session": n, "named": "", "reason": err})
            continue
        first = res.rounds[0]
        rows.append({"session": n, "n_motions": res.n_motions, "named": ",".join(res.named) or "none",
                     "excess_before": res.excess_before, "excess_after": res.excess_after,
                     "not_identifiable": ",".join(c for c, r in first.items() if r["status"] == "not_identifiable"),
                     **{f"p_{c}": r.get("p_adjusted") for c, r in first.items()}, "reason": ""})
    return pd.DataFrame(rows)


def repeats(rows: pd.DataFrame, units=UNITS) -> pd.DataFrame:
    """Per unit and effect named anywhere: on how many of its tested sessions, and whether on all."""
    out = []
    for unit, names in units.items():
        tested = rows[rows.session.isin(names) & (rows.reason == "")]
        effects = sorted({e for v in tested.named for e in v.split(",") if e and e != "none"})
        for e in effects:
            k = int(sum(e in v.split(",") for v in tested.named))
            out.append({"unit": unit, "effect": e, "sessions_named": k, "sessions_tested": len(tested),
                        "repeats": bool(len(tested) > 1 and k == len(tested))})
    return pd.DataFrame(out, columns=["unit", "effect", "sessions_named", "sessions_tested", "repeats"])


__all__ = ["UNITS", "repeats", "session_rows"]
