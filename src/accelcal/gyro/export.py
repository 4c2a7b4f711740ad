"""Accelerometer and gyro calibrations written in the peers' own layouts, so users can move between tools.

* :func:`imutk_calib_text` — IMU-TK's ``.calib`` file (``CalibratedTriad_::save``): the
  misalignment ``T`` (3x3), a blank line, the scale ``K`` (3x3, diagonal), a blank line,
  the bias ``b``; model ``x = T K (raw - b)``.  :func:`imutk_files` gives both triads:
  the accelerometer's ``T K = M⁻¹`` (accelcal's frame, lower triangular: IMU-TK loads any
  ``T``), the gyro's ``T K = C``.  IMU-TK has no g-sensitivity: a model with one is
  refused.
* :func:`imucal_json` — imucal's ``FerrarisCalibrationInfo`` JSON (``cal_type: Ferraris``):
  ``K_a`` (row norms of ``M``), ``R_a = K_a⁻¹ M``, ``b_a``, and the gyro's ``K_g``,
  ``R_g``, ``b_g``, ``K_ga`` for imucal's deg/s output.  ``K_ga`` multiplies imucal's
  *calibrated* acceleration, i.e. it is ``G``.

:func:`calibration_imutk` and :func:`calibration_imucal` do it for a whole calibration
(:class:`accelcal.calibration.Calibration` with its ``gyro``): the accelerometer in the
raw unit it is applied to (a nominal conversion of raw counts folded in), without its
fitted effects (neither peer models them: :func:`unexported_effects` names them).
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import InputShapeError
from .model import GyroModel


#: imucal's calibration JSON format version (``CalibrationInfo.CAL_FORMAT_VERSION`` of imucal 2.x).
IMUCAL_FORMAT_VERSION = "2.0.0"


def _rows(a) -> str:
    a = np.atleast_2d(np.asarray(a, float))
    return "\n".join(" ".join(f"{v:.12g}" for v in row) for row in a)


def imutk_calib_text(T, K, b) -> str:
    """One ``.calib`` file: ``T``, blank, ``K``, blank, ``b`` (one value per line)."""
    return f"{_rows(T)}\n\n{_rows(K)}\n\n{_rows(np.asarray(b, float).reshape(3, 1))}\n"


def imutk_files(acc_M, acc_bias, gyro: GyroModel | None) -> dict[str, str]:
    """``{'acc': text, 'gyro': text}`` of IMU-TK's ``test_imu_acc.calib`` / ``test_imu_gyro.calib``
    (the accelerometer's alone when ``gyro`` is None)."""
    if gyro is not None and gyro.g_sensitivity is not None:
        raise InputShapeError("IMU-TK's gyro model has no g-sensitivity, which this gyro calibration fitted: refit "
                              "without it to export to IMU-TK (accelcal calibrate --gyro-g-sensitivity off)")
    A = np.linalg.inv(np.asarray(acc_M, float))
    Ka = np.diag(np.diag(A))
    out = {"acc": imutk_calib_text(A / np.diag(A)[None, :], Ka, acc_bias)}
    if gyro is not None:
        g = gyro.to_imutk()
        out["gyro"] = imutk_calib_text(g["T"], g["K"], g["b"])
    return out


def imucal_json(acc_M, acc_bias, gyro: GyroModel, *, acc_raw_unit: str = "m/s^2", comment: str | None = None) -> str:
    """imucal's JSON of a ``FerrarisCalibrationInfo`` (``FerrarisCalibrationInfo.from_json`` reads it)."""
    M = np.asarray(acc_M, float)
    k = np.linalg.norm(M, axis=1)
    g = gyro.to_imucal("deg/s")
    d = {"cal_type": "Ferraris", "_format_version": IMUCAL_FORMAT_VERSION, "acc_unit": "m/s^2", "gyr_unit": "deg/s",
         "from_acc_unit": acc_raw_unit,
         "from_gyr_unit": gyro.raw_unit, "comment": comment,
         "K_a": np.diag(k).tolist(), "R_a": (M / k[:, None]).tolist(), "b_a": np.asarray(acc_bias, float).tolist(),
         "K_g": g["K_g"].tolist(), "R_g": g["R_g"].tolist(), "K_ga": g["K_ga"].tolist(), "b_g": g["b_g"].tolist()}
    return json.dumps(d, indent=1)


def raw_accelerometer(cal) -> tuple[np.ndarray, np.ndarray]:
    """``(M, b)`` of ``raw = M x + b`` in the raw unit the calibration is applied to: its
    input conversion ``z = (raw - offset) / sensitivity`` folded in."""
    sens, off = np.asarray(cal.input_sensitivity, float), np.asarray(cal.input_offset, float)
    return sens[:, None] * np.asarray(cal.M, float), sens * np.asarray(cal.bias, float) + off


def unexported_effects(cal) -> tuple[str, ...]:
    """The fitted effects of ``cal`` that neither peer's model holds (left out of an export)."""
    return tuple(e.id for e in cal.effects)


def calibration_imutk(cal) -> dict[str, str]:
    """IMU-TK's two ``.calib`` texts of a calibration (``'gyro'`` only when it has a gyroscope)."""
    M, b = raw_accelerometer(cal)
    return imutk_files(M, b, None if cal.gyro is None else cal.gyro.model)


def calibration_imucal(cal, comment: str | None = None) -> str:
    """imucal's ``FerrarisCalibrationInfo`` JSON of a calibration with a gyroscope."""
    if cal.gyro is None:
        raise InputShapeError("imucal's calibration holds an accelerometer and a gyroscope; this calibration has no "
                              "gyroscope (calibrate a recording with gyro columns, or export to IMU-TK)")
    M, b = raw_accelerometer(cal)
    return imucal_json(M, b, cal.gyro.model, acc_raw_unit=cal.input_unit or cal.unit or "m/s^2", comment=comment)


__all__ = ["calibration_imucal", "calibration_imutk", "imucal_json", "imutk_calib_text", "imutk_files",
           "raw_accelerometer", "unexported_effects"]
