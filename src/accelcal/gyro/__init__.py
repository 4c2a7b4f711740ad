"""The gyroscope, calibrated from the same multi-position session as the accelerometer.

>>> from accelcal.gyro import calibrate_gyro, prepare_session, GyroModel
>>> gcal = calibrate_gyro(rec.t, gyro, poses, acc_calibration, raw_unit="rad/s")
>>> print(gcal.summary())                      # both ± and the trust lines
>>> gcal.model.correct(gyro)                   # angular rate [rad/s], accelerometer frame
>>> session = prepare_session(rec.t, gyro, poses, acc_calibration)   # the rests and motions, once
>>> with_noise, rest_noise_only = session.fit(noise_model=True), session.fit(noise_model=False)

Modules: :mod:`~accelcal.gyro.model` (``ω = C (y - b - G f)`` and the peers'
parametrisations; their files: :mod:`accelcal.export`), :mod:`~accelcal.gyro.integrate`
(five integrators, the exact Jacobian),
:mod:`~accelcal.gyro.fit` (the iterative and the one-step estimate, the Cramér–Rao bound),
:mod:`~accelcal.gyro.rests` (bias, noise, time base, saturation),
:mod:`~accelcal.gyro.calibrate` (the whole session: prepared once, fitted per noise model;
typed errors: :mod:`~accelcal.gyro.errors`), :mod:`~accelcal.gyro.assess` (a fit judged:
quality, trust lines, the per-motion table), :mod:`~accelcal.gyro.result` (``to_dict``/``from_dict``,
``summary()``), :mod:`~accelcal.gyro.ferraris` (rotations of known angle),
:mod:`~accelcal.gyro.rotations` (rotations of known angle found in the gyro alone, each run
its bias: ``calibrate_rotations(rec.t, rec.gyro, angles_deg=..., runs=rec.runs)``),
:mod:`~accelcal.gyro.recording` (a recording's gyro after its accelerometer, as the CLI),
:mod:`~accelcal.gyro.simulate` (sessions with an exactly known rotation).  The static
detection settings for sessions with short still phases: :mod:`accelcal.static_auto`.
"""

from __future__ import annotations

from .calibrate import PreparedSession, calibrate_gyro, evaluate_model, prepare_session
from .ferraris import FerrarisFit, calibrate_ferraris_session, fit_ferraris
from .fit import MotionSet, crlb, fit_iterative, fit_one_step
from .integrate import integrate_intervals, integrate_sequential
from .model import GyroModel, frame_rotation
from .recording import calibrate_recording_gyro
from .result import GyroCalibration, GyroQuality
from .rotations import calibrate_rotations, find_rotations

__all__ = ["FerrarisFit", "GyroCalibration", "GyroModel", "GyroQuality", "MotionSet", "PreparedSession",
           "calibrate_ferraris_session", "calibrate_gyro", "calibrate_recording_gyro", "calibrate_rotations", "crlb",
           "evaluate_model", "find_rotations", "fit_ferraris", "fit_iterative", "fit_one_step", "frame_rotation",
           "integrate_intervals", "integrate_sequential", "prepare_session"]
