"""Whether a calibration is plausible enough to hand to an estimator or an autopilot, and
whether its fit can be trusted (``--strict``).

Autopilot users have shipped calibrations with a scale of 0.02 or offsets beyond 1 m/s²
because nothing refused them.  An export refuses, in one line, a calibration with

* a scale outside 1 ± :data:`MAX_SCALE_ERROR` (a unit mistake, or a fit on too few poses:
  ArduPilot itself keeps ``INS_ACCSCAL`` within 0.8-1.2);
* an offset beyond the sensor's range (``acc_range_g``, default :data:`ACC_RANGE_G`;
  ``gyro_range_dps``, default :data:`GYRO_RANGE_DPS`: the largest full scales of MEMS parts);
* a matrix whose symmetric part is not positive definite (an axis flipped or swapped:
  the sensor frame is not the one the calibration assumes).
"""

from __future__ import annotations

import numpy as np

from ..units import ANGULAR_RATE_UNITS, G0
from .base import ExportError

MAX_SCALE_ERROR = 0.20
ACC_RANGE_G = 16.0
GYRO_RANGE_DPS = 2000.0


def check_plausible(cal, *, acc_range_g: float = ACC_RANGE_G, gyro_range_dps: float = GYRO_RANGE_DPS) -> None:
    """Raise a one-line :class:`ExportError` for an implausible calibration (module docstring)."""
    physical = cal.unit == "m/s^2" or np.any(cal.input_sensitivity != 1) or np.any(cal.input_offset != 0)
    _positive_definite(cal.M, "the accelerometer's M")
    if physical:
        _scales(np.linalg.norm(cal.M, axis=1), "accelerometer")
    if cal.unit == "m/s^2" and not (np.any(cal.input_sensitivity != 1) or np.any(cal.input_offset != 0)):
        _offsets(cal.bias / G0, acc_range_g, "accelerometer", "g", "m/s^2", G0, "--acc-range")
    if cal.gyro is None:
        return
    m = cal.gyro.model
    k = ANGULAR_RATE_UNITS[m.raw_unit]
    _positive_definite(m.C, "the gyroscope's C")
    if k is not None:
        _scales(1.0 + cal.gyro.scale_factors, "gyroscope")
        _offsets(np.degrees(m.bias * k), gyro_range_dps, "gyroscope", "deg/s", "deg/s", 1.0, "--gyro-range")


def _scales(gain, sensor: str) -> None:
    bad = [f"{ax} {s:.4g}" for ax, s in zip("xyz", gain) if not abs(s - 1.0) <= MAX_SCALE_ERROR]
    if bad:
        raise ExportError(f"implausible calibration: the {sensor}'s scale is {', '.join(bad)} (outside 1 +- "
                          f"{MAX_SCALE_ERROR:.0%}); check the data's unit (--unit, --gyro-unit) and recalibrate")


def _offsets(values, limit: float, sensor: str, unit: str, shown: str, factor: float, flag: str) -> None:
    bad = [f"{ax} {v * factor:.4g} {shown}" for ax, v in zip("xyz", values) if not abs(v) <= limit]
    if bad:
        raise ExportError(f"implausible calibration: the {sensor}'s offset is {', '.join(bad)}, beyond the sensor's "
                          f"range of {limit:g} {unit} ({flag} sets it); check the data's unit and recalibrate")


def _positive_definite(A, name: str) -> None:
    A = np.asarray(A, float)
    if not np.all(np.linalg.eigvalsh(A + A.T) > 0):
        raise ExportError(f"implausible calibration: {name} is not positive definite (an axis flipped or swapped): "
                          "check the axes of the data and recalibrate")


def trust_problems(cal) -> list[str]:
    """Why the calibration's fit cannot be trusted (its quality's warnings and its gyroscope's); [] if it can."""
    out = []
    q = getattr(cal, "quality", None)
    if q is not None and not q.trustworthy:
        out += [f"accelerometer: {w}" for w in q.warnings]
    gq = None if cal.gyro is None else getattr(cal.gyro, "quality", None)
    if gq is not None and not gq.trustworthy:
        out += [f"gyroscope: {w}" for w in gq.warnings]
    return out


__all__ = ["ACC_RANGE_G", "GYRO_RANGE_DPS", "MAX_SCALE_ERROR", "check_plausible", "trust_problems"]
