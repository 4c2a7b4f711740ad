"""The noise report as JSON, and as the files estimators read: Kalibr's ``imu.yaml`` and OpenVINS's
``kalibr_imu_chain.yaml``.

Values (continuous time, as both tools define them):

============================  ==========================  =========================================
key                           unit                        from the IEEE fit of each axis
============================  ==========================  =========================================
accelerometer_noise_density   m/s²/√Hz  (= m/s/√s)        white noise N (ADEV = N/√τ, N = ADEV(1 s))
accelerometer_random_walk     m/s³/√Hz  (= m/s²/√s)       random walk K (ADEV = K√(τ/3), K = ADEV(3 s))
gyroscope_noise_density       rad/s/√Hz (= rad/√s)        white noise N
gyroscope_random_walk         rad/s²/√Hz (= rad/s/√s)     random walk K
============================  ==========================  =========================================

The files hold one number per key: the worst (largest) axis, with every axis and the
interval in a comment beside it.  A random walk the record does not resolve
(:mod:`accelcal.noise.report`) is exported as the upper end of its interval, and the
comment says so.  ``inflate`` multiplies the exported noise densities and random walks
(OpenVINS's documentation advises 10–20× for unmodelled effects); the measured values
stay in the comments.

OpenVINS's model (``docs/propagation.dox``, ``VioManagerOptions.h``)::

    ω_m = T_w R_IMUtoGYRO ω + T_g a + b_g + n_g,    a_m = T_a R_IMUtoACC a + b_a + n_a

and it estimates ``D = T⁻¹``; its ``kalibr`` model keeps the lower triangle of ``D_a``,
``D_w`` (the inverse of a lower-triangular ``T`` is lower triangular) and a gyroscope
rotation, with ``R_IMUtoACC`` the identity.  accelcal's model is ``z = M x + b`` with ``M``
lower triangular, so ``T_a = M``, ``R_IMUtoACC = I`` and the model is ``kalibr``; the
bias ``b`` is not a field of the file (OpenVINS estimates ``b_a`` online: it is written
as a comment).  accelcal does not calibrate the gyroscope yet: ``T_w = I``,
``R_IMUtoGYRO = I``, ``T_g = 0``.  A calibration is exported only when it is in m/s²,
without a nominal conversion of counts; its fitted effects (temperature, ...) have no
place in the file and are left out with a warning.

``allan_variance_ros`` convention (optional): a line of slope −½ fitted in log–log to
the Allan deviations at τ < 10 s and read at τ = 1 s, a line of slope +½ fitted to all
of them and read at τ = 3 s, and the minimum Allan deviation as "bias instability" —
on this report's octave τ grid, not that tool's denser grid, so its numbers differ
from that tool's by the grid as well.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import AccelcalError
from ..jsonsafe import json_safe

FORMAT = "accelcal-noise"
FORMAT_VERSION = 1
#: Unit of each term's coefficient, for data unit ``u``.
TERM_UNITS = {"quantization": "{u}*s", "white": "{u}/sqrt(Hz)", "bias_instability": "{u}",
              "random_walk": "{w}", "drift_ramp": "{u}/s"}
#: (yaml key, sensor, report key, unit) of the exported values.
KALIBR_KEYS = (("accelerometer_noise_density", "accelerometer", "noise_density", "m/s^2/sqrt(Hz)"),
               ("accelerometer_random_walk", "accelerometer", "random_walk", "m/s^3/sqrt(Hz)"),
               ("gyroscope_noise_density", "gyroscope", "noise_density", "rad/s/sqrt(Hz)"),
               ("gyroscope_random_walk", "gyroscope", "random_walk", "rad/s^2/sqrt(Hz)"))
AVR_WHITE_TAU_MAX = 10.0


class ExportError(AccelcalError):
    """A noise report or a calibration that cannot be written in an estimator's format."""


# --------------------------------------------------------------------------- JSON


def report_dict(report) -> dict:
    """The report as plain JSON types (NaN and inf as None)."""
    out = {"format": FORMAT, "format_version": FORMAT_VERSION, "source": report.source, "fs_hz": report.fs,
           "n_samples": report.n, "duration_s": report.duration_s, "level": report.level, "n_boot": report.n_boot,
           "seed": report.seed, "static": {k: v for k, v in report.static.items() if k != "warnings"},
           "warnings": list(report.warnings), "notes": list(report.notes), **report.extra,
           "sensors": {name: _sensor_dict(s) for name, s in report.sensors.items()}}
    return json_safe(out)


def _sensor_dict(s) -> dict:
    a = s.allan
    axes = {}
    for j, (ax, terms) in enumerate(zip("xyz", s.terms)):
        units = {k: TERM_UNITS[k].format(u=s.unit, w=walk_unit(s.unit)) for k in terms}
        axes[ax] = {"terms": {k: {**e.to_dict(), "unit": units[k]} for k, e in terms.items()},
                    **exported_values(s, j), "allan_variance_ros": avr_convention(a.taus, a.adev[:, j]),
                    "adev_floor": {"value": 0.664 * terms["bias_instability"].value, "unit": s.unit,
                                   "meaning": "flicker floor of the fit, 0.664 B"},
                    "conversions": conversions(s.sensor, s.unit, terms)}
    return {"unit": s.unit, "taus_s": a.taus, "m": a.m, "n_terms": a.n_terms, "adev": a.adev,
            "adev_interval": s.adev_interval, "edf": s.edf, "adev_model": s.model_adev(a.taus), "axes": axes}


def walk_unit(unit: str) -> str:
    """Unit of a random walk coefficient K of data in ``unit`` (``u/s/sqrt(Hz)``, spelled out for SI data)."""
    return {"m/s^2": "m/s^3/sqrt(Hz)", "rad/s": "rad/s^2/sqrt(Hz)"}.get(unit, f"{unit}/s/sqrt(Hz)")


def exported_values(s, j: int) -> dict:
    """Noise density and random walk of axis ``j`` as the exports write them (see the module docstring)."""
    t = s.terms[j]
    w, k = t["white"], t["random_walk"]
    rw = k.value if k.resolved else k.hi
    u = s.unit
    return {"noise_density": {"value": w.value, "interval": [w.lo, w.hi], "unit": f"{u}/sqrt(Hz)"},
            "random_walk": {"value": rw, "interval": [k.lo, k.hi], "unit": walk_unit(u),
                            "upper_bound": not k.resolved, "fitted": k.value}}


def avr_convention(taus, adev) -> dict:
    """allan_variance_ros's numbers on this τ grid (module docstring)."""
    taus, adev = np.asarray(taus, float), np.asarray(adev, float)
    short = taus < AVR_WHITE_TAU_MAX
    white = math.exp(float(np.mean(np.log(adev[short]) + 0.5 * np.log(taus[short])))) if short.any() else None
    walk = math.exp(float(np.mean(np.log(adev) - 0.5 * np.log(taus))) + 0.5 * math.log(3.0))
    i = int(np.argmin(adev))
    return {"noise_density": white, "random_walk": walk, "bias_instability": float(adev[i]),
            "bias_instability_tau_s": float(taus[i])}


def conversions(sensor: str, unit: str, terms: dict) -> dict:
    """Datasheet units of the white noise and the flicker floor (m/s² or rad/s data only)."""
    n, b = terms["white"].value, 0.664 * terms["bias_instability"].value
    if unit == "m/s^2":
        return {"velocity_random_walk_m_s_sqrt_h": 60.0 * n, "bias_instability_floor_mg": 1e3 * b / 9.80665}
    if unit == "rad/s":
        return {"angle_random_walk_deg_sqrt_h": 60.0 * math.degrees(n), "bias_instability_floor_deg_h":
                3600.0 * math.degrees(b), "bias_instability_floor_deg_s": math.degrees(b)}
    return {}


# --------------------------------------------------------------------------- Kalibr and OpenVINS


def _values(report, inflate: float) -> tuple[dict, list[str]]:
    """{yaml key: (value, comment)} of the four exported numbers, worst axis, inflated."""
    if not (inflate >= 1 and math.isfinite(inflate)):
        raise ExportError(f"the inflation factor must be a finite number >= 1, got {inflate}")
    want = {"accelerometer": "m/s^2", "gyroscope": "rad/s"}
    out, missing = {}, []
    for key, sensor, what, unit in KALIBR_KEYS:
        s = report.sensors.get(sensor)
        if s is None:
            missing.append(key)
            continue
        if s.unit != want[sensor]:
            raise ExportError(f"the {sensor} is in {s.unit}; Kalibr and OpenVINS need {want[sensor]} (read the data in "
                              "physical units: --unit, or calibrate the counts first)")
        per = [exported_values(s, j)[what] for j in range(3)]
        worst = int(np.argmax([p["value"] for p in per]))
        bits = ", ".join(f"{ax} {p['value']:.4g}" + (" (upper bound)" if p.get("upper_bound") else "")
                         for ax, p in zip("xyz", per))
        note = f"[ {unit} ] worst axis {'xyz'[worst]}; per axis {bits}; {int(100 * report.level)} % interval of " \
               f"{'xyz'[worst]} [{per[worst]['interval'][0]:.3g}, {per[worst]['interval'][1]:.3g}]"
        if per[worst].get("upper_bound"):
            note += "; not resolved by the record: the upper end of its interval"
        if inflate != 1:
            note += f"; inflated x{inflate:g} from {per[worst]['value']:.4g}"
        out[key] = (per[worst]["value"] * inflate, note)
    return out, missing


def kalibr_yaml(report, *, rostopic: str = "/imu0", inflate: float = 1.0) -> str:
    """Kalibr's ``imu.yaml`` (continuous-time noise densities and random walks, update rate, topic)."""
    vals, missing = _values(report, inflate)
    lines = [f"# Kalibr IMU noise model from accelcal noise ({report.source}, {report.duration_s / 3600:.3g} h at "
             f"{report.fs:.6g} Hz)", "# continuous-time values from the IEEE Std 952 fit of the Allan deviation;",
             "# each number is the worst axis, the comment gives every axis and the interval"]
    if inflate != 1:
        lines.append(f"# inflated x{inflate:g} (OpenVINS advises 10-20x for effects the model lacks)")
    lines += [f"# {k}: no {k.split('_')[0]} in the recording: not written" for k in missing]
    for key, (v, note) in vals.items():
        lines.append(f"{key}: {v:.6e}  # {note}")
    lines.append(f"rostopic: {rostopic}")
    lines.append(f"update_rate: {_rate(report.fs)}  # [ Hz ] the recording's median rate")
    return "\n".join(lines) + "\n"


def openvins_yaml(report, *, rostopic: str = "/imu0", inflate: float = 1.0, calibration=None) -> tuple[str, list]:
    """OpenVINS's ``kalibr_imu_chain.yaml``; returns (text, warnings).  See the module docstring."""
    vals, missing = _values(report, inflate)
    if missing:
        raise ExportError(f"OpenVINS needs both sensors; this recording has no {missing[0].split('_')[0]} "
                          "(a log with the gyroscope gives both)")
    Ta, bias, warnings, source = np.eye(3), None, [], "identity (no calibration given)"
    if calibration is not None:
        Ta, bias, warnings = _accelerometer_intrinsics(calibration)
        source = "accelcal calibration: Ta = M"
    lines = ["%YAML:1.0", f"# OpenVINS IMU chain from accelcal noise ({report.source}); noise values as Kalibr's "
             "(continuous time, worst axis)", "# model: a_m = Ta R_IMUtoACC a + b_a + n_a,  w_m = Tw R_IMUtoGYRO w + "
             "Tg a + b_g + n_g  (OpenVINS estimates D = T^-1)", "imu0:", "  T_i_b:"]
    lines += [f"    - [{', '.join('1.0' if i == j else '0.0' for j in range(4))}]" for i in range(4)]
    for key, (v, note) in vals.items():
        lines.append(f"  {key}: {v:.6e}  # {note}")
    lines += [f"  rostopic: {rostopic}", "  time_offset: 0.0", f"  update_rate: {_rate(report.fs)}  # [ Hz ]",
              '  model: "kalibr"  # lower-triangular D (accelcal\'s M is lower triangular), R_IMUtoACC = I',
              "  # gyroscope: not calibrated by accelcal: Tw = I, R_IMUtoGYRO = I, Tg = 0"]
    lines += _matrix("Tw", np.eye(3)) + _matrix("R_IMUtoGYRO", np.eye(3))
    lines += [f"  # Ta: {source}"] + _matrix("Ta", Ta) + _matrix("R_IMUtoACC", np.eye(3))
    lines += _matrix("Tg", np.zeros((3, 3)))
    if bias is not None:
        lines.append("  # accelerometer bias b_a of the calibration (not a field: OpenVINS estimates it online) "
                     f"[ m/s^2 ]: [{', '.join(f'{b:.6g}' for b in bias)}]")
    return "\n".join(lines) + "\n", warnings


def _rate(fs: float) -> str:
    return repr(float(f"{fs:.6g}"))


def _matrix(name: str, m: np.ndarray) -> list[str]:
    return [f"  {name}:"] + [f"    - [ {', '.join(repr(float(v)) for v in row)} ]" for row in np.asarray(m, float)]


def _accelerometer_intrinsics(cal) -> tuple[np.ndarray, np.ndarray, list[str]]:
    if cal.unit != "m/s^2":
        raise ExportError(f"the calibration is in {cal.unit}; OpenVINS's Ta is dimensionless: calibrate data in m/s^2")
    if np.any(cal.input_offset != 0) or np.any(cal.input_sensitivity != 1):
        raise ExportError("the calibration converts raw counts nominally; OpenVINS's Ta needs a calibration of m/s^2 "
                          "data")
    warnings = []
    if cal.effects:
        warnings.append(f"the calibration's effects ({', '.join(e.id for e in cal.effects)}) have no place in "
                        "OpenVINS's file: only M (as Ta) is exported")
    return np.asarray(cal.M, float), np.asarray(cal.bias, float), warnings


__all__ = ["ExportError", "FORMAT", "FORMAT_VERSION", "KALIBR_KEYS", "avr_convention", "conversions",
           "exported_values", "kalibr_yaml", "openvins_yaml", "report_dict", "walk_unit"]
