"""The two Ferraris sessions: imucal's example (beside imucal itself) and the CTU rig's rotations.

imucal's session (``../shared/data/imucal_ferraris``): six static holds and three turns of
360 deg, with its section list, read by accelcal's imucal reader at its sampling rate
(:data:`accelcal.formats.imucal.IMUCAL_RATE_HZ`, 102.4 Hz: imucal's own example says so
since commit 278a2c3; at the 204.8 Hz the data README states, each turn integrates to
about 180 deg).  accelcal's Ferraris fit runs twice: with the nominal axes (imucal's
assumption, comparable parameter by parameter) and with the axes measured by the
accelerometer.  Six holds do not determine accelcal's full accelerometer model (it needs
ten poses; the bias-only model leaves imucal's 2 % scale errors in the directions), so the
accelerometer here is imucal's own Ferraris fit of the holds, for every gyro calibration
alike.  Figure of merit: the five motions between the holds (gravity turns by 90 or 180
deg).

CTU (``../shared/data/ctu_ferraris``): three gyro-only records, one turn each, the offsets
from samples 1-2000 and the integration windows and reference angles of the repository's
script (361.338, 367.160, 363.6703 deg): nominal axes only; no peer result is published.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from accelcal.gyro.ferraris import REST_SECTIONS, calibrate_ferraris_session, fit_ferraris
from accelcal.gyro.model import GyroModel
from accelcal.gyro.rests import rest_noise, rest_statistics

from .peers import AffineAccel
from .sessions import DATA

CTU_WINDOWS = {"x": (2420, 2910), "y": (2565, 3120), "z": (2975, 3500)}  # 1-based, inclusive
CTU_ANGLES = (361.338, 367.160, 363.6703)
CTU_RATE_HZ = 100.0


def imucal_session():
    """Time [s], acc [m/s²], gyro [deg/s, imucal's unit] and the section list of imucal's example."""
    from accelcal.formats import read

    d = DATA / "imucal_ferraris"
    rec = read(d / "example_ferraris_session.csv")
    raw = json.loads((d / "example_ferraris_session_list.json").read_text())
    sec = {k: (v["start"], v["end"]) for k, v in raw.items()}
    return rec.t, rec.acc, np.rad2deg(rec.gyro), sec


def _params(name: str, model: GyroModel, se: dict | None) -> list[dict]:
    rows = []
    for a in range(3):
        rows.append({"calibration": name, "parameter": f"s_{'xyz'[a]}", "unit": "ppm",
                     "value": 1e6 * model.scale_factors()[a],
                     "se": np.nan if se is None else 1e6 * se["scale_factors"][a]})
    for i in range(3):
        for j in range(3):
            if i != j:
                rows.append({"calibration": name, "parameter": f"T_{'xyz'[i]}{'xyz'[j]}", "unit": "mrad",
                             "value": 1e3 * model.T[i, j], "se": np.nan if se is None else 1e3 * se["T"][i, j]})
    return rows


def imucal_comparison(peers_json) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Parameters (ours ± s.e. with nominal and with measured axes, imucal's) and the figure of merit."""
    from accelcal.gyro.calibrate import evaluate_model
    from accelcal.static import static_poses_from_intervals

    t, acc, gyro, sec = imucal_session()
    rests = np.array(sorted(sec[k] for k in REST_SECTIONS))
    poses = static_poses_from_intervals(t, acc, rests)
    im = json.loads(peers_json.read_text())["calibration"]
    acc_cal = AffineAccel(np.asarray(im["K_a"]) @ np.asarray(im["R_a"]), im["b_a"])
    nominal = calibrate_ferraris_session(t, gyro, sec)
    measured = calibrate_ferraris_session(t, gyro, sec, accel=acc_cal, acc=acc)
    imucal = GyroModel.from_imucal(im["K_g"], im["R_g"], im["b_g"], None)
    rows = _params("accelcal_nominal_axes", nominal.model, nominal.standard_errors) + \
        _params("accelcal_measured_axes", measured.model, measured.standard_errors) + _params("imucal", imucal, None)
    params = pd.DataFrame(rows)
    ref = params[params.calibration == "accelcal_nominal_axes"].set_index("parameter")
    params["diff_in_se_vs_nominal_axes"] = [(v - ref.loc[p, "value"]) / ref.loc[p, "se"]
                                            for p, v in zip(params.parameter, params.value)]
    foms = []
    for name, accel, model in (("accelcal_nominal_axes", acc_cal, nominal.model),
                               ("accelcal_measured_axes", acc_cal, measured.model), ("imucal", acc_cal, imucal)):
        ev, _ = evaluate_model(t, gyro, poses, accel, model.C, model.bias)
        foms.append({"session": "imucal_ferraris", "calibration": name, "motions": len(ev.r),
                     "rms_deg": float(np.sqrt(np.mean(ev.angles_deg ** 2))), "max_deg": float(ev.angles_deg.max()),
                     "noise_rms_deg": float(np.sqrt(np.mean(ev.predicted_deg ** 2)))})
    return params, pd.DataFrame(foms)


def ctu_calibration() -> pd.DataFrame:
    """accelcal's Ferraris fit of the CTU rotations: parameters ± s.e. (nominal axes)."""
    import scipy.io

    m = scipy.io.loadmat(DATA / "ctu_ferraris" / "measured_angular_rates.mat")
    segs, yv, bv = [], [], []
    for ax in "xyz":
        d = np.asarray(m[f"{ax}_rotation"], float)
        t = np.arange(len(d)) / CTU_RATE_HZ
        rs = rest_statistics(t, d, [[0, 2000]])
        a, e = CTU_WINDOWS[ax]
        segs.append(d[a - 1:e] - rs.means[0])
        yv.append(rest_noise(rs))
        bv.append(rs.mean_std[0] ** 2)
    fit = fit_ferraris(segs, 1.0 / CTU_RATE_HZ, CTU_ANGLES, nominal=np.pi / 180, y_var=np.mean(yv, axis=0),
                       bias_var=np.mean(bv, axis=0))
    model = GyroModel(fit.C, np.zeros(3), raw_unit="deg/s")
    se_C = np.sqrt(np.diag(fit.cov)).reshape(3, 3)
    Jt = np.zeros((9, 9))
    for i in range(3):
        for j in range(3):
            if i != j:
                Jt[3 * i + j, 3 * i + j] = 1.0 / fit.C[j, j]
                Jt[3 * i + j, 4 * j] = -fit.C[i, j] / fit.C[j, j] ** 2
    se = {"scale_factors": np.diag(se_C) / (np.pi / 180),
          "T": np.sqrt(np.diag(Jt @ fit.cov @ Jt.T)).reshape(3, 3)}
    out = pd.DataFrame(_params("accelcal_ctu", model, se))
    out["nominal_angle_deg"] = np.nan
    for j, ax in enumerate("xyz"):
        out.loc[out.parameter == f"s_{ax}", "nominal_angle_deg"] = fit.nominal_angles_deg[j]
    return out


__all__ = ["CTU_ANGLES", "CTU_WINDOWS", "ctu_calibration", "imucal_comparison", "imucal_session"]
