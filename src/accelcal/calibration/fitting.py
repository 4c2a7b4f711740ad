"""Calibrating: the registry's estimators on the static poses of a recording, with the
quality of the fit, its standard errors and its provenance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import (AccelcalError, DegeneratePosesError, NotConvergedError, NotPositiveDefiniteError,
                      RecordingError, TooFewPosesError)
from ..one_orientation import check_several_orientations
from ..quality import assess, distinct_orientations
from ..registry import estimator, estimators
from ..static_auto import find_static_poses
from .base import Calibration


def pose_noise_std(mean_std) -> float:
    """One noise level for the pose means: the RMS of their per-axis standard errors.

    What ALS is given: its correction removes ``Σ_i σ_i²`` from the moment matrix, which
    this RMS reproduces exactly for the terms linear in ``σ²`` (the mean of the variances).
    """
    return float(np.sqrt(np.mean(np.square(mean_std))))


def calibrate_poses(poses, g: float, method: str = "full_lls", *, unit: str | None, conversion=None,
                    provenance: dict | None = None) -> Calibration:
    """Fit ``method`` to static poses and assess the fit.

    Parameters
    ----------
    poses : StaticPoses
        From :func:`accelcal.static.detect_static` or known intervals.
    g : float
        Local gravity [m/s²].
    method : str
        Registry name (``full_lls`` or ``full-lls``, ...).
    unit : {'m/s^2', 'counts'} or None
        Unit of the pose means.
    conversion : NominalConversion, optional
        Nominal counts → m/s² conversion applied before the fit (how a bias-only model,
        which fixes ``M = I``, can be fitted to raw counts).
    provenance : dict, optional
        Extra keys for the JSON.

    Noise.  ALS is given the noise level of the pose means measured at the rests
    (:func:`pose_noise_std`), not the one it could estimate from the poses: the rests
    measure it independently, from thousands of samples, whereas the poses would mix
    the noise with any misfit of the model (the Xsens residuals are 2.5x the noise) and
    give a noisy value from a few dozen points.
    """

    est = estimator(method)
    z = np.asarray(poses.means, float)
    se = np.asarray(poses.mean_std, float)
    offset, sens, fit_unit, input_unit = np.zeros(3), np.ones(3), unit, unit
    if conversion is not None:
        offset = np.asarray(conversion.offset, float)
        sens = np.asarray(conversion.counts_per_unit, float)
        z, se, fit_unit = (z - offset) / sens, se / sens, "m/s^2"
    if est.model == "bias" and fit_unit == "counts":
        raise AccelcalError(f"{est.cli_name} fixes M = I, so the data must be in m/s^2 (or g); these are raw counts: "
                            "use a full model (full-lls), or pass the unit (--unit) if they are not counts")
    if len(z) < est.min_poses:
        raise TooFewPosesError(f"{len(z)} static poses found, {est.cli_name} needs at least {est.min_poses}")
    noise = pose_noise_std(se) if est.needs_noise else None
    try:
        r = est.fit(z, g, noise_std=noise)
    except (DegeneratePosesError, NotPositiveDefiniteError, NotConvergedError) as e:
        raise _orientation_cause(e, z, est) from None
    quality, se_noise = assess(z, se, r.M, r.bias, r.residuals, est.n_parameters, est.model, est.min_poses)
    cls = est.load_calibration()
    # the class's own fields, declared once there, taken from the estimator's result
    extra = {k: getattr(r, k) for k in cls._method_field_names() if hasattr(r, k)}
    if "noise_source" in cls._method_field_names():
        extra["noise_source"] = "rests: RMS of the pose-mean standard errors"
    return cls(
        bias=r.bias, M=r.M, g=float(g), unit=fit_unit, input_offset=offset, input_sensitivity=sens,
        input_unit=input_unit,
        standard_errors=dict(r.standard_errors), standard_errors_noise=se_noise, quality=quality,
        residuals=np.asarray(r.residuals), poses=_pose_table(poses, z, se), provenance=dict(provenance or {}),
        **extra)


def _pose_table(poses, z, se) -> dict:
    """The calibration's table of its poses: times, means and their standard errors (in the
    fit's unit), samples, temperature, and the known intervals' labels when there are."""
    table = {"t_start": poses.t_start, "t_end": poses.t_end, "mean": z, "mean_std": se,
             "n_samples": poses.n_samples, "temp": poses.temp}
    labels = getattr(poses, "labels", None)
    if labels is not None:
        table["labels"] = list(labels)
    return table


def _raw_directions(z) -> np.ndarray:
    """Pose directions before any fit: about the centre of the best sphere through the poses
    (the bias-only LLS, which needs no g), so that raw counts with a large offset work too."""
    z = np.asarray(z, float)
    try:
        centre = estimator("bias_lls").fit(z, 1.0).bias
    except AccelcalError:
        centre = z.mean(axis=0)
    d = z - centre
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _orientation_cause(err: AccelcalError, z, est) -> AccelcalError:
    """A failed fit on poses that repeat too few orientations says so (the likely cause)."""

    k = distinct_orientations(_raw_directions(z))
    if k >= est.min_poses:
        return err
    return DegeneratePosesError(f"{len(z)} poses but only {k} distinct orientations (10 deg apart): {est.cli_name} "
                                f"needs at least {est.min_poses}; turn the sensor to new orientations between rests"
                                f"{_bias_only_hint(est, k)} [{err}]")


def _bias_only_hint(est, k: int) -> str:
    """The bias-only fallback, offered only to a method that is not bias-only already and where it would fit."""
    need = min(e.min_poses for e in estimators("accelerometer") if e.model == "bias")
    if est.model == "bias" or k < need:
        return ""
    return f" (or use a bias-only method, >= {need})"


def calibrate_recording(rec, g: float, method: str = "full_lls", *, static: dict | None = None,
                        conversion=None, provenance: dict | None = None, search: bool = False,
                        min_poses: int = 0) -> tuple[Calibration, object]:
    """Static poses of ``rec`` (its known intervals, or detected), then :func:`calibrate_poses`.

    Parameters
    ----------
    rec : Recording
    g : float
        Local gravity [m/s²].
    method : str
    static : dict, optional
        Keyword arguments of :func:`accelcal.static.detect_static` (``window``,
        ``threshold_factor``, ``min_duration``, ``trim``, ``init_duration``,
        ``noise_reference``).
    conversion, provenance
        As for :func:`calibrate_poses`.
    search : bool
        When the detection with ``static`` finds fewer poses than the method needs (or
        ``min_poses``, if more), try the candidate settings of
        :func:`accelcal.static_auto.choose_static` (IMU-TK's threshold multipliers 2-10,
        and shorter windows for still phases of about a second) and keep the most precise
        fit; the choice is in ``provenance['static']['search']`` (its ``description``
        says it in a line).  Not for known intervals.
    min_poses : int
        Fewest poses wanted beyond the method's own minimum (a gyro calibration needs
        six rests) before the search starts.

    Returns
    -------
    calibration : Calibration
    poses : StaticPoses
        The poses it was fitted to.

    Raises
    ------
    RecordingError
        No static poses (the message says what was tried).
    TooFewPosesError, DegeneratePosesError
        Not enough poses or orientations for the method (the message names the count and
        what to do).
    OneOrientationError
        The sensor keeps one orientation for the whole record (a static record), found
        from its 1 s means before the detection (:mod:`accelcal.one_orientation`).
    """
    if not (np.isfinite(g) and 9.7 <= g <= 9.9):
        raise AccelcalError(f"g = {g:g}: the local gravity magnitude in m/s^2 (9.78-9.83 on the Earth's surface; "
                            "data in g are converted, pass --unit g)")
    if rec.acc is None:
        raise RecordingError(f"{rec.source}: no accelerometer in this recording (a gyro alone): calibrate its gyro from "
                             "rotations of known angle (accelcal.gyro.rotations.calibrate_rotations)")
    est = estimator(method)
    if rec.intervals is None:  # a static record: said at once, before detection walks it (one_orientation)
        check_several_orientations(rec, est.min_poses, est.cli_name)
    poses, searched = find_static_poses(rec, g, static, max(est.min_poses, min_poses) if search else 0)
    prov = dict(provenance or {})
    prov.setdefault("static", {})
    prov["static"].update({"reference": poses.reference, "note": poses.reference_note,
                           "known_intervals": rec.intervals is not None, **(static or {})})
    if searched is not None:
        prov["static"].update(searched["settings"])
        prov["static"]["search"] = searched
    prov.setdefault("notes", list(rec.notes))
    labels = rec.labels if rec.intervals is not None else None
    try:
        cal = calibrate_poses(_Poses(poses, labels), g, method, unit=rec.unit, conversion=conversion, provenance=prov)
    except TooFewPosesError as e:
        raise TooFewPosesError(f"{e}; {_too_few_hint(rec, poses, est)}") from None
    return cal, poses


@dataclass(frozen=True)
class _Poses:
    """StaticPoses with the labels of known intervals (for the pose table)."""

    base: object
    labels: tuple | None

    def __getattr__(self, name):
        return getattr(self.base, name)


def _too_few_hint(rec, poses, est) -> str:
    k = distinct_orientations(_raw_directions(poses.means)) if len(poses) >= 4 else len(poses)
    rate = rec.rate
    if not 1.0 <= rate <= 20000.0:
        return (f"the sampling rate is {rate:.4g} Hz from the time column: if its unit is not seconds, pass "
                "--time-unit (ms, us, ns)")
    if rec.intervals is not None:
        return f"the file gives {len(rec.intervals)} known static intervals; record more poses"
    fallback = _bias_only_hint(est, k).replace(" (or", ", or").rstrip(")")
    return (f"{k} distinct orientations; record more rests in new orientations (at least {est.min_poses}) or "
            f"loosen the detection (--threshold, --window, --min-duration){fallback}")
