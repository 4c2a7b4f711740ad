"""PX4's raw magnetometer, ``sensor_mag``, beside the IMU of a ULog (:func:`accelcal.formats.px4.read`).

What the topic is (PX4-Autopilot ``msg/SensorMag.msg``): ``timestamp`` (publication, µs
since boot), ``timestamp_sample``, ``device_id``, ``is_external``, ``x, y, z`` — "[Gauss]
magnetic field in the FRD board frame" — ``temperature``, ``error_count``.  It is the
driver's output (``PX4Magnetometer``: the chip's axes turned to the board's by the driver's
fixed rotation) *before* the autopilot's calibration: ``calibration::Magnetometer::Correct``
(``src/lib/sensor_calibration/Magnetometer.hpp``) computes ``_rotation * (_scale * ((data +
_power * _power_compensation) - _offset))`` from ``CAL_MAGn_*OFF``, ``*SCALE``, ``*ODIAG``,
``CAL_MAGn_ROT`` afterwards.  So ``sensor_mag`` is what a calibration starts from; an
external compass's ``CAL_MAGn_ROT`` is not in it (the alignment to the accelerometer
estimates that rotation).  Read in gauss and converted to µT (x 100).

Not read as raw: ``sensor_mag`` of PX4 before 1.10 (it has ``x_raw``: the driver applied
``CAL_MAGn`` offsets and scales to ``x, y, z`` itself, as to ``sensor_accel`` then),
``vehicle_magnetometer`` (``magnetometer_ga``) and old logs' ``sensor_combined.magnetometer_ga``,
which are the output of ``Correct`` (calibrated, in the vehicle's frame): the magnetometer
is then not read and one ``warning: magnetometer:`` note says why.

Instances: one ``multi_id`` per compass (``device_id`` names it), chosen like the IMU's
(``--mag-instance`` when several have at least :data:`~accelcal.recording.MIN_ROWS`
samples).  Timed by the IMU's rule (``timestamp_sample``, or ``timestamp`` with
``--time-source log``; one clock, PX4's ``hrt``) and put on the IMU's rows by
:mod:`accelcal.formats.mag_logs`.
"""

from __future__ import annotations

import numpy as np

from ..errors import TopicError
from ..recording import MIN_ROWS
from .logs import choose
from .mag_logs import attach, skipped

#: The ULog topics this module reads (or names when they are the only magnetometer).
MAG_TOPICS = ("sensor_mag", "vehicle_magnetometer")
#: gauss -> µT (SensorMag.msg's unit; ``MAG_UNITS['gauss']``).
GAUSS_TO_UT = 100.0
_FIX = "pass --no-mag"


def add_magnetometer(rec, path, data: dict, params: dict, time_source: str, instance: int | None):
    """``rec`` with the log's ``sensor_mag`` on its rows, or with one warning note (module docstring).
    ``data``: {(topic, multi_id): pyulog data}; ``rec.time_column``: the IMU rows' stamps [µs]."""
    raw = {i: d for (name, i), d in data.items() if name == "sensor_mag"}
    usable = {i: d for i, d in raw.items() if len(d.data["timestamp"]) >= MIN_ROWS}
    if not usable:
        why = _why_none(raw, data)
        return rec if why is None and instance is None else skipped(rec, why or "no sensor_mag in this log")
    cands = {str(i): f"{len(d.data['timestamp'])} samples, device id {_device(d)}" for i, d in usable.items()}
    try:
        inst = int(choose(path, cands, None if instance is None else str(instance), cands,
                          kind="sensor_mag instance", option="--mag-instance"))
    except TopicError as e:
        if instance is not None:
            raise
        return skipped(rec, f"{str(e).split(': ', 1)[-1]} (or --no-mag)")
    d = usable[inst]
    missing = [f for f in ("x", "y", "z") if f not in d.data]
    if missing:
        return skipped(rec, f"sensor_mag instance {inst} lacks {', '.join(missing)}; {_FIX}")
    if "x_raw" in d.data:  # as sensor_accel before PX4 1.10: the driver applied the calibration itself
        return skipped(rec, f"in this PX4 version sensor_mag x, y, z are calibrated by the driver (CAL_MAG offsets and "
                            f"scales applied; x_raw holds the chip's counts before its rotation), not raw; {_FIX}")
    key = "timestamp_sample" if time_source == "header" and "timestamp_sample" in d.data else "timestamp"
    field = np.column_stack([d.data[k].astype(np.float64) for k in ("x", "y", "z")]) * GAUSS_TO_UT
    ok = np.all(np.isfinite(field), axis=1)
    imu_us = np.asarray(rec.time_column[1], dtype=np.int64)
    mag_us = d.data[key].astype(np.int64)[ok]
    what = (f"sensor_mag instance {inst} (device id {_device(d)}, "
            f"{'external' if _flag(d, 'is_external') else 'internal'}; {key}), gauss converted to uT, before the "
            "autopilot's calibration")
    cal = _calibration(params, _device(d))
    return attach(rec, (imu_us - imu_us[0]) * 1e-6, (mag_us - imu_us[0]) * 1e-6, field[ok], what, _FIX,
                  extra_notes=(cal,) if cal else ())


def _why_none(raw: dict, data: dict) -> str | None:
    """Why a log with a magnetometer gives none to read raw (None: the log has no magnetometer)."""
    if raw:
        n = max(len(d.data["timestamp"]) for d in raw.values())
        return (f"sensor_mag is logged with only {n} samples (the logger's profile samples it slowly): log it at its "
                f"rate (SDLOG_PROFILE: high rate, or the logger's topics file), or pass --no-mag")
    calibrated = [k for k in ("vehicle_magnetometer",) if any(name == k for name, _ in data)]
    if ("sensor_combined", 0) in data and "magnetometer_ga[0]" in data[("sensor_combined", 0)].data:
        calibrated.append("sensor_combined.magnetometer_ga")
    if calibrated:
        return (f"only {' and '.join(calibrated)} logged: the autopilot's calibrated field (CAL_MAG* applied, in the "
                "vehicle's frame), not the raw sensor_mag; log sensor_mag, or pass --no-mag")
    return None


def _device(d) -> str:
    ids = d.data.get("device_id")
    return "?" if ids is None or not len(ids) else str(int(ids[0]))


def _flag(d, name: str) -> bool:
    v = d.data.get(name)
    return v is not None and len(v) > 0 and bool(v[0])


def _calibration(params: dict, device: str) -> str:
    """The autopilot's own CAL_MAG<n>_* of this compass (its slot's ID is the device id), as a note."""
    slot = next((n for n in range(4) if str(params.get(f"CAL_MAG{n}_ID", "")) == device), None)
    if slot is None:
        return ""
    keys = [f"CAL_MAG{slot}_{a}{k}" for k in ("OFF", "SCALE") for a in "XYZ"] + [f"CAL_MAG{slot}_ROT"]
    vals = ", ".join(f"{k}={params[k]:.6g}" for k in keys if k in params)
    return f"the autopilot's own calibration of this magnetometer is in the log's parameters (gauss): {vals}"


__all__ = ["GAUSS_TO_UT", "MAG_TOPICS", "add_magnetometer"]
