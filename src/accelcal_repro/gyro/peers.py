"""accelcal's gyro calibration beside the peers', parameter by parameter and by one figure of
merit none of them optimises.

Peers, per session:

* ``imutk_run`` — IMU-TK built from source and run outside the workflow (``tools/gyro_peers.py``
  records it: ``imutk.json``; the workflow reads it when ``gyro.imutk_run`` names it): its
  example app on the Xsens files, its calls with the sessions' settings on the others;
* ``imutk_published`` — the IMU-TK fork's own ``test_imu_{acc,gyro}.calib`` (data1-4);
* ``factory`` — the Xsens unit's data-sheet values quoted in the data README;
* ``imucal`` — imucal's Ferraris calibration of its example session, run as a package
  (:mod:`.ferraris_sessions`).

Frames.  Each calibration expresses rates in *its* accelerometer frame: accelcal's makes
the accelerometer's sensing matrix lower triangular (x along the x accelerometer),
IMU-TK's upper triangular (z along z).  To compare, every calibration is carried into
accelcal's convention with the rotation its own accelerometer defines
(:func:`accelcal.gyro.model.frame_rotation`); what remains is the physics.  The factory
values are given to two decimals (misalignments ±0.005) and their convention (``raw = S M
ω``, rows of ``M`` the axes) is the MATLAB port's reading.

Parameters compared: the scale ``K = diag(C)`` (as counts per rad/s for counts, or as the
relative scale factor), the six off-diagonals of ``T = C K⁻¹`` [mrad], the bias; the
difference is given in accelcal's standard errors.

Figure of merit: the angle between each rest's gravity direction and the previous rest's
carried over by the calibrated, integrated gyro (Magnus-4), per motion, RMS over a session,
on the same rests for everyone (the gyro's own, :func:`accelcal.gyro.rests.gyro_rests`), each
calibration with its own accelerometer and either its own bias (``own_bias``: as published)
or the session's rest bias (``rest_bias``: the scale and misalignment alone).  accelcal's rows
carry its trust verdict and reasons (:func:`trust_columns`), so that the figure marks a
poorly determined calibration beside well-determined ones.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from accelcal.gyro.calibrate import evaluate_model
from accelcal.gyro.model import GyroModel, frame_rotation
from accelcal.gyro.rests import bias_series, fit_bias, gyro_rests

#: Xsens MTi data-sheet values (data README): raw = S M x + offset.
XSENS_FACTORY = {
    "acc_scale": np.diag([415.0, 413.0, 415.0]),
    "acc_misal": np.array([[1.00, 0.00, -0.01], [0.01, 1.00, 0.01], [0.02, 0.01, 1.00]]),
    "acc_offset": np.array([33123.0, 33276.0, 32360.0]),
    "gyro_scale": np.diag([4778.0, 4758.0, 4766.0]),
    "gyro_misal": np.array([[1.00, -0.01, -0.02], [0.00, 1.00, 0.04], [-0.01, 0.01, 1.00]]),
    "gyro_offset": np.array([32768.0, 32466.0, 32485.0]),
}


class AffineAccel:
    """A peer's accelerometer: ``f = A⁻¹ (z - b)`` with its sensing matrix ``A`` (raw per m/s²)."""

    def __init__(self, sensing, bias):
        self.sensing, self.bias = np.asarray(sensing, float), np.asarray(bias, float)

    def apply(self, z):
        return np.linalg.solve(self.sensing, (np.asarray(z, float) - self.bias).T).T


def read_calib(path: Path) -> dict:
    """IMU-TK's ``.calib``: T (3x3), blank, K (3x3), blank, b (3)."""
    rows = [[float(v) for v in line.split()] for line in Path(path).read_text().splitlines() if line.strip()]
    return {"T": np.array(rows[0:3]), "K": np.array(rows[3:6]), "b": np.array([r[0] for r in rows[6:9]])}


def _imutk_pair(acc: dict, gyro: dict, raw_unit: str):
    A = np.linalg.inv(np.asarray(acc["T"]) @ np.asarray(acc["K"]))
    return AffineAccel(A, acc["b"]), GyroModel.from_imutk(gyro["T"], gyro["K"], gyro["b"], raw_unit)


def peer_calibrations(spec, raw_unit: str, paths: dict, imutk_run: dict | None = None) -> dict:
    """``{peer: (accelerometer, GyroModel)}`` available for the session ``spec``, each in its own frame.

    ``imutk_run``: the ``runs`` of ``tools/gyro_peers.py``'s ``imutk.json`` (None: not given)."""
    out = {}
    rec = (imutk_run or {}).get(spec.name)
    if rec and rec.get("returncode") == 0 and "gyro" in rec:
        out["imutk_run"] = _imutk_pair(rec["acc"], rec["gyro"], raw_unit)
    if spec.calib:
        p = paths[spec.dataset]
        out["imutk_published"] = _imutk_pair(read_calib(p[spec.calib[0]]), read_calib(p[spec.calib[1]]), raw_unit)
    if spec.name == "xsens":
        f = XSENS_FACTORY
        out["factory"] = (AffineAccel(f["acc_scale"] @ f["acc_misal"], f["acc_offset"]),
                          GyroModel(np.linalg.inv(f["gyro_scale"] @ f["gyro_misal"]), f["gyro_offset"],
                                    raw_unit=raw_unit))
    return out


def to_accelcal_frame(accel, model: GyroModel) -> GyroModel:
    """The gyro model in accelcal's frame convention, by the rotation its own accelerometer defines."""
    return model.rotated(frame_rotation(accel.sensing))


def compare_parameters(session: str, ours, peers: dict) -> pd.DataFrame:
    """Rows: session, peer, parameter, ours, ours_se, peer, diff_in_se (ours: a GyroCalibration)."""
    m, se = ours.model, ours.standard_errors
    counts = m.raw_unit == "counts"
    nominal = ours.nominal

    def params(model):
        out = {}
        k = np.diag(model.C)
        for a in range(3):
            out[f"K_{'xyz'[a]}"] = 1.0 / k[a] if counts else k[a] / nominal - 1.0
        T = model.T
        for i in range(3):
            for j in range(3):
                if i != j:
                    out[f"T_{'xyz'[i]}{'xyz'[j]}"] = 1e3 * T[i, j]
        for a in range(3):
            out[f"b_{'xyz'[a]}"] = model.bias[a]
        return out

    k, ke = np.diag(m.C), np.diag(se["C"])
    ses = {}
    for a in range(3):
        ses[f"K_{'xyz'[a]}"] = ke[a] / k[a] ** 2 if counts else ke[a] / nominal
        ses[f"b_{'xyz'[a]}"] = se["bias"][a]
    for i in range(3):
        for j in range(3):
            if i != j:
                ses[f"T_{'xyz'[i]}{'xyz'[j]}"] = 1e3 * se["T"][i, j]
    mine = params(m)
    rows = []
    for peer, (accel, model) in peers.items():
        theirs = params(to_accelcal_frame(accel, model))
        for p, v in mine.items():
            rows.append({"session": session, "peer": peer, "parameter": p, "ours": v, "ours_se": ses[p],
                         "peer_value": theirs[p], "diff_in_se": (theirs[p] - v) / ses[p]})
    return pd.DataFrame(rows)


def figure_of_merit(session: str, rec, poses, ours_acc, ours, peers: dict,
                    integrator: str = "magnus4") -> pd.DataFrame:
    """Per calibration: RMS and median per-motion angle [deg] on the session's rests (module
    docstring); ``rec`` the session's Recording (its gyro in the peers' raw unit)."""

    rs = gyro_rests(rec.t, rec.gyro, poses, ours_acc, rec.acc).stats  # the rests evaluate_model uses
    rest_b = bias_series(fit_bias(rs, "interpolated"), rs, rec.t)
    cals = {"accelcal": (ours_acc, ours.model), **peers}
    rows = []
    for name, (accel, model) in cals.items():
        for kind in ("own_bias", "rest_bias"):
            G = model.g_sensitivity if kind == "own_bias" else None
            bias = model.bias if kind == "own_bias" else 0.0
            gyro = rec.gyro if kind == "own_bias" else rec.gyro - rest_b
            ev, ms = evaluate_model(rec.t, gyro, poses, accel, model.C, bias, integrator=integrator, g_sensitivity=G,
                                    acc=rec.acc)
            # real motions only (not two rests that overlap); none lost by the integration (> 30 deg)
            used = (ms.stops - ms.starts > 1) & (np.linalg.norm(ev.r, axis=1) < 0.5)
            a = ev.angles_deg[used]
            rows.append({"session": session, "calibration": name, "bias": kind, "motions": int(used.sum()),
                         "rms_deg": float(np.sqrt(np.mean(a ** 2))), "median_deg": float(np.median(a)),
                         "max_deg": float(a.max()), "noise_rms_deg": float(np.sqrt(np.mean(ev.predicted_deg ** 2))),
                         **trust_columns(ours if name == "accelcal" else None)})
    return pd.DataFrame(rows)


def trust_columns(cal) -> dict:
    """``verdict`` and ``reasons`` of a calibration's trust (:attr:`accelcal.gyro.result.GyroQuality.verdict`);
    empty for a peer's calibration, which carries no evidence of its own."""
    if cal is None:
        return {"verdict": "", "reasons": ""}
    return {"verdict": cal.quality.verdict, "reasons": "; ".join(cal.quality.reasons)}


__all__ = ["AffineAccel", "XSENS_FACTORY", "compare_parameters", "figure_of_merit", "peer_calibrations",
           "read_calib", "to_accelcal_frame", "trust_columns"]
