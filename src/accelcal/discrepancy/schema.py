"""The status keys of the discrepancy report (``accelcal discrepancy``'s JSON), each value with its meaning.

:data:`STATUS` is the one place a status value is defined; :data:`REPORT_SCHEMA` is the
same as a JSON Schema (draft 2020-12) of the report's status keys (the rest of the
report is numbers, lists and the candidates' rows, described in the command's help and
the modules that write them); :func:`statuses` reads them out of a report and
:func:`check_statuses` refuses a value the table does not define (the tests run it on
every report they build).  The README lists the same values.

Two readings of the residual excess.  ``excess_status_white`` compares the residuals with
the rests' white noise alone, before (base model) and after the named effects:
``explained`` there means the named *effects* bring the residuals down to the noise the
rests show.  ``excess_status`` compares them with the model the loop used: under the
wander null the named effects (and outlier poses) *with* the named noise terms (a white
scale, a bias wander or a per-placement offset, estimated jointly): ``explained`` there
means that model predicts the scatter it leaves, and ``excess_explained_by`` says what
carries it.  Under the white null the two keys agree.
"""

from __future__ import annotations

import math

from ..effects import EFFECT_IDS
from ..errors import AccelcalError
from .rules import null_name
from .wander_process import MEANINGS

_EXCESS = {
    "no excess": "the base model's residuals are consistent with the rests' white pose noise at level alpha: "
                 "nothing to explain",
    "explained": "the residuals exceed the rests' noise, and the model of this reading predicts the scatter "
                 "that remains (chi-square inside the central 1 - alpha of its distribution)",
    "not explained": "the residuals exceed the rests' noise, and the model of this reading does not predict "
                     "the scatter that remains",
    "untestable": "no residual degree of freedom, or (wander null) the noise model could not be estimated",
}

#: Every status key of the report (a dotted path into the JSON) and its values, with their meaning.
STATUS: dict[str, dict[str, str]] = {
    "outcome": {
        **{e: f"the effect {e} was named first" for e in EFFECT_IDS},
        "outlier_pose": "an outlier pose was named first",
        "none": "nothing named, and every applicable candidate was tested",
        "not_identifiable": "nothing named, and a candidate could not be tested with these poses (or against "
                            "the wander, or told apart from another): the recording cannot rule it out",
        "error": "the loop failed (a model did not converge); the errors key says why",
    },
    "gyroscope.outcome": {
        "effect": "the gyro loop named an effect beyond the gyro model (gyroscope.named)",
        "none": "nothing named for the gyro, and every applicable candidate was tested",
        "not_identifiable": "nothing named for the gyro, and a candidate could not be tested with these motions "
                            "(its row's needs says which motions it would need)",
        "not_tested": "the gyro loop did not run: no gyro, or the gyro could not be calibrated from these rests "
                      "(gyroscope.reason, one line); the accelerometer's loop ran",
    },
    "magnetometer.outcome": {
        "effect": "the magnetometer loop named an effect beyond the hard iron (magnetometer.named: soft_iron, "
                  "disturbance, temperature)",
        "none": "nothing named for the magnetometer, and every applicable candidate was tested",
        "not_identifiable": "nothing named for the magnetometer, and a candidate could not be tested (no "
                            "temperature column, too few orientations: its row's needs says what)",
        "not_tested": "the magnetometer loop did not run: no magnetometer, or columns no fit can use "
                      "(magnetometer.reason, one line); the accelerometer's loop ran",
    },
    "null": {"wander": "white pose noise times a scale plus a bias wander or per-placement offset, estimated "
                        "jointly; bootstrap likelihood-ratio tests",
             "white": "white pose noise times a common scale; F-tests (the negative control)"},
    "excess_status": {k: v + " (this reading: the named effects and the named noise terms)" for k, v in
                      _EXCESS.items()},
    "excess_status_white": {k: v + " (this reading: the named effects against the rests' white noise alone)"
                            for k, v in _EXCESS.items()},
    "noise_model.term": {
        "bias_wander": "a slowly wandering bias shared by neighbouring poses (Gauss-Markov, random walk or flicker)",
        "per_placement_offset": "an offset constant within each pose and independent between poses (placement by "
                                "hand, a mount that settles differently each time)",
        "none": "the pose-to-pose noise beyond the rests' is estimated at zero",
        "not_estimated": "too few poses (or a degenerate design) to estimate it; reason says why",
    },
    "noise_model.process": MEANINGS,
    "noise_implication.verdict": {
        "consistent": "the final residuals' chi-square lies in the central 1 - alpha of what the named noise "
                      "model predicts",
        "residuals exceed it": "the residuals scatter more than the named noise model predicts",
        "it over-predicts": "the residuals scatter less than the named noise model predicts",
        "no degrees of freedom": "no residual degree of freedom to compare",
    },
    "noise_implication.allan_check.verdict": {
        "consistent": "the rests' Allan deviation agrees with white noise plus the wander where both see it",
        "rests show less": "the rests' Allan deviation is below what the wander implies: the rests contradict it",
        "not visible in the rests": "the wander (or a per-placement offset, constant within each rest) is not "
                                    "visible at the averaging times the rests reach",
        "no wander named": "no bias wander to check",
        "no rests analysed": "the stochastic layer did not run",
    },
}

#: :data:`STATUS` as a JSON Schema of the report's status keys.
REPORT_SCHEMA: dict = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "accelcal discrepancy report: status keys",
    "type": "object",
    "properties": {
        "outcome": {"enum": list(STATUS["outcome"]), "description": "; ".join(f"{k}: {v}" for k, v in
                                                                             STATUS["outcome"].items())},
        **{k: {"enum": list(STATUS[k]), "description": "; ".join(f"{v}: {d}" for v, d in STATUS[k].items())}
           for k in ("null", "excess_status", "excess_status_white")},
        "excess_explained_by": {"type": "array", "items": {"type": "string"},
                                "description": "what carries the excess when excess_status is explained: named "
                                               "effects, outlier poses, the noise term, a white scale above 1"},
        "gyroscope": {"type": "object", "properties": {
            "outcome": {"enum": list(STATUS["gyroscope.outcome"])},
            "named": {"type": "array", "items": {"type": "string"}},
            "reason": {"type": "string"}}},
        "magnetometer": {"type": "object", "properties": {
            "outcome": {"enum": list(STATUS["magnetometer.outcome"])},
            "named": {"type": "array", "items": {"type": "string"}},
            "reason": {"type": "string"}}},
        "noise_model": {"type": "object", "properties": {
            "term": {"enum": list(STATUS["noise_model.term"])},
            "process": {"enum": list(STATUS["noise_model.process"])},
            "reading": {"type": "string", "description": "the noise term in words, with what its numbers mean"}}},
        "noise_implication": {"type": "object", "properties": {
            "verdict": {"enum": list(STATUS["noise_implication.verdict"])},
            "allan_check": {"type": "object", "properties": {"verdict": {"type": "string", "description": (
                "one of " + ", ".join(STATUS["noise_implication.allan_check.verdict"]) + ", or per axis "
                "'x: ...; y: ...' when the axes differ")}}}}},
    },
    "required": ["outcome", "excess_status", "excess_status_white"],
}


def _get(report: dict, path: str):
    v = report
    for k in path.split("."):
        if not isinstance(v, dict) or k not in v:
            return None
        v = v[k]
    return v


#: Top-level keys of earlier reports and their current names (the time-correlated noise model
#: was the ``colored`` null; it is the wander null now).
OLD_REPORT_KEYS = {"gap_colored_before": "gap_wander_before", "gap_colored_after": "gap_wander_after"}


def upgraded_report(report: dict) -> dict:
    """``report`` (a copy) with the keys and null names of earlier versions read as the current
    ones (:data:`OLD_REPORT_KEYS`, :data:`~accelcal.discrepancy.rules.OLD_NULL_NAMES`)."""
    out = {OLD_REPORT_KEYS.get(k, k): v for k, v in report.items()}
    if isinstance(out.get("null"), str):
        out["null"] = null_name(out["null"])
    if isinstance(out.get("rules"), dict) and isinstance(out["rules"].get("null"), str):
        out["rules"] = {**out["rules"], "null": null_name(out["rules"]["null"])}
    return out


def statuses(report: dict) -> dict[str, str]:
    """The status values a report holds, by :data:`STATUS` key (missing keys left out; a
    per-axis Allan verdict split into its axes' values; a report of an earlier version read
    through :func:`upgraded_report`)."""
    report = upgraded_report(report)
    out = {}
    for key in STATUS:
        v = _get(report, key)
        if v is None:
            continue
        if key == "noise_implication.allan_check.verdict" and ": " in v:
            for part in v.split("; "):
                axis, value = part.split(": ", 1)
                out[f"{key}[{axis}]"] = value
        else:
            out[key] = v
    return out


def check_statuses(report: dict) -> dict[str, str]:
    """:func:`statuses`, each checked against :data:`STATUS`.

    Raises
    ------
    AccelcalError
        A value the table does not define (a status written without its meaning).
    """
    out = statuses(report)
    for key, value in out.items():
        known = STATUS[key.split("[")[0]]
        if value not in known:
            raise AccelcalError(f"report status {key} = {value!r} is not defined in "
                                f"accelcal.discrepancy.schema.STATUS ({', '.join(known)})")
    return out


def white_excess_status(p_before: float, p_after: float, alpha: float) -> str:
    """The excess against the rests' white noise from the χ² tail probabilities of the base
    model's and the final model's residuals: ``no excess`` (the base fits at level α),
    ``explained`` (the final does), ``not explained``, ``untestable`` (no degree of freedom)."""
    if not (math.isfinite(p_before) and math.isfinite(p_after)):
        return "untestable"
    if p_before >= alpha:
        return "no excess"
    return "explained" if p_after >= alpha else "not explained"


__all__ = ["OLD_REPORT_KEYS", "REPORT_SCHEMA", "STATUS", "check_statuses", "statuses", "upgraded_report",
           "white_excess_status"]
