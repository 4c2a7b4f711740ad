"""Do the gyro's 95 % intervals cover the truth 95 % of the time when the bias wanders?

Simulated sessions with what real ones show (:func:`accelcal.gyro.simulate.simulate_recording`):
a bias that walks (rate random walk), a rotation error per motion proportional to its
angle, per-rest accelerometer offsets, white noise — at sizes measured on the IMU-TK fork
and SNU sessions (:mod:`accelcal.gyro.noise`'s estimates there: walk PSD 1e-8-2e-7
rad²/s³, per-motion relative error 0.1-0.4 %, white noise 6-7e-4 rad/s per sample at 100
Hz), an accelerometer with 5 mrad errors calibrated (full LLS) from the same 17 rests.
Each trial is calibrated as :func:`accelcal.gyro.calibrate.calibrate_gyro` calibrates a
session (the known rests as poses, a perfect accelerometer, or with ``fitted_accelerometer``
one with its own errors calibrated from the same rests: the gyro's frame is then the
fitted one, whose uncertainty the ± carry), prepared once
(:func:`accelcal.gyro.calibrate.prepare_session`) and fitted once with the noise model
and once with the rest noise alone (the ± scaled by ``max(1, excess)``, the former way);
a parameter is covered when ``|estimate - truth|`` is within its 95 % interval
(:meth:`accelcal.gyro.result.GyroCalibration.interval95`: ``t(0.975, ν) s.e.`` with the
noise model, ``1.96 s.e.`` without).

Tables: :func:`coverage` (one row per trial, model and parameter), :func:`summary`
(coverage per parameter with its binomial standard error, and pooled per kind).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.calibration.fitting import calibrate_poses
from accelcal.gyro.calibrate import prepare_session
from accelcal.gyro.model import GyroModel
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording
from accelcal.static import static_poses_from_intervals

#: The simulated sessions (sizes from the real ones, module docstring).
SESSION = {"n_motions": 16, "angle_deg": 90.0, "peak_rate_dps": 150.0, "fs": 100.0, "rest_s": 1.5,
           "init_rest_s": 5.0, "acc_noise": 0.03, "gyro_noise": 7e-4, "bias_walk_psd": 1e-7,
           "motion_rel_std": 2e-3, "rest_offset_std": 0.0, "fitted_accelerometer": True}
PARAMETERS = ("s_x", "s_y", "s_z", "T_xy", "T_xz", "T_yx", "T_yz", "T_zx", "T_zy")


class _Identity:
    """A perfect accelerometer calibration (the simulated accelerometer has M = I, no bias)."""

    @staticmethod
    def apply(z):
        return np.asarray(z, float)


def _values(model):
    C = model.C
    T = model.T
    return np.array([C[0, 0] - 1, C[1, 1] - 1, C[2, 2] - 1, T[0, 1], T[0, 2], T[1, 0], T[1, 2], T[2, 0], T[2, 1]])


def _ses(cal, half=False):
    se = {k: cal.interval95(k) for k in ("scale_factors", "T")} if half else cal.standard_errors
    return np.concatenate([se["scale_factors"], [se["T"][i, j] for i in range(3) for j in range(3) if i != j]])


def trial(rng: np.random.Generator, session: dict = SESSION) -> list[dict]:
    """One simulated session calibrated with and without the noise model (module docstring)."""

    session = dict(session)
    fitted = session.pop("fitted_accelerometer", False)
    C = random_gyro_matrix(rng, 0.01, 0.5)
    M = np.eye(3)
    if fitted:  # an accelerometer with its own errors, calibrated from the same rests (full LLS)
        M = np.tril(np.eye(3) + rng.normal(0, 5e-3, (3, 3)))
    sim = simulate_recording(rng, C=C, gyro_bias=rng.normal(0, 0.01, 3), M=M, **session)
    poses = static_poses_from_intervals(sim["t"], sim["acc"], sim["rest_intervals"])
    accel = _Identity()
    if fitted:

        accel = calibrate_poses(poses, sim["g"], "full_lls", unit="m/s^2")
    truth = _values(GyroModel(C, np.zeros(3)))
    rows = []
    prepared = prepare_session(sim["t"], sim["gyro"], poses, accel, g_sensitivity=False)  # once for both models
    for model in (True, False):
        cal = prepared.fit(noise_model=model)
        est, se, half = _values(cal.model), _ses(cal), _ses(cal, half=True)
        for p, e, s, w, t in zip(PARAMETERS, est, se, half, truth):
            rows.append({"noise_model": model, "parameter": p, "error": e - t, "se": s, "half_width": w,
                         "covered": bool(abs(e - t) <= w)})
    return rows


def coverage(n_trials: int, seed: int, session: dict = SESSION) -> pd.DataFrame:
    """One row per trial, model (with / without the noise model) and parameter."""
    rows = []
    for k, rng in enumerate(np.random.default_rng(seed).spawn(n_trials)):
        rows += [{"trial": k, **r} for r in trial(rng, session)]
    return pd.DataFrame(rows)


def summary(df: pd.DataFrame) -> pd.DataFrame:
    """Coverage per model and parameter, and pooled per kind (``scale``, ``misalignment``, ``all``),
    with the binomial standard error and the RMS of error / s.e."""
    rows = []
    kinds = {"scale": [p for p in PARAMETERS if p.startswith("s_")],
             "misalignment": [p for p in PARAMETERS if p.startswith("T_")], "all": list(PARAMETERS)}
    for model, d in df.groupby("noise_model", sort=False):
        groups = [(p, d[d.parameter == p]) for p in PARAMETERS] + [(k, d[d.parameter.isin(v)]) for k, v in kinds.items()]
        for name, g in groups:
            c = float(g.covered.mean())
            rows.append({"noise_model": bool(model), "parameter": name, "n": len(g), "coverage": c,
                         "coverage_se": float(np.sqrt(c * (1 - c) / len(g))),
                         "rms_z": float(np.sqrt(np.mean((g.error / g.se) ** 2)))})
    return pd.DataFrame(rows)


__all__ = ["PARAMETERS", "SESSION", "coverage", "summary", "trial"]
