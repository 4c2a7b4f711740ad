"""The evidence on each candidate of a real session: what rules it out, or what it would need.

From the session's discrepancy report (the JSON of ``accelcal discrepancy``): per candidate
effect of round 1 its test, its minimum detectable effect against its estimate, the share
of the excess it could explain, and for a candidate the poses cannot test the poses it
needs; and the named noise term between the poses (a per-placement offset with what
repeated placements say).  ``results/discrepancy/sessions/evidence.csv`` and the figure
``discrepancy_evidence`` (:func:`.figures.plot_evidence`).
"""

from __future__ import annotations

import re

import numpy as np

from accelcal.discrepancy.fit import fit
from accelcal.discrepancy.wander_process import process_in
from accelcal.errors import AccelcalError

from .sessions import pose_data_of


def evidence_rows(name: str, report: dict) -> list[dict]:
    """Per candidate of round 1 what rules it out, or what it would need (``verdict``): its test
    (as the loop ran it), its minimum detectable effect (``mde_data``: the largest change of a
    pose mean at the size the test detects with the design power, data unit; ``mde_mg`` in
    mg for data in m/s²) against the estimate's size (``estimate_data``, and the upper end
    of its 95 % interval, ``estimate_high_data``: the same pose-mean scale, largest over the
    parameters), the estimate in standard errors, the share of the base model's excess χ²
    (``χ²₀ − dof₀``, white weights) that fitting it removes, ``(χ²₀ − χ²₁)/(χ²₀ − dof₀)``
    (what the effect could explain if it were real), and for a candidate the poses cannot
    test, the poses it needs (``poses_needed``).  A last row per session: the named noise
    term between the poses (its size, and what repeated placements say)."""
    data = pose_data_of(report)
    try:
        base = fit(data)
    except AccelcalError:
        return []
    rows = []
    for c in report.get("candidates", []):
        if c.get("round") != 1:
            continue
        rows.append({"recording": name, "item": "effect", **_candidate_evidence(c, data, base, report)})
    rows.append(_noise_evidence(name, report))
    return rows


def _to_mg(report: dict, v: float) -> float:
    return 1e3 * v / 9.80665 if report.get("unit") == "m/s^2" else float("nan")


def _candidate_evidence(c: dict, data, base, report: dict) -> dict:
    est, se = np.array(c["estimate"], float), np.array(c["se"], float)
    mde, mde_data = np.array(c["mde"], float), np.array(c["mde_data"], float)
    share = float("nan")
    if base.chi2 > base.dof and c["identifiable"]:
        try:
            share = (base.chi2 - fit(data, (c["effect"],), p0=base.p).chi2) / (base.chi2 - base.dof)
        except AccelcalError:
            pass
    with np.errstate(invalid="ignore", divide="ignore"):
        per_unit = np.where(mde > 0, mde_data / mde, np.nan)        # pose-mean change per unit parameter
        est_data = float(np.nanmax(np.abs(est) * per_unit)) if np.isfinite(est).any() else float("nan")
        high_data = float(np.nanmax((np.abs(est) + 1.96 * se) * per_unit)) if np.isfinite(est).any() else float("nan")
    reasons = "; ".join(c.get("reasons", []))
    worst = float(np.nanmax(mde_data)) if np.isfinite(mde_data).any() else float("nan")
    needed = _poses_needed(reasons)
    if c.get("named"):
        verdict = "named"
    elif not c["identifiable"]:
        verdict = "not testable here" + (f": needs at least {needed} poses" if needed else "") + f" ({reasons})"
    else:
        verdict = (f"not named (adjusted p {c.get('p_adjusted', float('nan')):.3g}): an effect moving the pose means "
                   f"by more than {worst:.3g} {report.get('unit') or 'data unit'} would have been detected with the "
                   "design power")
    return {"candidate": c["effect"], "identifiable": c["identifiable"], "reasons": reasons,
            "p_value": c.get("p_value"), "p_adjusted": c.get("p_adjusted"), "passed": c.get("passed"),
            "named": c.get("named"),
            "max_abs_z": float(np.nanmax(np.abs(est / se))) if np.all(se > 0) else float("nan"),
            "share_of_excess_chi2": share, "mde_data": worst, "mde_mg": _to_mg(report, worst),
            "estimate_data": est_data, "estimate_high_data": high_data, "estimate_high_mg": _to_mg(report, high_data),
            "poses_needed": needed, "n_poses": len(data), "verdict": verdict}


def _poses_needed(reasons: str) -> int | None:
    """The poses a refusal for want of degrees of freedom names (``at least N poses``), if any."""
    m = re.search(r"at least (\d+) poses", reasons)
    return int(m.group(1)) if m else None


def _num(v) -> float:
    return float("nan") if v is None else float(v)


def _noise_evidence(name: str, report: dict) -> dict:
    """The session's named noise term between the poses as an evidence row."""
    nm = report.get("noise_model") or {}
    size = process_in(nm).size(nm)
    lo, hi = (list(nm.get("size_ci") or []) + [None, None])[:2]
    return {"recording": name, "item": "noise", "candidate": nm.get("term", "not_estimated"),
            "identifiable": bool(nm.get("estimated")), "reasons": nm.get("reason", ""),
            "estimate_data": _num(size), "estimate_low_data": _num(lo), "estimate_high_data": _num(hi),
            "estimate_mg": _to_mg(report, _num(size)), "estimate_low_mg": _to_mg(report, _num(lo)),
            "estimate_high_mg": _to_mg(report, _num(hi)), "poses_needed": None, "n_poses": report.get("n_poses"),
            "verdict": nm.get("reading", ""),
            "pure_error_dof": (nm.get("placement") or {}).get("pure_error_dof")}


__all__ = ["evidence_rows"]
