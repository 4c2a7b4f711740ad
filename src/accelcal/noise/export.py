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

With a calibration (``accelcal noise --calibration``), both files also carry its IMU
intrinsics, accelerometer and gyroscope, as :mod:`accelcal.export.kalibr` and
:mod:`accelcal.export.openvins` write them (each consumer's own equations); without one,
OpenVINS's intrinsics are the identity.

``allan_variance_ros`` convention (optional): a line of slope −½ fitted in log–log to
the Allan deviations at τ < 10 s and read at τ = 1 s, a line of slope +½ fitted to all
of them and read at τ = 3 s, and the minimum Allan deviation as "bias instability" —
on this report's octave τ grid, not that tool's denser grid, so its numbers differ
from that tool's by the grid as well.
"""

from __future__ import annotations

import math

import numpy as np

from ..export import kalibr, openvins
from ..export.api import export
from ..export.base import ExportError, ExportInputs
from ..jsonsafe import json_safe
from .terms import TERMS, NoiseModelError, exported_term

FORMAT = "accelcal-noise"
FORMAT_VERSION = 1
AVR_WHITE_TAU_MAX = 10.0


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
        axes[ax] = {"terms": {k: {**e.to_dict(), "unit": TERMS[k].unit_of(s.unit)} for k, e in terms.items()},
                    **exported_values(s, j), "allan_variance_ros": avr_convention(a.taus, a.adev[:, j]),
                    "adev_floor": {"value": adev_floor(terms), "unit": s.unit,
                                   "meaning": "flicker floor of the fit, 0.664 B"},
                    "conversions": conversions(s.sensor, s.unit, terms)}
    return {"unit": s.unit, "taus_s": a.taus, "m": a.m, "n_terms": a.n_terms, "adev": a.adev,
            "adev_interval": s.adev_interval, "edf": s.edf, "adev_model": s.model_adev(a.taus), "axes": axes}


def adev_floor(terms: dict) -> float:
    """The fit's Allan-deviation floor: the coefficient of the term that has one (flicker's 0.664 B)
    times its :attr:`~accelcal.noise.terms.NoiseTerm.floor_factor`."""
    floors = [TERMS[k].floor_factor * e.value for k, e in terms.items() if TERMS[k].floor_factor is not None]
    if len(floors) != 1:
        raise NoiseModelError(f"the report needs one term with an Allan-deviation floor in the fit, got {len(floors)}")
    return floors[0]


def exported_values(s, j: int) -> dict:
    """Noise density and random walk of axis ``j`` as the exports write them (see the module docstring):
    the coefficients of the terms :attr:`~accelcal.noise.terms.NoiseTerm.exported_as` names."""
    t = s.terms[j]
    nd, walk = exported_term("noise_density"), exported_term("random_walk")
    w, k = t[nd.id], t[walk.id]
    rw = k.value if k.resolved else k.hi
    u = s.unit
    return {"noise_density": {"value": w.value, "interval": [w.lo, w.hi], "unit": nd.unit_of(u)},
            "random_walk": {"value": rw, "interval": [k.lo, k.hi], "unit": walk.unit_of(u),
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
    n, b = terms[exported_term("noise_density").id].value, adev_floor(terms)
    if unit == "m/s^2":
        return {"velocity_random_walk_m_s_sqrt_h": 60.0 * n, "bias_instability_floor_mg": 1e3 * b / 9.80665}
    if unit == "rad/s":
        return {"angle_random_walk_deg_sqrt_h": 60.0 * math.degrees(n), "bias_instability_floor_deg_h":
                3600.0 * math.degrees(b), "bias_instability_floor_deg_s": math.degrees(b)}
    return {}


# --------------------------------------------------------------------------- Kalibr and OpenVINS


def kalibr_yaml(report, *, rostopic: str = "/imu0", inflate: float = 1.0) -> str:
    """Kalibr's ``imu.yaml`` of the noise alone (:mod:`accelcal.export.kalibr`)."""

    return kalibr.write(ExportInputs(None, report_dict(report), {"rostopic": rostopic, "inflate": inflate})).files[""]


def openvins_yaml(report, *, rostopic: str = "/imu0", inflate: float = 1.0, calibration=None,
                 model: str = "kalibr") -> tuple[str, list]:
    """OpenVINS's ``kalibr_imu_chain.yaml`` (:mod:`accelcal.export.openvins`); returns (text, warnings):
    the terms the file leaves out."""

    inputs = ExportInputs(calibration, report_dict(report), {"rostopic": rostopic, "inflate": inflate, "model": model})
    out = openvins.write(inputs) if calibration is None else export("openvins", inputs)
    return out.files[""], [x.line() for x in out.left_out]


def calibrated_kalibr_yaml(report, calibration, *, rostopic: str = "/imu0", inflate: float = 1.0) -> tuple[str, list]:
    """Kalibr's ``imu.yaml`` with the calibration's intrinsics (:mod:`accelcal.export.kalibr`); (text, warnings)."""

    out = export("kalibr", ExportInputs(calibration, report_dict(report), {"rostopic": rostopic, "inflate": inflate}))
    return out.files[""], [x.line() for x in out.left_out]


__all__ = ["ExportError", "calibrated_kalibr_yaml", "FORMAT", "FORMAT_VERSION", "adev_floor", "avr_convention",
           "conversions", "exported_values", "kalibr_yaml", "openvins_yaml", "report_dict"]
