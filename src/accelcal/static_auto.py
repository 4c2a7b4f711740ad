"""Choosing the static-detection settings from the data (no hand-tuning).

IMU-TK tries the threshold multipliers 2, 3, ..., 10 and keeps the one whose
accelerometer fit has the lowest final cost.  A sum of squared residuals falls with
every pose left out, so that rule prefers fewer, cleaner poses and cannot compare
settings that find different numbers of poses.  Here the candidates (threshold
multipliers 2-10, and shorter windows and minimum durations for sessions whose still
phases last about a second) are compared by what the calibration is for, the precision of
its parameters:

    D = log det( cov_noise · max(1, excess)² )

the log-determinant of the covariance of the full model's nine parameters implied by the
pose noise measured at the rests (:func:`accelcal.quality.assess`), inflated by the
excess of the residuals over that noise.  More poses shrink it; poses that are not at rest
(a threshold so high that motion passes as rest) inflate the excess and grow it.  The
log-determinant does not depend on the units of the parameters.  A candidate needs at
least ``min_poses`` poses in that many distinct orientations.

A low threshold splits a rest wherever the noise briefly crosses it; the pieces are one
orientation measured several times, and counting them as poses would dilute the excess
(the model's misfit is per orientation, the pieces' noise is independent).  So
consecutive poses whose gravity directions differ by less than ``MERGE_DEG`` (a tap, not a
new placement; hand placements differ by tens of degrees) are merged into one pose
before scoring (:func:`merge_split_rests`), and the merged poses are what is returned.

:func:`choose_static` returns the settings, the poses and the whole table of candidates,
so that the choice can be printed ("threshold x6, window 0.5 s: 35 poses").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import AccelcalError, RecordingError
from .evaluation import residual_sigma
from .lls import bias_lls
from .quality import assess, distinct_orientations
from .registry import estimator
from .static import StaticPoses, detect_static, detect_static_recording
from .uncertainty import residual_jacobian

#: Threshold multipliers tried (IMU-TK's 2-10).
THRESHOLDS = (2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0)
#: (window [s], min_duration [s], trim [s]) tried with every threshold: the defaults of
#: accelcal.static, then settings for still phases of about one second.
SHAPES = ((1.0, 1.0, 0.25), (0.5, 0.5, 0.1), (0.3, 0.3, 0.05))
#: Consecutive poses closer than this [deg] are one rest split by noise.
MERGE_DEG = 1.0


@dataclass(frozen=True)
class StaticChoice:
    """The chosen detection settings and how every candidate fared."""

    settings: dict  #: keyword arguments of accelcal.static.detect_static
    poses: object  #: StaticPoses found with them
    criterion: float  #: log det of the inflated parameter covariance
    table: list  #: one dict per candidate: settings, n_poses, distinct, excess, criterion, note

    def describe(self) -> str:
        s = self.settings
        return (f"static detection chosen from {len(self.table)} candidates: threshold x{s['threshold_factor']:g}, "
                f"window {s['window']:g} s, min duration {s['min_duration']:g} s, trim {s['trim']:g} s: "
                f"{len(self.poses)} poses")


def _score(t, acc, g, unit, kw, min_poses):
    # the registry's full LLS and the quality assessment directly, not accelcal.calibration
    # (which calls this module when the default detection finds too few poses)

    poses = detect_static(t, acc, **kw)
    if len(poses) >= 4:
        poses = merge_split_rests(poses)
    if len(poses) < min_poses:
        return poses, math.inf, float("nan"), 0, f"{len(poses)} poses"
    e = estimator("full_lls")
    z = np.asarray(poses.means, float)
    cal = e.fit(z, g)
    q, _ = assess(z, np.asarray(poses.mean_std, float), cal.M, cal.bias, cal.residuals, e.n_parameters, e.model,
                  e.min_poses)
    distinct = distinct_orientations(_directions(cal, poses))
    if distinct < min_poses:
        return poses, math.inf, q.excess, distinct, f"{distinct} distinct orientations"
    cov = _noise_covariance(poses, cal) * max(1.0, q.excess if math.isfinite(q.excess) else 1.0) ** 2
    sign, logdet = np.linalg.slogdet(cov)
    return poses, (logdet if sign > 0 else math.inf), q.excess, distinct, ""


def merge_split_rests(poses, max_deg: float = MERGE_DEG):
    """Merge runs of consecutive poses whose gravity directions differ by less
    than ``max_deg``: one rest split by noise crossing the threshold.  A merged pose spans
    from the first piece's start to the last piece's end; its mean and standard error
    combine the pieces' (weighted by their samples, and inversely by their variances)."""

    z = np.asarray(poses.means, float)
    d = z - bias_lls(z, 1.0).bias  # about the centre of the best sphere: unit-free, no calibration needed
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    close = np.rad2deg(np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=1), -1, 1))) < max_deg
    if not np.any(close):
        return poses
    group = np.concatenate([[0], np.cumsum(~close)])
    n = poses.n_samples.astype(float)
    out = {k: [] for k in ("means", "t_start", "t_end", "n_samples", "noise_std", "mean_std", "temp", "intervals")}
    for gi in range(group[-1] + 1):
        idx = np.flatnonzero(group == gi)
        w = n[idx][:, None]
        out["means"].append(np.sum(poses.means[idx] * w, axis=0) / w.sum())
        out["mean_std"].append(1.0 / np.sqrt(np.sum(1.0 / poses.mean_std[idx] ** 2, axis=0)))
        out["noise_std"].append(np.sqrt(np.sum(poses.noise_std[idx] ** 2 * w, axis=0) / w.sum()))
        out["t_start"].append(poses.t_start[idx[0]])
        out["t_end"].append(poses.t_end[idx[-1]])
        out["n_samples"].append(int(n[idx].sum()))
        out["intervals"].append([poses.intervals[idx[0], 0], poses.intervals[idx[-1], 1]])
        if poses.temp is not None:
            out["temp"].append(float(np.sum(poses.temp[idx] * n[idx]) / n[idx].sum()))
    arr = {k: np.asarray(v) for k, v in out.items()}
    return StaticPoses(means=arr["means"], t_start=arr["t_start"], t_end=arr["t_end"],
                       t_mid=0.5 * (arr["t_start"] + arr["t_end"]), n_samples=arr["n_samples"].astype(int),
                       noise_std=arr["noise_std"], mean_std=arr["mean_std"],
                       temp=arr["temp"] if poses.temp is not None else None, intervals=arr["intervals"].astype(int),
                       init_rest=poses.init_rest, reference=poses.reference, reference_note=poses.reference_note)


def _directions(cal, poses):
    x = np.linalg.solve(cal.M, (np.asarray(poses.means, float) - cal.bias).T).T
    return x / np.linalg.norm(x, axis=1, keepdims=True)


def _noise_covariance(poses, cal) -> np.ndarray:
    """Covariance of (b, s, θ) from the pose noise: (Jᵀ W J)⁻¹, as accelcal.evaluation does."""

    z = np.asarray(poses.means, float)
    J = residual_jacobian(z, cal.M, cal.bias, "full")
    sig = residual_sigma(z, poses.mean_std, cal.M, cal.bias)
    Jw = J / sig[:, None]
    return np.linalg.inv(Jw.T @ Jw)


def choose_static(t, acc, g: float, *, unit: str | None = None, min_poses: int = 12, thresholds=THRESHOLDS,
                  shapes=SHAPES, init_duration: float | None = None) -> StaticChoice:
    """Detection settings whose accelerometer fit is most precise (module docstring).

    Parameters
    ----------
    t, acc
        The recording (accelerometer in ``unit``).
    g : float
        Local gravity [m/s²].
    unit : {'m/s^2', 'counts'} or None
    min_poses : int
        Fewest poses (and distinct orientations) a candidate must give (IMU-TK's
        ``min_num_intervals``, 12).
    thresholds, shapes
        The candidates (:data:`THRESHOLDS` × :data:`SHAPES`).

    Raises
    ------
    RecordingError
        No candidate gives ``min_poses`` poses in distinct orientations.
    """
    table, best = [], None
    for window, min_dur, trim in shapes:
        for k in thresholds:
            kw = {"threshold_factor": float(k), "window": window, "min_duration": min_dur, "trim": trim}
            if init_duration is not None:
                kw["init_duration"] = init_duration
            try:
                poses, crit, excess, distinct, note = _score(t, acc, g, unit, kw, min_poses)
            except AccelcalError as e:
                table.append({**kw, "n_poses": 0, "distinct": 0, "excess": float("nan"), "criterion": math.inf,
                              "note": str(e)[:120]})
                continue
            table.append({**kw, "n_poses": len(poses), "distinct": distinct, "excess": excess, "criterion": crit,
                          "note": note})
            if crit < math.inf and (best is None or crit < best[0]):
                best = (crit, kw, poses)
    if best is None:
        most = max(table, key=lambda r: r["n_poses"])
        raise RecordingError(f"no detection setting finds {min_poses} static poses in distinct orientations (at most "
                             f"{most['n_poses']}, threshold x{most['threshold_factor']:g}, "
                             f"window {most['window']:g} s): "
                             "record more poses, or hold each still for longer")
    return StaticChoice(best[1], best[2], best[0], table)


def find_static_poses(rec, g: float, static: dict | None = None, need: int = 0):
    """The front end of ``accelcal calibrate`` and ``accelcal discrepancy``: one code path.

    The poses of ``rec`` with the settings ``static`` (its known intervals when it carries
    them); if they are fewer than ``need`` (0: never search), the candidates' best
    (:func:`choose_static`).  Both commands call this, so that they fit the same poses.

    Returns
    -------
    poses : StaticPoses
    searched : dict or None
        The search's record (``settings``, ``description``, ``defaults_found``,
        ``defaults_note``, ``candidates``), None when the settings ``static`` were kept.

    Raises
    ------
    AccelcalError
        No static pose (the defaults' own reason when the search finds nothing either).
    """

    static = dict(static or {})
    failed = None
    try:
        poses = detect_static_recording(rec, **static)
        found, why = len(poses), ""
    except AccelcalError as e:
        if not need or rec.intervals is not None:
            raise
        poses, found, why, failed = None, 0, str(e), e
    if not need or rec.intervals is not None or found >= need:
        return poses, None
    try:
        choice = choose_static(rec.t, rec.acc, g, unit=rec.unit, min_poses=need,
                               init_duration=static.get("init_duration"))
    except AccelcalError:
        if failed is not None:  # the defaults' own reason says more than "no setting finds enough"
            raise failed from None
        return poses, None
    return choice.poses, {"settings": dict(choice.settings), "description": choice.describe(),
                          "defaults_found": found, "defaults_note": why[:200], "candidates": len(choice.table)}


__all__ = ["MERGE_DEG", "SHAPES", "THRESHOLDS", "StaticChoice", "choose_static", "find_static_poses",
           "merge_split_rests"]
