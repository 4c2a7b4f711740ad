"""VINS-Mono / VINS-Fusion's IMU noise keys: ``acc_n``, ``gyr_n``, ``acc_w``, ``gyr_w``, ``g_norm``.

VINS's own equations (HKUST-Aerial-Robotics/VINS-Fusion,
``vins_estimator/src/factor/integration_base.h``): the noise matrix holds ``ACC_N²``,
``GYR_N²`` (l. 31-34) and ``ACC_W²``, ``GYR_W²`` (l. 35-36); one step of length ``dt``
propagates it with ``V`` (l. 117-129: ``0.5 R dt`` on each of the two accelerometer samples
of the mid-point velocity increment, ``I dt`` on the bias walks), ``covariance = F P Fᵀ +
V noise Vᵀ`` (l. 134).  So the velocity increment of one step gets ``0.5 dt² ACC_N²``: the
variance of ``dt (a_0 + a_1) / 2`` for samples of standard deviation ``ACC_N``; and a bias
step gets ``dt² ACC_W²``, a random walk of density ``K`` giving ``K² dt``.  Hence, for a
noise density ``N`` and random walk ``K`` (continuous time) at ``f`` Hz::

    acc_n = N_a √f,  gyr_n = N_g √f,  acc_w = K_a √f,  gyr_w = K_g √f

(per-sample standard deviations, as VINS's config comments call them).  ``g_norm`` is
the gravity the calibration was fitted with.  VINS has no IMU intrinsics: the summary says
what feeding it raw data costs; apply the calibration to the data first.
"""

from __future__ import annotations

import math

from .base import APPLY_FIRST, Export, ExportError, intrinsics_left_out, noise_rate, noise_value

KEYS = (("acc_n", "accelerometer", "noise_density"), ("gyr_n", "gyroscope", "noise_density"),
        ("acc_w", "accelerometer", "random_walk"), ("gyr_w", "gyroscope", "random_walk"))


def write(inputs) -> Export:
    cal, noise = inputs.calibration, inputs.noise
    fs = noise_rate(noise)
    inflate = float(inputs.option("inflate", 1.0))
    lines = ["%YAML:1.0", f"# VINS-Mono / VINS-Fusion IMU parameters from accelcal (noise: {noise.get('source')}); "
             "paste into your config", f"# per-sample standard deviations at the recording's {fs:.6g} Hz: "
             "continuous-time value x sqrt(rate), as VINS's integration_base.h propagates them"]
    for key, sensor, what in KEYS:
        v = noise_value(noise, sensor, what, "VINS", inflate)
        if v is None:
            raise ExportError(f"VINS needs the noise of both sensors; the noise report has no {sensor}")
        unit = {("accelerometer", "noise_density"): "m/s^2", ("gyroscope", "noise_density"): "rad/s",
                ("accelerometer", "random_walk"): "m/s^3", ("gyroscope", "random_walk"): "rad/s^2"}[sensor, what]
        lines.append(f"{key}: {v.value * math.sqrt(fs):.6e}  # [ {unit} ] = {v.value:.6e} {v.unit} "
                     f"x sqrt({fs:.6g} Hz); "
                     + v.comment.split("] ", 1)[1])
    lines.append(f"g_norm: {cal.g:.6f}  # [ m/s^2 ] the gravity the calibration was fitted with")
    return Export({"": "\n".join(lines) + "\n"}, intrinsics_left_out(cal, "VINS"),
                  [f"VINS's values are per sample: they hold for data at {fs:.6g} Hz only", APPLY_FIRST])


__all__ = ["KEYS", "write"]
