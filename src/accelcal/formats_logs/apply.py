"""A calibration applied to the IMU topic of a log, written as a table.

:func:`apply_to_log` reads a ROS bag, MCAP file, ULog or DataFlash log with the readers of
this package, applies an accelcal calibration to its accelerometer
(:meth:`accelcal.calibration.Calibration.apply`, in the unit the log holds: m/s²) and
writes a CSV: the time column as the log recorded it (``header_stamp_ns``,
``timestamp_sample_us``, ...), the calibrated ``ax, ay, az`` [m/s²], the gyroscope
``gx, gy, gz`` [rad/s] as recorded (accelcal does not calibrate the gyroscope yet) and
``temp`` [°C] where the log has it.  Written atomically: the file is whole or absent.

A calibration's ``bias_drift`` effect describes the drift during its own session and
is not applied to a log (as ``accelcal apply`` does for other recordings).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..atomic import atomic_output


def apply_to_log(log_path, calibration, out_path, *, effects: bool = True, **read_kw) -> dict:
    """Calibrate the accelerometer of a log and write the table; returns a summary.

    Parameters
    ----------
    log_path : path-like
        The log (any format of :data:`accelcal.formats_logs.LOG_FORMATS`).
    calibration : path-like or Calibration
        An accelcal calibration JSON (``accelcal calibrate``, or a discrepancy report).
    out_path : path-like
        The CSV to write.
    effects : bool
        Apply the calibration's fitted effects (default) or its base model only.
    **read_kw
        ``topic``, ``time_source``, ``instance``, ``format``, ``progress`` for the reader.

    Returns
    -------
    dict
        ``n`` samples, ``columns``, ``effects`` applied, ``warnings``, ``notes`` of the reader.
    """
    from ..calibration import Calibration, load_calibration
    from . import read_log

    cal = calibration if isinstance(calibration, Calibration) else load_calibration(calibration)
    rec = read_log(log_path, **read_kw)
    warnings = []
    terms = cal.effects if effects else ()
    if any(e.id == "bias_drift" for e in terms):
        warnings.append("the calibration's bias_drift term describes the drift during its own session; it is not "
                        "applied to a log")
        terms = tuple(e for e in terms if e.id != "bias_drift")
    cal = replace(cal, effects=terms)
    acc = cal.apply(rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit)
    name, values = rec.time_column if rec.time_column is not None else ("t", rec.t)
    data = {name: np.asarray(values), "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2]}
    if rec.gyro is not None:
        data.update({"gx": rec.gyro[:, 0], "gy": rec.gyro[:, 1], "gz": rec.gyro[:, 2]})
    if rec.temp is not None:
        data["temp"] = rec.temp
    _write_csv(Path(out_path), data)
    return {"n": int(rec.n), "columns": list(data), "effects": [e.id for e in terms], "warnings": warnings,
            "notes": list(rec.notes)}


def _write_csv(path: Path, data: dict) -> None:
    import pandas as pd

    with atomic_output(path) as tmp, open(tmp, "w", newline="") as f:
        # float64 written with the shortest repr that round-trips (pandas' default)
        pd.DataFrame(data).to_csv(f, index=False)


__all__ = ["apply_to_log"]
