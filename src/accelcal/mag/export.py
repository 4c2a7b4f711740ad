"""The magnetometer's calibration in the forms autopilots and Magneto read, each following
its consumer's own equations (checked by ``tests/test_mag_export.py``, which implements them).

PX4 (``src/lib/sensor_calibration/Magnetometer.hpp``, ``Correct()``, commit 021ee44, l. 86–89):
``m = R_board · S · (raw - CAL_MAGn_{X,Y,Z}OFF)`` with ``S`` symmetric, ``diag = CAL_MAGn_{X,Y,Z}SCALE``
and ``S01, S02, S12 = CAL_MAGn_{X,Y,Z}ODIAG`` (``Magnetometer.cpp``, ``ParametersUpdate``); in gauss.
ArduPilot (``libraries/AP_Compass/AP_Compass_Backend.cpp``, ``correct_field``, commit 2017268,
l. 86–114): ``m = M · ((raw + COMPASS_OFS) · COMPASS_SCALE)`` with ``M`` from ``COMPASS_DIA_*`` and
``COMPASS_ODI_*`` (X: xy, Y: xz, Z: yz); in milligauss; the offsets are *added*, and a
``COMPASS_SCALE`` outside [1/1.5, 1.5] is ignored by the autopilot (``Compass::have_scale_factor``),
so the scale goes into the matrix then.  Magneto 1.2: ``h_cal = A⁻¹ (h - b)``.

Neither autopilot has a parameter for an arbitrary rotation between the magnetometer and
the accelerometer (rotation enums only): the symmetric soft iron is exported and the
alignment's angle is stated in a comment line, not dropped silently.
"""

from __future__ import annotations

import numpy as np

from ..errors import AccelcalError

#: Factors from a Recording's magnetometer unit to gauss.
TO_GAUSS = {"uT": 0.01, "gauss": 1.0}
#: ArduPilot's accepted COMPASS_SCALE range (``CompassCalibrator.h``: COMPASS_MIN/MAX_SCALE_FACTOR).
ARDUPILOT_SCALE_RANGE = (1 / 1.5, 1.5)


def _gauss_factor(model) -> float:
    if model.raw_unit not in TO_GAUSS:
        raise AccelcalError(f"the magnetometer was calibrated from {model.raw_unit}: autopilot parameters need a "
                            "physical unit (read it with --mag-unit uT, gauss or T)")
    return TO_GAUSS[model.raw_unit]


def _radius(A) -> float:
    """The fitted field strength in the raw unit: the radius whose sphere has the ellipsoid's volume."""
    return float(np.linalg.det(A) ** (-1.0 / 3.0))


def output_scale(model) -> float:
    """The field strength the exported correction outputs, in the raw unit: the model's (µT,
    from --location/--date) when given, else the fitted strength (the raw magnitude kept)."""
    if model.strength_unit == "uT" and model.raw_unit in TO_GAUSS:
        return model.strength * 0.01 / TO_GAUSS[model.raw_unit]
    return _radius(model.A)


def _comment(model, prefix: str) -> list[str]:
    ang = float(np.degrees(np.arccos(np.clip((np.trace(model.R) - 1) / 2, -1, 1))))
    lines = [f"{prefix} accelcal magnetometer calibration: hard and symmetric soft iron"]
    if ang > 0:
        lines.append(f"{prefix} the alignment to the accelerometer ({ang:.2f} deg) has no parameter here: not exported")
    if model.strength_unit == "normalised":
        lines.append(f"{prefix} field strength: the fitted one (no --location/--date)")
    return lines


def px4_rows(model, instance: int = 0) -> list[tuple[str, float]]:
    """``CAL_MAGn_*`` parameters as ``(name, value)``: offsets [gauss], the symmetric matrix ``S``."""
    k = _gauss_factor(model)
    S = model.A * output_scale(model)  # raw -> output, both in the raw unit
    off = model.b * k
    p = f"CAL_MAG{instance}_"
    rows = [(f"{p}{a}OFF", off[i]) for i, a in enumerate("XYZ")]
    rows += [(f"{p}{a}SCALE", S[i, i]) for i, a in enumerate("XYZ")]
    rows += [(f"{p}{a}ODIAG", S[i, j]) for a, (i, j) in zip("XYZ", ((0, 1), (0, 2), (1, 2)))]
    return rows


def px4_params(model, instance: int = 0) -> str:
    """``CAL_MAGn_*`` parameters (QGroundControl's ``.params`` tab-separated: vehicle, component, name, value, type)."""
    return "\n".join(_comment(model, "#") + [f"1\t1\t{n}\t{v:.9g}\t9" for n, v in px4_rows(model, instance)]) + "\n"


def ardupilot_rows(model, instance: int = 1) -> tuple[list[tuple[str, float]], list[str]]:
    """``COMPASS_OFS*``, ``COMPASS_DIA*``, ``COMPASS_ODI*``, ``COMPASS_SCALE*`` as ``(name, value)`` [milligauss],
    and the comment lines (where the scale went)."""
    k = _gauss_factor(model) * 1000.0  # milligauss
    r = _radius(model.A)
    D = model.A * r  # unit volume: diagonals near 1, as ArduPilot's calibrator leaves them
    scale = output_scale(model) / r
    lo, hi = ARDUPILOT_SCALE_RANGE
    lines = []
    if not lo <= scale <= hi:
        D, scale = D * scale, 1.0
        lines.append("the scale to the model's strength is outside COMPASS_SCALE's range: put in the matrix")
    n = "" if instance == 1 else str(instance)
    ofs = -model.b * k
    rows = [(f"COMPASS_OFS{n}_{a}", ofs[i]) for i, a in enumerate("XYZ")]
    rows += [(f"COMPASS_DIA{n}_{a}", D[i, i]) for i, a in enumerate("XYZ")]
    rows += [(f"COMPASS_ODI{n}_{a}", D[i, j]) for a, (i, j) in zip("XYZ", ((0, 1), (0, 2), (1, 2)))]
    rows.append((f"COMPASS_SCALE{n}", scale))
    return rows, lines


def ardupilot_params(model, instance: int = 1) -> str:
    """The ArduPilot rows (:func:`ardupilot_rows`) in Mission Planner's ``NAME,VALUE`` layout."""
    rows, lines = ardupilot_rows(model, instance)
    return "\n".join(_comment(model, "#") + [f"# {x}" for x in lines] + [f"{name},{v:.9g}" for name, v in rows]) + "\n"


def px4_section(inputs):
    """The ``px4`` consumer's magnetometer section (:mod:`accelcal.export.registry`): CAL_MAG0 from the
    calibration's magnetometer, if it has one."""
    mag = getattr(inputs.calibration, "mag", None)
    if mag is None:
        return [], [], []
    notes = [x.lstrip("# ") for x in _comment(mag.model, "#")[1:]]
    return px4_rows(mag.model, int(inputs.option("instance", 0))), [], notes


def ardupilot_section(inputs):
    """The ``ardupilot`` consumer's magnetometer section: COMPASS_* of the calibration's magnetometer, if any."""
    mag = getattr(inputs.calibration, "mag", None)
    if mag is None:
        return [], [], []
    rows, lines = ardupilot_rows(mag.model, int(inputs.option("instance", 0)) + 1)  # INS set 0 is compass 1
    return rows, [], [x.lstrip("# ") for x in _comment(mag.model, "#")[1:]] + lines


def magneto_text(model) -> str:
    """Magneto 1.2's result block: the combined bias ``b`` and ``A⁻¹`` with ``h_cal = A⁻¹ (h - b)``,
    scaled to the field norm (the model's, or 1: normalised)."""
    Ainv = model.A * model.strength
    out = [f"Norm of magnetic field: {model.strength:.9g} ({model.strength_unit})", "Combined bias (b):",
           " ".join(f"{v:.9g}" for v in model.b),
           "Correction for combined scale factors, misalignments and soft iron (A-1):"]
    out += [" ".join(f"{v:.9g}" for v in row) for row in Ainv]
    return "\n".join(out) + "\n"


__all__ = ["ARDUPILOT_SCALE_RANGE", "ardupilot_params", "ardupilot_rows", "ardupilot_section", "magneto_text",
           "output_scale", "px4_params", "px4_rows", "px4_section"]
