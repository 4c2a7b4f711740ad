"""OpenVINS's ``kalibr_imu_chain.yaml``: noise, and the IMU intrinsics ``Tw``, ``R_IMUtoGYRO``,
``Ta``, ``R_IMUtoACC``, ``Tg`` in either of OpenVINS's models.

OpenVINS's equations (rpng/open_vins):

* ``ov_msckf/src/core/VioManagerOptions.h`` l. 306-351: the file's matrices are read,
  ``Dw = Tw⁻¹``, ``Da = Ta⁻¹``, ``R_ACCtoIMU = R_IMUtoACCᵀ``, ``R_GYROtoIMU = R_IMUtoGYROᵀ``;
  the ``kalibr`` model keeps the lower triangle of ``Dw``, ``Da``, the ``rpng`` model the
  upper (l. 342-348; ``ov_msckf/src/state/State.h`` ``Dm`` l. 91-101) — a term outside
  it is dropped silently by OpenVINS, so the export puts none there.
* ``ov_msckf/src/state/Propagator.cpp`` l. 184-190: ``a_hat = R_ACCtoIMU Da (a_m - b_a)``,
  ``w_hat = R_GYROtoIMU Dw (w_m - b_g - Tg a_hat)``.

accelcal's ``f = M⁻¹ (a_m - b)``, ``ω = C (w_m - b_g - G f)`` then give:

* ``kalibr`` (IMU frame = accelcal's frame): ``Ta = M`` (``Da`` lower triangular),
  ``R_IMUtoACC = I``, ``R_GYROtoIMU Dw = C`` with ``Dw`` lower triangular (``Tw`` and
  ``R_IMUtoGYRO`` from the LQ decomposition of ``C⁻¹``), ``Tg = G``.
* ``rpng`` (``R_IMUtoGYRO = I``: the IMU frame is the gyroscope's, ``P`` times accelcal's,
  ``C = Pᵀ Dw`` a QR decomposition): ``Dw`` upper triangular, ``R_ACCtoIMU Da = P M⁻¹``
  (QR, ``Da`` upper triangular), ``Tg = G Pᵀ``.  The file states ``P``.

The biases are states OpenVINS estimates online (``b_a``, ``b_g``): written as comments.
"""

from __future__ import annotations

import numpy as np

from .base import Export, ExportError, accelerometer_si, effects_left_out, gyro_si, matrix_lines, noise_rate, rate_text
from .kalibr import noise_lines

MODELS = ("kalibr", "rpng")


def _qr_positive(A) -> tuple[np.ndarray, np.ndarray]:
    """``A = Q R``, ``R`` upper triangular with a positive diagonal, ``Q`` orthogonal."""
    Q, R = np.linalg.qr(np.asarray(A, float))
    s = np.sign(np.diag(R))
    s[s == 0] = 1.0
    return Q * s[None, :], s[:, None] * R


def _ql_positive(A) -> tuple[np.ndarray, np.ndarray]:
    """``A = Q L``, ``L`` lower triangular with a positive diagonal, ``Q`` orthogonal."""
    J = np.eye(3)[::-1]
    Q, R = _qr_positive(A @ J)          # A J = Q R  ->  A = Q (R J), and J R J is lower
    return Q @ J, J @ R @ J


def openvins_intrinsics(cal, model: str = "kalibr") -> dict:
    """``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg`` and ``P`` (accelcal's frame to the IMU frame)."""
    if model not in MODELS:
        raise ExportError(f"OpenVINS's intrinsic model is kalibr or rpng, got {model!r} (--model)")
    M, _ = accelerometer_si(cal, "OpenVINS")
    g = gyro_si(cal, "OpenVINS")
    C, G = (np.eye(3), np.zeros((3, 3))) if g is None else (g[0], g[2])
    if model == "kalibr":
        R_gi, Dw = _ql_positive(C)                  # C = R_GYROtoIMU Dw, Dw lower
        return {"Tw": np.linalg.inv(Dw), "R_IMUtoGYRO": R_gi.T, "Ta": M, "R_IMUtoACC": np.eye(3), "Tg": G,
                "P": np.eye(3)}
    Pt, Dw = _qr_positive(C)                        # C = P^T Dw, Dw upper
    P = Pt.T
    R_ai, Da = _qr_positive(P @ np.linalg.inv(M))   # P M^-1 = R_ACCtoIMU Da, Da upper
    return {"Tw": np.linalg.inv(Dw), "R_IMUtoGYRO": np.eye(3), "Ta": np.linalg.inv(Da), "R_IMUtoACC": R_ai.T,
            "Tg": G @ P.T, "P": P}


def write(inputs) -> Export:
    cal, noise = inputs.calibration, inputs.noise
    model = inputs.option("model", "kalibr")
    inflate = float(inputs.option("inflate", 1.0))
    values, missing = noise_lines(noise, inflate, "OpenVINS", indent="  ")
    if missing:
        raise ExportError("OpenVINS needs the noise of both sensors; the noise report has no "
                          f"{missing[0].split('_')[0]} (a log with the gyroscope gives both)")
    if cal is None:  # the noise alone (accelcal noise --openvins without --calibration)
        k = {"Tw": np.eye(3), "R_IMUtoGYRO": np.eye(3), "Ta": np.eye(3), "R_IMUtoACC": np.eye(3),
             "Tg": np.zeros((3, 3)), "P": np.eye(3)}
    else:
        k = openvins_intrinsics(cal, model)
    lines = ["%YAML:1.0", f"# OpenVINS IMU chain from accelcal: noise from {noise.get('source')}, intrinsics from "
             f"{inputs.option('source', 'the calibration') if cal is not None else 'no calibration (identity)'}",
             "# OpenVINS: a_hat = R_ACCtoIMU Da (a_m - b_a), w_hat = R_GYROtoIMU Dw (w_m - b_g - Tg a_hat), "
             "D = T^-1 (Propagator.cpp)", "imu0:", "  T_i_b:"]
    lines += [f"    - [{', '.join('1.0' if i == j else '0.0' for j in range(4))}]" for i in range(4)]
    lines += values
    lines += [f"  rostopic: {inputs.option('rostopic', '/imu0')}", "  time_offset: 0.0",
              f"  update_rate: {rate_text(noise_rate(noise))}  # [ Hz ]", f'  model: "{model}"']
    notes = ["the biases are in comments: OpenVINS estimates b_a and b_g online"]
    if model == "rpng":
        lines.append("  # rpng: the IMU frame is the gyroscope's; w_IMU = P w_accelcal with P = " + _mat(k["P"]))
        notes.append("rpng model: the IMU frame is the gyroscope's, rotated from accelcal's by P (in the file): "
                     "express the camera extrinsics in it")
    if cal is None:
        lines.append("  # no calibration given: Tw = I, R_IMUtoGYRO = I, Ta = I, R_IMUtoACC = I, Tg = 0")
    elif cal.gyro is None:
        lines.append("  # gyroscope: the calibration has no gyroscope: Tw = I, R_IMUtoGYRO = I, Tg = 0")
        notes.append("no gyroscope in the calibration: Tw = I, R_IMUtoGYRO = I, Tg = 0")
    for name in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):
        lines += matrix_lines(name, k[name])
    if cal is None:
        return Export({"": "\n".join(lines) + "\n"}, [], ["no calibration: identity intrinsics"])
    _, b = accelerometer_si(cal, "OpenVINS")
    lines.append(f"  # accelerometer bias b_a [ m/s^2 ] (a state, not a field): {_vec(b)}")
    g = gyro_si(cal, "OpenVINS")
    if g is not None:
        lines.append(f"  # gyroscope bias b_g [ rad/s ] (a state, not a field): {_vec(g[1])}")
    return Export({"": "\n".join(lines) + "\n"}, effects_left_out(cal, "OpenVINS"), notes)


def _vec(v) -> str:
    return "[" + ", ".join(f"{x:.9g}" for x in np.ravel(v)) + "]"


def _mat(m) -> str:
    return "[" + "; ".join(", ".join(f"{x:.17g}" for x in row) for row in np.asarray(m)) + "]"


__all__ = ["MODELS", "openvins_intrinsics", "write"]
