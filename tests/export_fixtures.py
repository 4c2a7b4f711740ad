"""Calibrations and noise reports for the export tests: every term of accelcal's model non-zero."""

from __future__ import annotations

import numpy as np

from accelcal.calibration import calibration_class
from accelcal.gyro.model import GyroModel
from accelcal.gyro.result import GyroCalibration, GyroQuality

G0 = 9.80665


def gyro_quality(warnings=()) -> GyroQuality:
    return GyroQuality(n_motions=12, n_parameters=12, dof=24, chi2=20.0, p_value=0.7, excess=0.9,
                       residual_rms_deg=0.01, predicted_rms_deg=0.01, axis_turn_deg=(720.0, 720.0, 720.0),
                       warnings=tuple(warnings))


def full_calibration(*, seed: int = 3, g_sensitivity: bool = True, gyro: bool = True, raw_gyro_unit="rad/s",
                     diagonal: bool = False, gyro_scale: bool = True):
    """A calibration in m/s^2 with M full lower triangular, b, and a gyro with C (all nine), b, G non-zero.

    ``diagonal``: only what a per-axis autopilot holds (M diagonal; the gyro C = I/k, G = None
    unless ``gyro_scale``: C diagonal)."""
    rng = np.random.default_rng(seed)
    M = np.tril(np.eye(3) + 0.01 * rng.standard_normal((3, 3)))
    M[np.diag_indices(3)] = 1.0 + np.array([0.012, -0.008, 0.015])
    b = np.array([0.11, -0.07, 0.19])
    if diagonal:
        M = np.diag(np.diag(M))
    k = 1.0 if raw_gyro_unit == "rad/s" else np.pi / 180.0
    C = (np.eye(3) + 0.006 * rng.standard_normal((3, 3))) * k
    G = 1e-4 * rng.standard_normal((3, 3)) / k if g_sensitivity else None
    if diagonal:
        C = np.diag(np.diag(C)) if gyro_scale else np.eye(3) * k
        G = None
    bg = np.array([0.004, -0.011, 0.007]) / k
    model = GyroModel(C=C, bias=bg, g_sensitivity=G, raw_unit=raw_gyro_unit)
    gcal = calibration_class("gyro_iterative", GyroCalibration)(
        model=model, standard_errors={"scale_factors": np.array([2e-4, 3e-4, 2.5e-4])}, quality=gyro_quality(),
        settings={"nominal": k})
    se = {"bias": np.full(3, 1e-3), "scale_factors": np.array([1e-4, 1.2e-4, 0.9e-4]),
          "nonorthogonality_deg": np.full(3, 0.01)}
    return calibration_class("full_lls")(bias=b, M=M, g=9.81, unit="m/s^2", input_unit="m/s^2", standard_errors=se,
                                         gyro=gcal if gyro else None, provenance={"recording": "session.csv"})


def noise_report(*, gyro: bool = True, fs: float = 200.0) -> dict:
    """A noise report's JSON as accelcal noise writes it (the keys exports read)."""
    def axes(n, k):
        return {ax: {"noise_density": {"value": n * (1 + 0.1 * i), "interval": [0.9 * n, 1.1 * n]},
                     "random_walk": {"value": k * (1 + 0.2 * i), "interval": [0.5 * k, 2 * k], "upper_bound": i == 2}}
                for i, ax in enumerate("xyz")}
    sensors = {"accelerometer": {"unit": "m/s^2", "axes": axes(1.2e-3, 4e-5)}}
    if gyro:
        sensors["gyroscope"] = {"unit": "rad/s", "axes": axes(8e-5, 2e-6)}
    return {"format": "accelcal-noise", "format_version": 1, "source": "static.bag", "fs_hz": fs, "level": 0.95,
            "duration_s": 7200.0, "sensors": sensors}
