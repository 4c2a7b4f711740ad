"""PX4's calibration parameters in a ``.params`` file (QGroundControl's layout, which its
"Load from file" and ``param import`` read).

PX4's own equations (PX4/PX4-Autopilot, ``src/lib/sensor_calibration/``):

* ``Accelerometer.hpp`` l. 82-85: ``Correct(data) = _rotation * (data - _thermal_offset -
  _offset).emult(_scale)``, with ``_offset`` = ``CAL_ACCn_{X,Y,Z}OFF`` [m/s²] and ``_scale``
  = ``CAL_ACCn_{X,Y,Z}SCALE`` (``Accelerometer.cpp``, ``"CAL_%s%u_%cOFF"``/``"%cSCALE"``).
* ``Gyroscope.hpp`` l. 75-78: ``Correct(data) = _rotation * (data - _thermal_offset -
  _offset)``, ``CAL_GYROn_{X,Y,Z}OFF`` [rad/s]; no scale.

The offsets and scales apply in the sensor's frame (``sensor_accel``, ``sensor_gyro``:
what accelcal calibrates from a ULog), before the rotation, which this file leaves as it
is.  PX4 uses a calibration slot only for the device whose ``CAL_ACCn_ID`` matches: the
id is written when known (``--device-id``, or the ULog the calibration was made from).
"""

from __future__ import annotations

import re

from .base import Export, ExportError
from .params import autopilot_left_out, collect, per_axis_accelerometer, per_axis_gyroscope, qgc_params
from .registry import sections


def _instance(inputs) -> int:
    n = int(inputs.option("instance", 0))
    if not 0 <= n <= 3:
        raise ExportError(f"PX4 has calibration slots 0-3, got --instance {n}")
    return n


def _device_id(inputs, sensor: str):
    """The device id: ``--device-id`` (the accelerometer's), else the ULog reader's note."""
    given = inputs.option("device_id") if sensor == "accel" else None
    if given is not None:
        return int(given)
    notes = " ".join(inputs.calibration.provenance.get("notes") or ())
    m = re.search(rf"sensor_{sensor} instance \d+ \(device id (\d+)[,)]", notes)
    return int(m.group(1)) if m else None


def accelerometer_section(inputs):
    cal, n = inputs.calibration, _instance(inputs)
    off, scale = per_axis_accelerometer(cal, "PX4")
    params = []
    dev = _device_id(inputs, "accel")
    if dev is not None:
        params.append((f"CAL_ACC{n}_ID", dev))
    for ax, o, s in zip("XYZ", off, scale):
        params += [(f"CAL_ACC{n}_{ax}OFF", o), (f"CAL_ACC{n}_{ax}SCALE", s)]
    notes = [] if dev is not None else [f"CAL_ACC{n}_ID not written (unknown device id): PX4 applies slot {n} only to "
                                        "the device whose id it holds (--device-id)"]
    if "PX4 ULog, sensor_combined" in " ".join(cal.provenance.get("notes") or ()):
        notes.append("the calibration was made from sensor_combined, which PX4 had already calibrated: these offsets "
                     "and scales compose with the vehicle's present ones, they do not replace them")
    return params, autopilot_left_out(cal, "PX4", "accelerometer"), notes


def gyroscope_section(inputs):
    cal, n = inputs.calibration, _instance(inputs)
    off = per_axis_gyroscope(cal, "PX4")
    if off is None:
        return [], [], ["no gyroscope in the calibration: CAL_GYRO parameters not written"]
    dev = _device_id(inputs, "gyro")
    params = ([] if dev is None else [(f"CAL_GYRO{n}_ID", dev)]) + [(f"CAL_GYRO{n}_{ax}OFF", o)
                                                                      for ax, o in zip("XYZ", off)]
    return params, autopilot_left_out(cal, "PX4", "gyroscope"), []


def write(inputs) -> Export:
    params, left, notes = collect(sections("px4"), inputs)
    header = [f"PX4 calibration parameters from accelcal ({inputs.option('source', 'a calibration')})",
              "x = (raw - CAL_ACCn_xOFF) * CAL_ACCn_xSCALE, w = raw - CAL_GYROn_xOFF (sensor frame)"]
    return Export({"": qgc_params(params, header)}, left, notes)


__all__ = ["accelerometer_section", "gyroscope_section", "write"]
