"""What every export shares: its inputs, its result, the sensors in the units consumers take,
the worst-axis noise values, and the cost of a term a consumer's model cannot hold.

Conventions (accelcal's models, :mod:`accelcal.calibration` and :mod:`accelcal.gyro.model`)::

    raw_a = M f + b                       f  specific force [m/s²] in accelcal's frame
    ω = C (raw_w - b_w - G f)             ω  angular rate [rad/s] in the same frame

A consumer that cannot hold a term gets the rest, and :class:`Export` carries a
:class:`LeftOut` line for each term left out, with what it costs: the largest error over
every orientation of gravity (|f| = g) in mg, or in °/s for the gyroscope (its scale and
misalignment at :data:`REFERENCE_RATE_DPS`, a g-sensitivity at |f| = g).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import AccelcalError
from ..units import ANGULAR_RATE_UNITS, G0

#: What a consumer without IMU intrinsics needs: data the calibration was applied to.
APPLY_FIRST = ("feed it data the calibration was applied to (accelcal apply): then nothing above is lost, and the "
               "noise values still hold")
#: The rate at which a gyroscope's scale and misalignment left out are costed [deg/s].
REFERENCE_RATE_DPS = 100.0


class ExportError(AccelcalError):
    """A calibration or noise report that cannot be written in a consumer's format (one line)."""


@dataclass(frozen=True)
class LeftOut:
    """A term of the calibration a consumer's model cannot hold, and what leaving it out costs."""

    term: str
    cost: str
    exact_loss: bool = True  #: False for a term whose loss is zero here (only said, never refused)

    def line(self) -> str:
        return f"left out: {self.term} ({self.cost})"


@dataclass
class Export:
    """One consumer's files and what the summary says of them.

    ``files`` maps a file-name suffix ('' for the file named by the user) to its text;
    ``left_out`` the terms the consumer cannot hold; ``notes`` what the user must know
    (where a bias goes, which frame the file is in)."""

    files: dict[str, str]
    left_out: list[LeftOut] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class ExportInputs:
    """What an exporter reads: the calibration, the noise report's JSON (or None) and the options.

    ``options``: ``rostopic``, ``inflate``, ``instance``, ``model`` (OpenVINS), ``corr_time_h``
    (KF-GINS), ``device_id`` (PX4), ``source`` (the calibration's file name) ..."""

    calibration: object
    noise: dict | None = None
    options: dict = field(default_factory=dict)

    def option(self, name, default=None):
        v = self.options.get(name)
        return default if v is None else v


# --------------------------------------------------------------------------- the sensors in SI units


def accelerometer_si(cal, consumer: str) -> tuple[np.ndarray, np.ndarray]:
    """``(M, b)`` of ``raw = M f + b`` with raw data in m/s² (what the estimators and autopilots take)."""
    if cal.unit != "m/s^2":
        raise ExportError(f"{consumer} takes the accelerometer in m/s^2; this calibration is of "
                          f"{cal.unit or 'an unknown'} data: calibrate data read in m/s^2 (--unit m/s2, g or mg)")
    if np.any(cal.input_offset != 0) or np.any(cal.input_sensitivity != 1):
        raise ExportError(f"{consumer} takes the accelerometer in m/s^2; this calibration converts raw counts "
                          "nominally: calibrate data read in m/s^2")
    return np.asarray(cal.M, float), np.asarray(cal.bias, float)


def gyro_si(cal, consumer: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(C, b, G)`` of ``ω = C (raw - b - G f)`` with raw data in rad/s (None: no gyroscope).

    A gyroscope calibrated from deg/s data is rewritten for rad/s data: the same map."""
    if cal.gyro is None:
        return None
    m = cal.gyro.model
    k = ANGULAR_RATE_UNITS[m.raw_unit]
    if k is None:
        raise ExportError(f"{consumer} takes the gyroscope in rad/s; this calibration's gyroscope is of raw counts: "
                          "calibrate gyro data read in rad/s or deg/s (--gyro-unit)")
    G = np.zeros((3, 3)) if m.g_sensitivity is None else np.asarray(m.g_sensitivity, float)
    return np.asarray(m.C, float) / k, np.asarray(m.bias, float) * k, G * k


def require_gyro(cal, consumer: str, why: str) -> None:
    if cal.gyro is None:
        raise ExportError(f"{consumer} needs the gyroscope ({why}); this calibration has none: calibrate a recording "
                          "with gyro columns or topic (or --gyro FILE)")


def require_noise(inputs: ExportInputs, consumer: str) -> dict:
    if inputs.noise is None:
        raise ExportError(f"{consumer} needs the noise densities and random walks: pass --noise NOISE.json (from "
                          "accelcal noise on a static recording)")
    return inputs.noise


# --------------------------------------------------------------------------- noise values


#: (sensor, report key) -> the SI unit a consumer takes.
NOISE_UNITS = {("accelerometer", "noise_density"): "m/s^2/sqrt(Hz)", ("accelerometer", "random_walk"): "m/s^3/sqrt(Hz)",
               ("gyroscope", "noise_density"): "rad/s/sqrt(Hz)", ("gyroscope", "random_walk"): "rad/s^2/sqrt(Hz)"}
SENSOR_UNITS = {"accelerometer": "m/s^2", "gyroscope": "rad/s"}


@dataclass(frozen=True)
class NoiseValue:
    """One exported noise number: the worst axis of a sensor, inflated, and a comment on it."""

    value: float
    unit: str
    comment: str
    per_axis: tuple[float, ...]


def noise_value(noise: dict, sensor: str, what: str, consumer: str, inflate: float = 1.0) -> NoiseValue | None:
    """The worst axis of ``sensor``'s ``what`` ('noise_density' or 'random_walk') in a noise report's
    JSON (None when the report has no such sensor)."""
    if not (inflate >= 1 and math.isfinite(inflate)):
        raise ExportError(f"the inflation factor must be a finite number >= 1, got {inflate}")
    s = (noise.get("sensors") or {}).get(sensor)
    if s is None:
        return None
    if s.get("unit") != SENSOR_UNITS[sensor]:
        raise ExportError(f"the noise report's {sensor} is in {s.get('unit')}; {consumer} needs {SENSOR_UNITS[sensor]} "
                          "(read the data in physical units: --unit, --gyro-unit)")
    try:
        per = [s["axes"][ax][what] for ax in "xyz"]
        vals = [float("nan") if p["value"] is None else float(p["value"]) for p in per]
    except (KeyError, TypeError, ValueError):
        raise ExportError(f"the noise report has no {sensor} {what.replace('_', ' ')} (not accelcal noise's JSON?)") \
            from None
    if not all(math.isfinite(v) and v > 0 for v in vals):
        raise ExportError(f"the noise report's {sensor} {what.replace('_', ' ')} is not a positive number on every "
                          f"axis ({', '.join(f'{v:.3g}' for v in vals)}): rerun accelcal noise on a longer static recording")
    j = int(np.argmax(vals))
    unit = NOISE_UNITS[(sensor, what)]
    bits = ", ".join(f"{ax} {v:.4g}" + (" (upper bound)" if p.get("upper_bound") else "")
                     for ax, v, p in zip("xyz", vals, per))
    lo, hi = (per[j].get("interval") or [None, None])[:2]
    level = noise.get("level")
    comment = f"[ {unit} ] worst axis {'xyz'[j]}; per axis {bits}"
    if lo is not None and hi is not None:
        comment += f"; {int(100 * (level or 0.95))} % interval of {'xyz'[j]} [{lo:.3g}, {hi:.3g}]"
    if per[j].get("upper_bound"):
        comment += "; not resolved by the record: the upper end of its interval"
    if inflate != 1:
        comment += f"; inflated x{inflate:g} from {vals[j]:.4g}"
    return NoiseValue(vals[j] * inflate, unit, comment, tuple(vals))


def noise_rate(noise: dict) -> float:
    fs = noise.get("fs_hz")
    if not (isinstance(fs, (int, float)) and fs > 0):
        raise ExportError("the noise report has no sampling rate (fs_hz): not accelcal noise's JSON?")
    return float(fs)


def rate_text(fs: float) -> str:
    return repr(float(f"{fs:.6g}"))


# --------------------------------------------------------------------------- costs


def _smax(A) -> float:
    return float(np.linalg.norm(np.asarray(A, float), 2))


def accel_cost_mg(E, g: float = G0) -> float:
    """Largest error [mg] of ``E f`` over every orientation of gravity, |f| = g."""
    return _smax(E) * g / G0 * 1e3


def rate_cost_dps(E, rate_dps: float = REFERENCE_RATE_DPS) -> float:
    """Largest error [deg/s] of ``E ω`` over every direction of a rate of ``rate_dps``."""
    return _smax(E) * rate_dps


def g_sensitivity_cost_dps(CG, g: float = G0) -> float:
    """Largest error [deg/s] of ``C G f`` (a g-sensitivity left out) over every orientation, |f| = g."""
    return math.degrees(_smax(CG) * g)


def effects_left_out(cal, consumer: str) -> list[LeftOut]:
    """The fitted effects (temperature, drift ...; the gyroscope's named by ``accelcal discrepancy``), which no
    consumer's model holds."""
    out = [LeftOut(f"the fitted effect {e.id}", f"{consumer} has no such term; its size follows its covariate: "
                   f"parameters {', '.join(f'{v:.3g}' for v in np.ravel(e.values))}") for e in cal.effects]
    gyro = [] if cal.gyro is None else [e for e in cal.gyro.effects if e["id"] != "g_sensitivity"]  # G: the model's
    return out + [LeftOut(f"the gyroscope's fitted effect {e['id']}", f"{consumer} has no such term: parameters "
                          f"{', '.join(f'{p} {v:.3g}' for p, v in zip(e['params'], e['values']))}") for e in gyro]


def diagonal_left_out(cal, consumer: str, *, gyro_scale: bool) -> list[LeftOut]:
    """What a model of per-axis offsets (and scales) leaves out of accelcal's: the accelerometer's
    misalignment, and the gyroscope's scale (unless ``gyro_scale``), misalignment and g-sensitivity."""
    M, _ = accelerometer_si(cal, consumer)
    D = np.diag(np.diag(M))
    out = [LeftOut("the accelerometer's non-orthogonality (M's off-diagonal terms)",
                   f"up to {accel_cost_mg(np.linalg.solve(D, M) - np.eye(3)):.3g} mg at the worst orientation")]
    g = gyro_si(cal, consumer)
    if g is not None:
        C, _, G = g
        Dc = np.diag(np.diag(C)) if gyro_scale else np.eye(3)
        what = "misalignment (C's off-diagonal terms)" if gyro_scale else "scale and misalignment (C)"
        out.append(LeftOut(f"the gyroscope's {what}", f"up to {rate_cost_dps(Dc @ np.linalg.inv(C) - np.eye(3)):.3g} "
                           f"deg/s at {REFERENCE_RATE_DPS:g} deg/s"))
        if np.any(G != 0):
            out.append(LeftOut("the gyroscope's g-sensitivity G", f"up to {g_sensitivity_cost_dps(Dc @ G):.3g} deg/s "
                               "at the worst orientation"))
    return [x for x in out if not _zero(x)] + effects_left_out(cal, consumer)


def _zero(x: LeftOut) -> bool:
    """A term whose cost is zero here (e.g. a diagonal M): nothing is left out."""
    return x.cost.startswith("up to 0 ")


def intrinsics_left_out(cal, consumer: str) -> list[LeftOut]:
    """What a consumer without IMU intrinsics (it estimates the biases online) leaves out: the
    accelerometer's scale and non-orthogonality, the gyroscope's scale, misalignment and g-sensitivity."""
    M, _ = accelerometer_si(cal, consumer)
    out = [LeftOut(f"the accelerometer's scale and non-orthogonality M ({consumer} has no IMU intrinsics)",
                   f"up to {accel_cost_mg(M - np.eye(3)):.3g} mg at the worst orientation on raw data")]
    g = gyro_si(cal, consumer)
    if g is not None:
        C, _, G = g
        cost = rate_cost_dps(np.linalg.inv(C) - np.eye(3))
        out.append(LeftOut("the gyroscope's scale and misalignment C",
                           f"up to {cost:.3g} deg/s at {REFERENCE_RATE_DPS:g} deg/s on raw data"))
        if np.any(G != 0):
            out.append(LeftOut("the gyroscope's g-sensitivity G", f"up to {g_sensitivity_cost_dps(G):.3g} deg/s at the "
                               "worst orientation on raw data"))
    return [x for x in out if not _zero(x)] + effects_left_out(cal, consumer)


def matrix_lines(name: str, m, indent: str = "  ") -> list[str]:
    """A 3x3 matrix as a YAML list of rows (the layout Kalibr, OpenVINS and OpenCV read)."""
    return [f"{indent}{name}:"] + [f"{indent}  - [ {', '.join(repr(float(v) + 0.0) for v in row)} ]"
                                   for row in np.asarray(m, float)]


__all__ = ["APPLY_FIRST", "Export", "ExportError", "ExportInputs", "LeftOut", "NoiseValue", "REFERENCE_RATE_DPS",
           "accel_cost_mg", "accelerometer_si", "diagonal_left_out", "effects_left_out", "g_sensitivity_cost_dps",
           "gyro_si", "intrinsics_left_out", "matrix_lines", "noise_rate", "noise_value", "rate_cost_dps", "rate_text", "require_gyro", "require_noise"]
