"""IMU-TK's ``.calib`` files (``CalibratedTriad_::save``, ethz-asl/imu_tk ``src/calibration.cpp``).

One file per triad: the misalignment ``T`` (3x3), a blank line, the scale ``K`` (3x3,
diagonal), a blank line, the bias ``b``; IMU-TK corrects ``x = T K (raw - b)``
(``CalibratedTriad_::unbiasNormalize``, ``calibration.h``).

* The accelerometer: ``T K = M⁻¹`` (accelcal's lower-triangular frame: IMU-TK loads any
  ``T``), ``b``, in the raw unit the calibration is applied to (a nominal conversion of
  raw counts folded in).
* The gyroscope: ``T K = C``, ``b`` (:meth:`accelcal.gyro.model.GyroModel.to_imutk`).
  IMU-TK's gyro model has no g-sensitivity: a fitted ``G`` is left out, and the summary
  says what that costs (refused only with ``--exact``).
"""

from __future__ import annotations

import numpy as np

from .base import Export, LeftOut, effects_left_out, g_sensitivity_cost_dps


def _rows(a) -> str:
    a = np.atleast_2d(np.asarray(a, float))
    return "\n".join(" ".join(f"{v:.12g}" for v in row) for row in a)


def imutk_calib_text(T, K, b) -> str:
    """One ``.calib`` file: ``T``, blank, ``K``, blank, ``b`` (one value per line)."""
    return f"{_rows(T)}\n\n{_rows(K)}\n\n{_rows(np.asarray(b, float).reshape(3, 1))}\n"


def imutk_files(acc_M, acc_bias, gyro=None) -> dict[str, str]:
    """``{'acc': text, 'gyro': text}`` (the accelerometer's alone when ``gyro`` is None); a
    gyro's g-sensitivity is not written (IMU-TK has none)."""
    A = np.linalg.inv(np.asarray(acc_M, float))
    out = {"acc": imutk_calib_text(A / np.diag(A)[None, :], np.diag(np.diag(A)), acc_bias)}
    if gyro is not None:
        g = gyro.to_imutk()
        out["gyro"] = imutk_calib_text(g["T"], g["K"], g["b"])
    return out


def raw_accelerometer(cal) -> tuple[np.ndarray, np.ndarray]:
    """``(M, b)`` of ``raw = M x + b`` in the raw unit the calibration is applied to: its
    input conversion ``z = (raw - offset) / sensitivity`` folded in."""
    sens, off = np.asarray(cal.input_sensitivity, float), np.asarray(cal.input_offset, float)
    return sens[:, None] * np.asarray(cal.M, float), sens * np.asarray(cal.bias, float) + off


def write(inputs) -> Export:
    cal = inputs.calibration
    M, b = raw_accelerometer(cal)
    model = None if cal.gyro is None else cal.gyro.model
    texts = imutk_files(M, b, model)
    left = effects_left_out(cal, "IMU-TK")
    if model is not None and model.g_sensitivity is not None and np.any(model.g_sensitivity != 0):
        # raw unit per m/s², C in rad/s per raw unit: the rate error C G f
        left.insert(0, LeftOut("the gyroscope's g-sensitivity G (IMU-TK's gyro model has none)",
                               f"up to {g_sensitivity_cost_dps(model.C @ model.g_sensitivity):.3g} deg/s at the worst "
                               "orientation"))
    notes = [f"IMU-TK corrects x = T K (raw - b); the accelerometer's raw unit is {cal.input_unit or cal.unit}"]
    if model is None:
        notes.append("no gyroscope in the calibration: only the accelerometer's file is written")
    return Export({f"_{k}.calib": v for k, v in texts.items()}, left, notes)


__all__ = ["imutk_calib_text", "imutk_files", "raw_accelerometer", "write"]
