"""Kalibr's ``imu.yaml``: the noise model ``kalibr_calibrate_imu_camera --imu`` reads, and the
IMU intrinsics of Kalibr's ``scale-misalignment`` model in the keys Kalibr writes them
(``IccScaledMisalignedImu.ImuParameters.setIntrisicsMatrices``).

Kalibr's equations (ethz-asl/kalibr, ``aslam_offline_calibration/kalibr/python/
kalibr_imu_camera_calibration/IccSensors.py``, ``IccScaledMisalignedImu``)::

    alpha = M_a (C_i_b a_b) + b_a                                   (l. 999-1002)
    omega = M_g (C_gyro_i C_i_b w_b) + A (C_gyro_i C_i_b a_b) + b_g  (l. 1045-1051)

``M_a``, ``M_g`` lower triangular, ``C_gyro_i`` a rotation, ``A`` the g-sensitivity; ``A``
multiplies the specific force *in the gyroscope's frame*.  With the IMU frame ``i``
accelcal's accelerometer frame (``C_i_b = I`` for the reference IMU)::

    M_a = M,    M_g C_gyro_i = C⁻¹ (an LQ decomposition),    A = G C_gyro_iᵀ

Biases are states of Kalibr's spline, not fields of the file: they are written as
comments.  Noise: continuous-time densities and random walks, Kalibr's discrete noise
being ``density / sqrt(1 / update_rate)`` (``kalibr_common/ConfigReader.py`` l. 473, 491).
"""

from __future__ import annotations

import numpy as np

from .base import (Export, accelerometer_si, effects_left_out, gyro_si, matrix_lines, noise_rate, noise_value,
                   rate_text)

KEYS = (("accelerometer_noise_density", "accelerometer", "noise_density"),
        ("accelerometer_random_walk", "accelerometer", "random_walk"),
        ("gyroscope_noise_density", "gyroscope", "noise_density"),
        ("gyroscope_random_walk", "gyroscope", "random_walk"))


def kalibr_intrinsics(cal) -> dict:
    """Kalibr's ``accelerometers: M`` and ``gyroscopes: M, A, C_gyro_i`` (None for the gyro when absent)."""
    M, _ = accelerometer_si(cal, "Kalibr")
    g = gyro_si(cal, "Kalibr")
    if g is None:
        return {"M_a": M, "M_g": None, "A": None, "C_gyro_i": None}
    C, b, G = g
    # Imported here, where a gyro is exported: the package accelcal.gyro (its __init__ imports
    # the whole gyro calibration) cost `accelcal noise`, which writes no gyro model, 0.12 s of
    # its ~2.4 s of CPU (python -X importtime).
    from ..gyro.model import GyroModel

    k = GyroModel(C, b, G).to_kalibr()
    return {"M_a": M, "M_g": k["M"], "A": k["A"], "C_gyro_i": k["C_gyro_i"]}


def noise_lines(noise: dict, inflate: float, consumer: str, indent: str = "") -> tuple[list[str], list[str]]:
    """The four noise keys (worst axis, comment beside each) and the sensors the report lacks."""
    lines, missing = [], []
    for key, sensor, what in KEYS:
        v = noise_value(noise, sensor, what, consumer, inflate)
        if v is None:
            missing.append(key)
            continue
        lines.append(f"{indent}{key}: {v.value:.6e}  # {v.comment}")
    return lines, missing


def write(inputs) -> Export:
    """Kalibr's ``imu.yaml``: the noise, and with a calibration its intrinsics (``inputs.calibration``
    None: the noise alone, as ``accelcal noise --kalibr`` writes it)."""
    cal, noise = inputs.calibration, inputs.noise
    inflate = float(inputs.option("inflate", 1.0))
    values, missing = noise_lines(noise, inflate, "Kalibr")
    lines = [f"# Kalibr IMU model from accelcal: noise from {noise.get('source')}"
             + (f", intrinsics from {inputs.option('source', 'the calibration')}" if cal is not None else ""),
             "# noise: continuous time, IEEE Std 952 fit of the Allan deviation, worst axis (all axes in the comment)"]
    if noise.get("duration_s") is not None:
        lines.append(f"# the noise recording: {noise['duration_s'] / 3600:.3g} h at {noise_rate(noise):.6g} Hz")
    if inflate != 1:
        lines.append(f"# inflated x{inflate:g} (OpenVINS advises 10-20x for effects the model lacks)")
    lines += [f"# {key}: no {key.split('_')[0]} in the noise report: not written" for key in missing]
    lines += values
    lines += [f"rostopic: {inputs.option('rostopic', '/imu0')}",
              f"update_rate: {rate_text(noise_rate(noise))}  # [ Hz ] the noise recording's median rate"]
    if cal is None:
        return Export({"": "\n".join(lines) + "\n"}, [], [])
    lines += _intrinsics_lines(cal)
    notes = ["the biases are in comments: Kalibr estimates them as states"]
    if cal.gyro is None:
        notes.append("no gyroscope in the calibration: Kalibr's gyroscopes block is not written")
    return Export({"": "\n".join(lines) + "\n"}, effects_left_out(cal, "Kalibr"), notes)


def _intrinsics_lines(cal) -> list[str]:
    k = kalibr_intrinsics(cal)
    _, b = accelerometer_si(cal, "Kalibr")
    lines = ["# intrinsics: Kalibr's scale-misalignment model (IccSensors.py): alpha = M_a a + b_a,",
             "#   omega = M_g C_gyro_i w + A C_gyro_i a + b_g, in the frame of accelcal's accelerometer",
             "model: scale-misalignment", "accelerometers:"] + matrix_lines("M", k["M_a"])
    lines.append(f"  # bias b_a [ m/s^2 ] (a state of Kalibr's spline, not a field): {_vec(b)}")
    if k["M_g"] is None:
        return lines + ["# gyroscopes: the calibration has no gyroscope: not written"]
    lines += ["gyroscopes:"] + matrix_lines("M", k["M_g"]) + matrix_lines("A", k["A"]) \
        + matrix_lines("C_gyro_i", k["C_gyro_i"])
    bg = gyro_si(cal, "Kalibr")[1]
    return lines + [f"  # bias b_g [ rad/s ] (a state of Kalibr's spline, not a field): {_vec(bg)}"]


def _vec(v) -> str:
    return "[" + ", ".join(f"{x:.9g}" for x in np.ravel(v)) + "]"


__all__ = ["KEYS", "kalibr_intrinsics", "noise_lines", "write"]
