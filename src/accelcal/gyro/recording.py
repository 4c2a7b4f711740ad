"""The gyro of a :class:`~accelcal.recording.Recording`, calibrated after its accelerometer:
what ``accelcal calibrate`` does, for Python.

>>> from accelcal import read, calibrate_recording
>>> from accelcal.gyro.recording import calibrate_recording_gyro
>>> rec = read("acc_data.txt", gyro="gyro_data.txt")
>>> cal, poses = calibrate_recording(rec, 9.81, "full_lls", search=True, min_poses=6)
>>> cal = dataclasses.replace(cal, gyro=calibrate_recording_gyro(rec, cal, poses))

The data decide the protocol, not a name: a recording that marks rotations of known angle
(:attr:`Recording.rotations`, imucal's ``*_rot`` sections) is a Ferraris session
(:func:`accelcal.gyro.ferraris.calibrate_ferraris_session`); any other is a multi-position
session, calibrated from the motions between the accelerometer's rests
(:func:`accelcal.gyro.calibrate.calibrate_gyro`).
"""

from __future__ import annotations

from ..registry import estimators
from .errors import GyroInputError, RotationAngleError

#: Rests a calibration from motions needs: one more than the fewest motions of the registry's estimators.
MIN_RESTS = 1 + max(e.min_poses for e in estimators("gyroscope", data="motions"))


def calibrate_recording_gyro(rec, acc_cal, poses, *, estimator: str = "gyro_iterative", nominal_sensitivity=None,
                             gyro_range=None, g_sensitivity="auto", rotation_angles=None, noise_model: bool = True):
    """The gyro of ``rec`` (module docstring).

    Parameters
    ----------
    rec : Recording
        With ``gyro`` (rad/s or counts: ``gyro_unit``).
    acc_cal : Calibration
        The accelerometer's calibration of ``rec`` (its frame is the gyro's).
    poses : StaticPoses
        The rests it was fitted to.
    estimator : str
        A registered gyro estimator of motions (``gyro_iterative``, ``gyro_one_step``).
    nominal_sensitivity : float, optional
        Raw counts per rad/s.
    gyro_range : (lo, hi), optional
        The measuring range in the raw unit.
    g_sensitivity : bool or 'auto'
    rotation_angles : float or sequence of 3, optional
        Ferraris sessions: the angle of each rotation [deg] (default 360).
    noise_model : bool
        Multi-position sessions: the noise model between the rests (:mod:`accelcal.gyro.noise`).

    Returns
    -------
    GyroCalibration
        Of the class of the estimator used (``gyro_ferraris`` for a Ferraris session).
    """
    if rec.gyro is None:
        raise GyroInputError(f"{rec.source}: no gyro samples (gyro columns, or a file of its own: --gyro FILE)")
    unit = rec.gyro_unit or "rad/s"
    if rec.rotations:
        from .ferraris import calibrate_ferraris_session

        labels = rec.labels or ()
        intervals = [] if rec.intervals is None else [tuple(int(i) for i in iv) for iv in rec.intervals]
        sections = {**dict(zip(labels, intervals)), **rec.rotations}
        # measured rotation axes need the full model's directions; a bias-only model leaves its scale errors in them
        accel = {"accel": acc_cal, "acc": rec.acc} if acc_cal.model == "full" else {}
        return calibrate_ferraris_session(rec.t, rec.gyro, sections, raw_unit=unit,
                                          angles_deg=360.0 if rotation_angles is None else rotation_angles,
                                          nominal_sensitivity=nominal_sensitivity, **accel)
    if rotation_angles is not None:
        raise RotationAngleError("--rotation-angle applies to a Ferraris session, whose rotations are marked "
                                 "(imucal's *_rot sections: --intervals SECTION_LIST, or an annotated session); "
                                 f"{rec.source} has none")
    from .calibrate import calibrate_gyro

    return calibrate_gyro(rec.t, rec.gyro, poses, acc_cal, raw_unit=unit, acc=rec.acc,
                          nominal_sensitivity=nominal_sensitivity, estimator=estimator, gyro_range=gyro_range,
                          g_sensitivity=g_sensitivity, noise_model=noise_model)


__all__ = ["MIN_RESTS", "calibrate_recording_gyro"]
