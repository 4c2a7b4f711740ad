"""Nominal conversions of the public recordings' raw values to m/s² (data sheets, peers)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import RecordingError


@dataclass(frozen=True)
class NominalConversion:
    """Nominal conversion of a format's raw values to m/s²: ``(raw - offset) / counts_per_unit``.

    Attributes
    ----------
    offset : ndarray, shape (3,)
        Raw value of zero specific force (nominal bias), file units.
    counts_per_unit : ndarray, shape (3,)
        File units per m/s² (1 if the file is already in m/s²).
    g_local : float or None
        Local gravity [m/s²] the data's authors used, if documented.
    note : str
        Where the numbers come from.
    """

    offset: np.ndarray
    counts_per_unit: np.ndarray
    g_local: float | None
    note: str

    def to_si(self, acc) -> np.ndarray:
        """Apply the nominal conversion to raw values ``acc`` (..., 3)."""
        return (np.asarray(acc, dtype=float) - self.offset) / self.counts_per_unit


_G0 = 9.80665  # standard gravity: "counts per g" datasheet figures refer to it
_NOMINAL = {
    "imutk_xsens": ((32768.0,) * 3, (415.0, 413.0, 415.0), 9.81744,
                    "IMU-TK example: bias 32768, g = 9.81744; sensitivities from imu_tk_matlab calibrate.m"),
    "mpu6050": ((0.0,) * 3, (16384.0 / _G0,) * 3, None,
                "MPU-6050 datasheet, ±2 g range: 16384 counts per g"),
    "imucal_session": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s²"),
    "imutk_fork": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s² (ROS IMU topic)"),
    "fxos8700": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s² (Adafruit sensor driver)"),
}


def nominal_conversion(kind: str) -> NominalConversion | None:
    """Nominal raw → m/s² conversion of a public format, or None where none is documented.

    Parameters
    ----------
    kind : {'imutk_xsens', 'mpu6050', 'imucal_session', 'imutk_fork', 'fxos8700', 'imucal_annotated'}
        The format.  ``'imucal_annotated'`` (raw counts of an unnamed sensor) returns None.
    """
    if kind == "imucal_annotated":
        return None
    if kind not in _NOMINAL:
        raise RecordingError(f"unknown recording format {kind!r}; known: {', '.join([*_NOMINAL, 'imucal_annotated'])}")
    offset, cpu, g, note = _NOMINAL[kind]
    return NominalConversion(np.array(offset), np.array(cpu), g, note)
