"""The gyroscope, calibrated from the same multi-position session as the accelerometer.

>>> from accelcal.gyro import calibrate_gyro, GyroModel
>>> gcal = calibrate_gyro(rec.t, gyro, poses, acc_calibration, raw_unit="rad/s")
>>> print(gcal.summary())                      # both ± and the trust lines
>>> gcal.model.correct(gyro)                   # angular rate [rad/s], accelerometer frame

Modules: :mod:`~accelcal.gyro.model` (``ω = C (y - b - G f)`` and the peers'
parametrisations; their files: :mod:`accelcal.export`), :mod:`~accelcal.gyro.integrate`
(five integrators, the exact Jacobian),
:mod:`~accelcal.gyro.fit` (the iterative and the one-step estimate, the Cramér–Rao bound),
:mod:`~accelcal.gyro.rests` (bias, noise, time base, saturation),
:mod:`~accelcal.gyro.calibrate` (the whole session, its trust lines and typed errors,
:mod:`~accelcal.gyro.errors`), :mod:`~accelcal.gyro.result` (``to_dict``/``from_dict``,
``summary()``), :mod:`~accelcal.gyro.ferraris` (rotations of known angle),
:mod:`~accelcal.gyro.rotations` (rotations of known angle found in the gyro alone, each run
its bias: ``calibrate_rotations(rec.t, rec.gyro, angles_deg=..., runs=rec.runs)``),
:mod:`~accelcal.gyro.recording` (a recording's gyro after its accelerometer, as the CLI),
:mod:`~accelcal.gyro.simulate` (sessions with an exactly known rotation).  The static
detection settings for sessions with short still phases: :mod:`accelcal.static_auto`.
"""

from __future__ import annotations

import importlib

_LAZY = {
    "GyroModel": "model", "frame_rotation": "model",
    "calibrate_gyro": "calibrate", "evaluate_model": "calibrate",
    "GyroCalibration": "result", "GyroQuality": "result",
    "fit_iterative": "fit", "fit_one_step": "fit", "crlb": "fit", "MotionSet": "fit",
    "fit_ferraris": "ferraris", "FerrarisFit": "ferraris", "calibrate_ferraris_session": "ferraris",
    "integrate_intervals": "integrate", "integrate_sequential": "integrate",
    "calibrate_recording_gyro": "recording",
    "calibrate_rotations": "rotations", "find_rotations": "rotations",
}


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = sorted(_LAZY)
