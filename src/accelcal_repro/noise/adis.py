"""The ADIS16405 record's noise terms against the datasheet's typical values.

Analog Devices' ADIS16405 datasheet (typical values, not limits)
states for the accelerometer a velocity random walk of 0.2 m/s/√h and an in-run bias
stability of 0.2 mg (1σ), for the gyroscope an angle random walk of 2 °/√h and an in-run
bias stability of 0.007 °/s (1σ).  The record (SMAC-Group ``imudata``, 2.78 h at
100 Hz, one orientation) is analysed by :func:`accelcal.noise.analyse_noise`; the
datasheet's figures are read from it as:

* a random walk (velocity, angle) is the white-noise density ``N`` of the IEEE fit
  (``RW [unit/√h] = 60 N [unit/√s]``, the Allan deviation at τ = 1 s of the white term);
* the in-run bias stability is the minimum of the measured Allan deviation, how Analog
  Devices characterises it, with its chi-square interval (model edf); the flicker floor
  of the fit, ``0.664 B`` (IEEE Std 952), is shown beside it.

Each row holds the fitted value, its interval at the report's level, the datasheet value
and their ratio; :data:`PRIMARY` marks the readings the stage's claims judge.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from accelcal.units import G0

#: (sensor, quantity, datasheet value in SI units, unit, datasheet as written, reading).
DATASHEET = (
    ("accelerometer", "velocity random walk", 0.2 / 60.0, "m/s^2/sqrt(Hz)", "0.2 m/s/sqrt(h)", "white N"),
    ("accelerometer", "in-run bias stability", 0.2e-3 * G0, "m/s^2", "0.2 mg", "ADEV minimum"),
    ("accelerometer", "in-run bias stability", 0.2e-3 * G0, "m/s^2", "0.2 mg", "flicker floor 0.664 B"),
    ("gyroscope", "angle random walk", math.radians(2.0 / 60.0), "rad/s/sqrt(Hz)", "2 deg/sqrt(h)", "white N"),
    ("gyroscope", "in-run bias stability", math.radians(0.007), "rad/s", "0.007 deg/s", "ADEV minimum"),
    ("gyroscope", "in-run bias stability", math.radians(0.007), "rad/s", "0.007 deg/s", "flicker floor 0.664 B"),
)
#: The reading of each quantity that the claims judge (the other is shown for comparison).
PRIMARY = {"velocity random walk": "white N", "angle random walk": "white N", "in-run bias stability": "ADEV minimum"}
#: The IEEE Std 952 flicker floor of the Allan deviation per unit of the bias instability B.
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
COLUMNS = ("sensor", "quantity", "reading", "primary", "axis", "fitted", "interval_low", "interval_high", "level",
           "tau_s", "datasheet", "datasheet_as_written", "unit", "ratio")


def datasheet_table(report) -> pd.DataFrame:
    """The fitted terms against :data:`DATASHEET`, one row per quantity, reading and axis (:data:`COLUMNS`).

    ``report`` is the :class:`~accelcal.noise.NoiseReport` of the record (both sensors in SI
    units); ``tau_s`` is where the ADEV minimum lies (NaN for the other readings).
    """
    rows = []
    for sensor, quantity, value, unit, written, reading in DATASHEET:
        s = report.sensors[sensor]
        if s.unit != ("m/s^2" if sensor == "accelerometer" else "rad/s"):
            raise ValueError(f"the {sensor} is in {s.unit}, the datasheet comparison needs SI units")
        for j, axis in enumerate("xyz"):
            fitted, lo, hi, tau = _reading(s, j, reading)
            rows.append({"sensor": sensor, "quantity": quantity, "reading": reading,
                         "primary": PRIMARY[quantity] == reading, "axis": axis, "fitted": fitted,
                         "interval_low": lo, "interval_high": hi, "level": report.level, "tau_s": tau,
                         "datasheet": value,
                         "datasheet_as_written": written, "unit": unit, "ratio": fitted / value})
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _reading(s, j: int, reading: str) -> tuple[float, float, float, float]:
    """(value, interval low, interval high, τ) of one reading of axis ``j`` of a sensor's noise."""
    if reading == "white N":
        t = s.terms[j]["white"]
        return t.value, t.lo, t.hi, float("nan")
    if reading == "ADEV minimum":
        i = int(np.argmin(s.allan.adev[:, j]))
        lo, hi = s.adev_interval[i, j]
        return float(s.allan.adev[i, j]), float(lo), float(hi), float(s.allan.taus[i])
    b = s.terms[j]["bias_instability"]
    return FLICKER_FLOOR * b.value, FLICKER_FLOOR * b.lo, FLICKER_FLOOR * b.hi, float("nan")


def figure_references(table: pd.DataFrame) -> dict:
    """The datasheet's values as the figure draws them: ``{sensor: {"white": N, "floor": ADEV}}``."""
    out = {}
    for r in table.drop_duplicates(["sensor", "quantity"]).itertuples():
        out.setdefault(r.sensor, {})["floor" if r.quantity == "in-run bias stability" else "white"] = r.datasheet
    return out


__all__ = ["COLUMNS", "DATASHEET", "FLICKER_FLOOR", "PRIMARY", "datasheet_table", "figure_references"]
