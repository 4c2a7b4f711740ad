"""What the autopilots' per-axis calibrations hold (PX4 and ArduPilot correct each axis alone)
and the two parameter-file layouts.

Both correct ``x = (raw - offset) ⊙ scale`` for the accelerometer and ``ω = raw - offset``
for the gyroscope, in the sensor's frame, before rotating to the body frame (see
:mod:`.px4`, :mod:`.ardupilot`).  From accelcal's ``raw = M f + b`` and
``ω = C (raw - b_w - G f)``: ``offset = b``, ``scale_i = 1 / M_ii``, gyro ``offset = b_w``.
That is exact for a diagonal ``M``; the non-orthogonality (``M``'s off-diagonal terms),
the gyroscope's ``C`` and ``G`` are left out, with their cost in the summary.
"""

from __future__ import annotations

import numpy as np

from .base import accelerometer_si, diagonal_left_out, gyro_si

#: MAVLink's parameter types, as QGroundControl's .params files write them.
MAV_PARAM_TYPE_INT32 = 6
MAV_PARAM_TYPE_REAL32 = 9


def per_axis_accelerometer(cal, consumer: str) -> tuple[np.ndarray, np.ndarray]:
    """``(offset [m/s²], scale)`` of ``x = (raw - offset) ⊙ scale``."""
    M, b = accelerometer_si(cal, consumer)
    return b, 1.0 / np.diag(M)


def per_axis_gyroscope(cal, consumer: str) -> np.ndarray | None:
    """The gyroscope's offset [rad/s] of ``ω = raw - offset`` (None: no gyroscope)."""
    g = gyro_si(cal, consumer)
    return None if g is None else g[1]


def autopilot_left_out(cal, consumer: str, sensor: str) -> list:
    """The terms of ``sensor`` ('accelerometer' or 'gyroscope') the per-axis model leaves out."""
    out = diagonal_left_out(cal, consumer, gyro_scale=False)
    if sensor == "accelerometer":
        return [x for x in out if "gyroscope" not in x.term]
    return [x for x in out if "gyroscope" in x.term]


def qgc_params(params, header: list[str], vehicle: int = 1, component: int = 1) -> str:
    """QGroundControl's .params layout: ``vehicle<TAB>component<TAB>name<TAB>value<TAB>type``."""
    lines = [f"# {h}" for h in header] + ["#", "# Vehicle-Id Component-Id Name Value Type"]
    for name, value in params:
        kind = MAV_PARAM_TYPE_INT32 if isinstance(value, (int, np.integer)) else MAV_PARAM_TYPE_REAL32
        text = str(int(value)) if kind == MAV_PARAM_TYPE_INT32 else f"{float(value):.12g}"
        lines.append(f"{vehicle}\t{component}\t{name}\t{text}\t{kind}")
    return "\n".join(lines) + "\n"


def parm_file(params, header: list[str]) -> str:
    """ArduPilot's .parm layout: ``NAME VALUE`` per line, ``#`` comments."""
    return "\n".join([f"# {h}" for h in header] + [f"{n} {float(v):.12g}" for n, v in params]) + "\n"


def collect(sections, inputs) -> tuple[list, list, list]:
    """Every section's parameters, left-out terms and notes, in order."""
    params, left, notes = [], [], []
    for section in sections:
        p, lo, n = section(inputs)
        params += p
        left += lo
        notes += n
    return params, left, notes


__all__ = ["MAV_PARAM_TYPE_INT32", "MAV_PARAM_TYPE_REAL32", "autopilot_left_out", "collect", "parm_file",
           "per_axis_accelerometer", "per_axis_gyroscope", "qgc_params"]
