"""The two Ferraris sessions: imucal's example (beside imucal itself) and the CTU rig's rotations.

imucal's session (``../shared/data/imucal_ferraris``): six static holds and three turns of
360 deg, with its section list, read by accelcal's imucal reader at its sampling rate
(:data:`accelcal.formats.imucal.IMUCAL_RATE_HZ`, 102.4 Hz: imucal's own example says so
since commit 278a2c3; at the 204.8 Hz the data README states, each turn integrates to
about 180 deg).  accelcal's Ferraris fit is the command line's (:mod:`.sessions`: six
holds allow only a bias-only accelerometer, whose scale errors would tilt measured axes,
so the rotation axes are the nominal ones, imucal's assumption); beside it, the same fit
with the axes measured by imucal's own accelerometer calibration.  imucal runs as a
package (:func:`run_imucal`, its example's settings).  Figure of merit: the five motions
between the holds (gravity turns by 90 or 180 deg), every gyro with imucal's
accelerometer (one frame for all).

CTU (``../shared/data/ctu_ferraris``): three gyro-only records, one turn each, the offsets
from samples 1-2000 and the integration windows and reference angles of the repository's
script (361.338, 367.160, 363.6703 deg): nominal axes only; no peer result is published.
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from accelcal.gyro.ferraris import calibrate_ferraris_session, fit_ferraris, standard_errors
from accelcal.gyro.model import RAW_UNITS, GyroModel
from accelcal.gyro.rests import rest_noise, rest_statistics

from .peers import AffineAccel, trust_columns

CTU_WINDOWS = {"x": (2420, 2910), "y": (2565, 3120), "z": (2975, 3500)}  # 1-based, inclusive
CTU_ANGLES = (361.338, 367.160, 363.6703)
CTU_RATE_HZ = 100.0
#: imucal's gravity (its default and example's).
IMUCAL_GRAV = 9.81


def run_imucal(session_csv, section_list_json) -> dict:
    """imucal's ``FerrarisCalibration`` of its example session, with its example's settings
    (at :data:`accelcal.formats.imucal.IMUCAL_RATE_HZ`); its parameters and wall time."""
    import imucal
    from imucal import FerrarisCalibration, ferraris_regions_from_section_list

    from accelcal.formats.imucal import IMUCAL_RATE_HZ

    data = pd.read_csv(session_csv, header=0, index_col=0)
    sections = pd.read_json(section_list_json).T
    t0 = time.perf_counter()
    regions = ferraris_regions_from_section_list(data, sections)
    cal = FerrarisCalibration(grav=IMUCAL_GRAV).compute(regions, sampling_rate_hz=IMUCAL_RATE_HZ,
                                                        from_acc_unit="m/s^2", from_gyr_unit="deg/s")
    wall = time.perf_counter() - t0
    out = {k: np.asarray(getattr(cal, k)).tolist() for k in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g")}
    out["meta"] = {"peer": "imucal", "version": imucal.__version__, "sampling_rate_hz": IMUCAL_RATE_HZ,
                   "grav": IMUCAL_GRAV, "wall_s": wall}
    return out


def in_raw_unit(model: GyroModel, unit: str) -> GyroModel:
    """The same gyro for raw samples in ``unit`` (rad/s <-> deg/s)."""
    k = RAW_UNITS[model.raw_unit] / RAW_UNITS[unit]  # new raw units per old raw unit
    return GyroModel(model.C / k, model.bias * k, None if model.g_sensitivity is None else model.g_sensitivity * k,
                     unit)


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


def imucal_comparison(r: dict, imucal: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Parameters (ours ± s.e. with nominal axes, the command line's, and with measured axes;
    imucal's) and the figure of merit; ``r`` is :func:`.sessions.calibrate_session`'s
    result on imucal's example, ``imucal`` :func:`run_imucal`'s."""
    from accelcal.gyro.calibrate import evaluate_model

    rec, poses, ours = r["rec"], r["poses"], r["gyro"]
    acc_cal = AffineAccel(np.asarray(imucal["K_a"]) @ np.asarray(imucal["R_a"]), imucal["b_a"])
    sections = {**dict(zip(rec.labels, map(tuple, rec.intervals))), **rec.rotations}
    measured = calibrate_ferraris_session(rec.t, rec.gyro, sections, raw_unit=rec.gyro_unit, accel=acc_cal,
                                          acc=rec.acc)
    theirs = in_raw_unit(GyroModel.from_imucal(imucal["K_g"], imucal["R_g"], imucal["b_g"], None), rec.gyro_unit)
    rows = _params("accelcal", ours.model, ours.standard_errors) + \
        _params("accelcal_measured_axes", measured.model, measured.standard_errors) + _params("imucal", theirs, None)
    params = pd.DataFrame(rows)
    ref = params[params.calibration == "accelcal"].set_index("parameter")
    params["diff_in_se"] = [(v - ref.loc[p, "value"]) / ref.loc[p, "se"] for p, v in zip(params.parameter, params.value)]
    foms = []
    for name, cal in (("accelcal", ours), ("accelcal_measured_axes", measured), ("imucal", None)):
        model = theirs if cal is None else cal.model
        ev, _ = evaluate_model(rec.t, rec.gyro, poses, acc_cal, model.C, model.bias)
        foms.append({"session": "imucal_ferraris", "calibration": name, "bias": "own_bias", "motions": len(ev.r),
                     "rms_deg": float(np.sqrt(np.mean(ev.angles_deg ** 2))), "median_deg": float(np.median(
                         ev.angles_deg)), "max_deg": float(ev.angles_deg.max()),
                     "noise_rms_deg": float(np.sqrt(np.mean(ev.predicted_deg ** 2))), **trust_columns(cal)})
    return params, pd.DataFrame(foms)


def ctu_calibration(rates_mat) -> pd.DataFrame:
    """accelcal's Ferraris fit of the CTU rotations: parameters ± s.e. (nominal axes), and each
    rotation's angle by the nominal scale (the reference angles' check)."""
    import scipy.io

    m = scipy.io.loadmat(rates_mat)
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
    se = standard_errors(fit, np.pi / 180)
    se = {"scale_factors": se["scale_factors"], "T": se["T"]}
    out = pd.DataFrame(_params("accelcal_ctu", model, se))
    out["nominal_angle_deg"] = np.nan
    for j, ax in enumerate("xyz"):
        out.loc[out.parameter == f"s_{ax}", "nominal_angle_deg"] = fit.nominal_angles_deg[j]
    return out


__all__ = ["CTU_ANGLES", "CTU_WINDOWS", "ctu_calibration", "imucal_comparison", "in_raw_unit", "run_imucal"]
