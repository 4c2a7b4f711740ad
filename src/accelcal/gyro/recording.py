"""The gyro of a :class:`~accelcal.recording.Recording`, calibrated after its accelerometer:
what ``accelcal calibrate`` does, for Python.

>>> from accelcal import read, calibrate_recording
>>> from accelcal.gyro.recording import calibrate_recording_gyro
>>> rec = read("acc_data.txt", gyro="gyro_data.txt")
>>> cal, poses = calibrate_recording(rec, 9.81, "full_lls", search=True, min_poses=6)
>>> cal = dataclasses.replace(cal, gyro=calibrate_recording_gyro(rec, cal, poses))

The data decide the protocol, and the choice is said: a recording that marks rotations of
known angle (:attr:`Recording.rotations`, imucal's ``*_rot`` sections) is a Ferraris session
(:func:`accelcal.gyro.ferraris.calibrate_ferraris_session`, the ``gyro_ferraris`` entry of the
registry's rotation estimators); one whose rotation angles are given but not marked has them
found in the gyro, each run with its own bias (:func:`accelcal.gyro.rotations.calibrate_rotations`);
any other is a multi-position session, calibrated from the motions between the accelerometer's
rests (:func:`accelcal.gyro.calibrate.calibrate_gyro`, a motion estimator).  An estimator asked
for that does not fit the session's data is refused in one line, never replaced; the
calibration's ``settings["estimator_chosen_by"]`` says who chose.
"""

from __future__ import annotations

import dataclasses

from ..registry import estimator, estimators, min_gyro_rests
from .calibrate import calibrate_gyro
from .errors import GyroInputError
from .ferraris import calibrate_ferraris_session
from .rotations import calibrate_rotations

#: Rests a calibration from motions needs: one more than the fewest motions of the registry's estimators.
MIN_RESTS = min_gyro_rests()


def calibrate_recording_gyro(rec, acc_cal, poses, *, estimator: str | None = None, nominal_sensitivity=None,
                             gyro_range=None, g_sensitivity="auto", rotation_angles=None, angle_std_deg: float = 0.0,
                             noise_model: bool = True):
    """The gyro of ``rec`` (module docstring).

    Parameters
    ----------
    rec : Recording
        With ``gyro`` (rad/s or counts: ``gyro_unit``; None: the unit is decided by the
        session's motions, :mod:`accelcal.gyro.unit_evidence`, or refused in one line).
    acc_cal : Calibration
        The accelerometer's calibration of ``rec`` (its frame is the gyro's).
    poses : StaticPoses
        The rests it was fitted to.
    estimator : str, optional
        A registered gyro estimator of the session's data; default: by the data
        (``gyro_ferraris`` for marked rotations, else ``gyro_iterative``).
    nominal_sensitivity : float, optional
        Raw counts per rad/s.
    gyro_range : (lo, hi), optional
        The measuring range in the raw unit.
    g_sensitivity : bool or 'auto'
    rotation_angles : float or sequence, optional
        Ferraris sessions: the angle of each rotation [deg] (default 360).  Given for a
        recording without marked rotations: the rotations of known angle are found in the
        gyro (:func:`accelcal.gyro.rotations.calibrate_rotations`) instead of the motions
        between rests.
    angle_std_deg : float
        Uncertainty of each stated angle [deg].
    noise_model : bool
        Multi-position sessions: the noise model between the rests (:mod:`accelcal.gyro.noise`).

    Returns
    -------
    GyroCalibration
        Of the class of the estimator used (``gyro_ferraris`` for a Ferraris session).
    """
    if rec.gyro is None:
        raise GyroInputError(f"{rec.source}: no gyro samples (gyro columns, or a file of its own: --gyro FILE)")
    unit = rec.gyro_unit  # None: not stated; the session's motions or rotations decide it (unit_evidence)
    entry, chosen_by = _estimator_for(rec, estimator, rotation_angles is not None)
    cal = _calibrate(rec, acc_cal, poses, entry.name, unit, nominal_sensitivity, gyro_range, g_sensitivity,
                     rotation_angles, angle_std_deg, noise_model)
    return dataclasses.replace(cal, settings={**cal.settings, "estimator_chosen_by": chosen_by})


def _estimator_for(rec, name: str | None, angles_given: bool):
    """The registry entry that calibrates ``rec``'s gyro and who chose it; one line if ``name`` cannot."""
    data = "rotations" if rec.rotations or angles_given else "motions"
    if name is None:
        entry = estimators("gyroscope", data=data)[0]
        why = ("the data: rotations of known angle are marked" if rec.rotations else
               "the data: rotations of stated angle (--rotation-angle)" if angles_given else
               "the data: motions between rests")
        return entry, why
    entry = estimator(name)
    if entry.sensor != "gyroscope":
        raise GyroInputError(f"{entry.cli_name} is not a gyro estimator; gyro estimators: "
                             f"{', '.join(e.cli_name for e in estimators('gyroscope'))}")
    if entry.data != data:
        fits = ", ".join(e.cli_name for e in estimators("gyroscope", data=data))
        marked = ("marks rotations of known angle (a Ferraris session)" if rec.rotations else
                  "has rotations of stated angle (--rotation-angle)" if angles_given else
                  "marks no rotations of known angle (imucal's *_rot sections: --intervals SECTION_LIST, or "
                  "--rotation-angle)")
        raise GyroInputError(f"{rec.source} {marked}: {entry.cli_name} fits {entry.data}; its estimators: {fits} "
                             "(or leave --gyro-method out to let the data choose)")
    return entry, "--gyro-method"


def _calibrate(rec, acc_cal, poses, estimator, unit, nominal_sensitivity, gyro_range, g_sensitivity, rotation_angles,
               angle_std_deg, noise_model):
    if rec.rotations:
        labels = rec.labels or ()
        intervals = [] if rec.intervals is None else [tuple(int(i) for i in iv) for iv in rec.intervals]
        sections = {**dict(zip(labels, intervals)), **rec.rotations}
        # measured rotation axes need the full model's directions; a bias-only model leaves its scale errors in them
        accel = {"accel": acc_cal, "acc": rec.acc} if acc_cal.model == "full" else {}
        return calibrate_ferraris_session(rec.t, rec.gyro, sections, raw_unit=unit,
                                          angles_deg=360.0 if rotation_angles is None else rotation_angles,
                                          nominal_sensitivity=nominal_sensitivity, angle_std_deg=angle_std_deg, **accel)
    if rotation_angles is not None:  # rotations of known angle, not marked: found in the gyro, each run its bias

        accel = {"accel": acc_cal, "acc": rec.acc} if acc_cal is not None and acc_cal.model == "full" else {}
        return calibrate_rotations(rec.t, rec.gyro, angles_deg=rotation_angles, runs=rec.runs, raw_unit=unit,
                                   nominal_sensitivity=nominal_sensitivity, angle_std_deg=angle_std_deg,
                                   source=str(rec.source), **accel)

    return calibrate_gyro(rec.t, rec.gyro, poses, acc_cal, raw_unit=unit, acc=rec.acc,
                          nominal_sensitivity=nominal_sensitivity, estimator=estimator, gyro_range=gyro_range,
                          g_sensitivity=g_sensitivity, noise_model=noise_model)


__all__ = ["MIN_RESTS", "calibrate_recording_gyro"]
