"""ArduPilot's calibration parameters in a ``.parm`` file (``NAME VALUE`` lines, which
MAVProxy's ``param load``, Mission Planner and ArduPilot's defaults files read).

ArduPilot's own equations (ArduPilot/ardupilot,
``libraries/AP_InertialSensor/AP_InertialSensor_Backend.cpp``):

* ``_rotate_and_correct_accel`` l. 94-134: after the sensor's orientation,
  ``accel -= _accel_offset`` (l. 123), then ``accel.x *= accel_scale.x`` ... (l. 127-130),
  then the board orientation: ``INS_ACCOFFS_{X,Y,Z}`` [m/s²], ``INS_ACCSCAL_{X,Y,Z}``;
* ``_rotate_and_correct_gyro`` l. 137-159: ``gyro -= _gyro_offset`` (l. 156):
  ``INS_GYROFFS_{X,Y,Z}`` [rad/s]; no scale.

The second and third IMU: ``INS_ACC2OFFS``, ``INS_ACC2SCAL``, ``INS_GYR2OFFS`` (and 3).
ArduPilot logs its IMU messages *after* this correction: a calibration made from a
DataFlash log corrects data already corrected, and its offsets add to the ones the
vehicle holds (the summary says so).
"""

from __future__ import annotations

from .base import Export, ExportError
from .params import autopilot_left_out, collect, parm_file, per_axis_accelerometer, per_axis_gyroscope
from .registry import sections


def _names(inputs) -> tuple[str, str, str]:
    n = int(inputs.option("instance", 0))
    if not 0 <= n <= 2:
        raise ExportError(f"ArduPilot has IMU calibration sets 0-2, got --instance {n}")
    k = "" if n == 0 else str(n + 1)
    return f"INS_ACC{k}OFFS", f"INS_ACC{k}SCAL", ("INS_GYROFFS" if n == 0 else f"INS_GYR{k}OFFS")


def accelerometer_section(inputs):
    cal = inputs.calibration
    off_name, scale_name, _ = _names(inputs)
    off, scale = per_axis_accelerometer(cal, "ArduPilot")
    params = [(f"{off_name}_{ax}", o) for ax, o in zip("XYZ", off)] + \
             [(f"{scale_name}_{ax}", s) for ax, s in zip("XYZ", scale)]
    notes = []
    if str(cal.provenance.get("recording", "")).lower().endswith(".bin"):
        notes.append("the calibration was made from a DataFlash log, whose IMU data ArduPilot had already corrected: "
                     "these offsets and scales compose with the vehicle's present ones, they do not replace them")
    return params, autopilot_left_out(cal, "ArduPilot", "accelerometer"), notes


def gyroscope_section(inputs):
    cal = inputs.calibration
    _, _, gyro_name = _names(inputs)
    off = per_axis_gyroscope(cal, "ArduPilot")
    if off is None:
        return [], [], ["no gyroscope in the calibration: INS_GYROFFS not written"]
    return [(f"{gyro_name}_{ax}", o) for ax, o in zip("XYZ", off)], \
        autopilot_left_out(cal, "ArduPilot", "gyroscope"), []


def write(inputs) -> Export:
    params, left, notes = collect(sections("ardupilot"), inputs)
    header = [f"ArduPilot calibration parameters from accelcal ({inputs.option('source', 'a calibration')})",
              "accel = (raw - INS_ACCOFFS) * INS_ACCSCAL, gyro = raw - INS_GYROFFS (sensor frame)"]
    return Export({"": parm_file(params, header)}, left, notes)


__all__ = ["accelerometer_section", "gyroscope_section", "write"]
