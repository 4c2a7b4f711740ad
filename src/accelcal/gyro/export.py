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


def imutk_files(acc_M, acc_bias, gyro: GyroModel) -> dict[str, str]:
    """``{'acc': text, 'gyro': text}`` of IMU-TK's ``test_imu_acc.calib`` / ``test_imu_gyro.calib``."""
    if gyro.g_sensitivity is not None:
        raise InputShapeError("IMU-TK's gyro model has no g-sensitivity: refit without it to export to IMU-TK")
    A = np.linalg.inv(np.asarray(acc_M, float))
    Ka = np.diag(np.diag(A))
    g = gyro.to_imutk()
    return {"acc": imutk_calib_text(A / np.diag(A)[None, :], Ka, acc_bias),
            "gyro": imutk_calib_text(g["T"], g["K"], g["b"])}


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


__all__ = ["imucal_json", "imutk_calib_text", "imutk_files"]
