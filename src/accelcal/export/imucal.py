"""imucal's calibration JSON (``FerrarisCalibrationInfo``, mad-lab-fau/imucal
``imucal/ferraris_calibration_info.py``), which ``CalibrationInfo.from_json`` reads.

imucal's sensor model ``y_a = K_a R_a a + b_a``, ``y_g = K_g R_g ω + K_ga a + b_g``
(``calibrate``: ``a = (K_a R_a)⁻¹ (y_a - b_a)``, ``ω = (K_g R_g)⁻¹ (y_g - K_ga a - b_g)``):
``K_a`` the row norms of ``M``, ``R_a = K_a⁻¹ M``, ``b_a``; the gyro's ``K_g``, ``R_g``,
``b_g`` for imucal's deg/s output and ``K_ga = G`` (it multiplies imucal's *calibrated*
acceleration).  Both sensors: a calibration without a gyroscope is refused.
"""

from __future__ import annotations

import json

import numpy as np

from .base import Export, effects_left_out
from .imutk import raw_accelerometer

#: imucal's calibration JSON format version (``CalibrationInfo.CAL_FORMAT_VERSION`` of imucal 2.x).
IMUCAL_FORMAT_VERSION = "2.0.0"


def imucal_json(acc_M, acc_bias, gyro, *, acc_raw_unit: str = "m/s^2", comment: str | None = None) -> str:
    """imucal's JSON of a ``FerrarisCalibrationInfo``."""
    M = np.asarray(acc_M, float)
    k = np.linalg.norm(M, axis=1)
    g = gyro.to_imucal("deg/s")
    d = {"cal_type": "Ferraris", "_format_version": IMUCAL_FORMAT_VERSION, "acc_unit": "m/s^2", "gyr_unit": "deg/s",
         "from_acc_unit": acc_raw_unit, "from_gyr_unit": gyro.raw_unit, "comment": comment,
         "K_a": np.diag(k).tolist(), "R_a": (M / k[:, None]).tolist(), "b_a": np.asarray(acc_bias, float).tolist(),
         "K_g": g["K_g"].tolist(), "R_g": g["R_g"].tolist(), "K_ga": g["K_ga"].tolist(), "b_g": g["b_g"].tolist()}
    return json.dumps(d, indent=1)


def write(inputs) -> Export:
    cal = inputs.calibration
    M, b = raw_accelerometer(cal)
    source = inputs.option("source")
    text = imucal_json(M, b, cal.gyro.model, acc_raw_unit=cal.input_unit or cal.unit or "m/s^2",
                       comment=f"exported by accelcal from {source}" if source else "exported by accelcal")
    return Export({"": text + "\n"}, effects_left_out(cal, "imucal"), ["imucal's calibrate() outputs m/s^2 and deg/s"])


__all__ = ["IMUCAL_FORMAT_VERSION", "imucal_json", "write"]
