"""KF-GINS's configuration: the initial IMU errors and the ``imunoise`` block.

KF-GINS's own equations (i2Nav-WHU/KF-GINS):

* ``src/kf-gins/gi_engine.cpp`` l. 157-171 (``imuCompensate``): ``dtheta -= gyrbias dt``,
  ``dvel -= accbias dt``, then ``dtheta /= (1 + gyrscale)``, ``dvel /= (1 + accscale)``,
  per axis: ``x = (raw - b) / (1 + s)`` — no misalignment.
* l. 46-56: the biases and scales are first-order Gauss-Markov processes of standard
  deviation ``σ`` and correlation time ``T`` (``F = -1/T``, l. 275-278), driven by a white
  noise of density ``2 σ² / T``; the angle and velocity random walks enter ``Qc`` squared.
* ``src/kf_gins.cpp`` l. 242-263, 342-348: the file's units — ``initgyrbias`` deg/h,
  ``initaccbias`` mGal, ``initgyrscale``/``initaccscale`` ppm, ``arw`` deg/√h, ``vrw``
  m/s/√h, ``gbstd`` deg/h, ``abstd`` mGal, ``gsstd``/``asstd`` ppm, ``corrtime`` h.

From accelcal: ``b``, ``s_i = M_ii - 1`` (``raw_i = M_ii f_i + b_i``) and ``s_i = 1/C_ii - 1``
for the gyroscope; ``arw``/``vrw`` the white noise density N; the bias std from the random
walk K, so that KF-GINS's driving noise ``2 σ² / T`` is the measured ``K²``: ``σ = K √(T/2)``
for the correlation time the user chooses (``--corr-time``, default 1 h); ``gsstd``/``asstd``
the calibration's standard errors of the scale factors.  Per axis: KF-GINS takes three
values each.  The data must be in the calibration's frame (KF-GINS: forward-right-down).
"""

from __future__ import annotations

import math

import numpy as np

from .base import Export, ExportError, accelerometer_si, diagonal_left_out, gyro_si, noise_value

MGAL = 1e-5  #: m/s² per mGal
DEG_H = math.pi / 180.0 / 3600.0  #: rad/s per deg/h


def _se_ppm(se: dict, what: str) -> np.ndarray:
    v = se.get("scale_factors")
    if v is None or not np.all(np.isfinite(np.asarray(v, float))):
        raise ExportError(f"KF-GINS needs the {what}'s scale-factor standard errors (gsstd/asstd), which this "
                          "calibration lacks: recalibrate with accelcal calibrate")
    return np.asarray(v, float) * 1e6


def _axes(v, fmt="{:.12g}") -> str:
    return "[ " + ", ".join(fmt.format(float(x)) for x in v) + " ]"


def write(inputs) -> Export:
    cal, noise = inputs.calibration, inputs.noise
    T_h = float(inputs.option("corr_time_h", 1.0))
    if not (T_h > 0 and math.isfinite(T_h)):
        raise ExportError(f"--corr-time must be a positive number of hours, got {T_h}")
    M, b = accelerometer_si(cal, "KF-GINS")
    C, bg, _ = gyro_si(cal, "KF-GINS")
    vals = {}
    for sensor in ("accelerometer", "gyroscope"):
        for what in ("noise_density", "random_walk"):
            v = noise_value(noise, sensor, what, "KF-GINS")
            if v is None:
                raise ExportError(f"KF-GINS needs the noise of both sensors; the noise report has no {sensor}")
            vals[sensor, what] = np.array(v.per_axis)
    k = math.sqrt(T_h * 3600.0 / 2.0)
    acc_se = cal.standard_errors_noise or cal.standard_errors
    lines = [f"# KF-GINS IMU errors and noise from accelcal ({inputs.option('source', 'a calibration')}, noise: "
             f"{noise.get('source')}); paste into your kf-gins.yaml",
             "# KF-GINS corrects x = (raw - bias) / (1 + scale) per axis (gi_engine.cpp imuCompensate)",
             f"initgyrbias: {_axes(bg / DEG_H)}    # [deg/h]",
             f"initaccbias: {_axes(b / MGAL)}    # [mGal]",
             f"initgyrscale: {_axes((1.0 / np.diag(C) - 1.0) * 1e6)}   # [ppm]",
             f"initaccscale: {_axes((np.diag(M) - 1.0) * 1e6)}   # [ppm]",
             "imunoise:",
             f"  arw: {_axes(np.degrees(vals['gyroscope', 'noise_density']) * 60.0)}    # [deg/sqrt(hr)] white noise N",
             f"  vrw: {_axes(vals['accelerometer', 'noise_density'] * 60.0)}    # [m/s/sqrt(hr)] white noise N",
             f"  gbstd: {_axes(vals['gyroscope', 'random_walk'] * k / DEG_H)}    # [deg/hr] K sqrt(T/2): "
             "KF-GINS's 2 sigma^2 / T is the measured random walk K^2",
             f"  abstd: {_axes(vals['accelerometer', 'random_walk'] * k / MGAL)}    # [mGal] K sqrt(T/2)",
             f"  gsstd: {_axes(_se_ppm(cal.gyro.standard_errors, 'gyroscope'))}    # [ppm] standard error of the "
             "calibration's scale",
             f"  asstd: {_axes(_se_ppm(acc_se, 'accelerometer'))}    # [ppm] standard error of the calibration's scale",
             f"  corrtime: {T_h:.6g}    # [hr] chosen (--corr-time); sets the bias std above"]
    return Export({"": "\n".join(lines) + "\n"}, diagonal_left_out(cal, "KF-GINS", gyro_scale=True),
                  [f"KF-GINS's bias std follows the chosen correlation time ({T_h:g} h): sigma = K sqrt(T/2)"])


__all__ = ["DEG_H", "MGAL", "write"]
