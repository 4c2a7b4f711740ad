"""A peer: imucal's Ferraris calibration on its own example session, against accelcal.

imucal (``FerrarisCalibration``, Ferraris et al. 1995) models the accelerometer as
``a_raw = K_a R_a a + b_a``: ``K_a`` diagonal (gains), ``R_a`` a full matrix with unit
rows (the sensing axes in the frame of the *calibration poses*) and ``b_a`` the bias.
It needs the six static positions x_p ... z_a, assumed exactly (anti)parallel to three
orthogonal directions, and computes ``b_a = (u_p + u_a)/2`` and
``K_a R_a = (u_p - u_a)/(2g)`` from their means.

accelcal's model is ``z = M x + b`` with ``M`` lower triangular (rows ``(1 + s_i) u_i``
in a frame tied to the x and y sensing axes) and no assumption about the pose
directions, which is why it needs ten poses in general orientations for ``M``.

Like with like:

* **bias** — ``b_a`` and ``b`` are the same quantity (the output at zero specific
  force, in the file unit): compared directly with accelcal's bias-only estimators on
  the same six poses.
* **scale** — the row norms of ``K_a R_a`` are ``diag(K_a)`` and the row norms of ``M``
  are ``1 + s_i``: both are the gains of the sensing axes, whatever the frame, so
  ``diag(K_a) - 1`` is comparable to ``s``.  accelcal's full model is not identifiable
  from six orientations, and its bias-only model fixes ``M = I``; but then the residual
  of pose ``i_p`` or ``i_a`` is ``|M g u| - g ≈ s_i g`` (to second order in the
  off-diagonal terms of M), so the mean residual of the two poses of axis ``i``
  divided by g is accelcal's implied scale factor of that axis.
* **non-orthogonality** — ``K_a R_a = L Q`` (LQ decomposition, ``L`` lower triangular
  with positive diagonal, ``Q`` orthogonal): ``L`` is ``K_a R_a`` expressed in
  accelcal's frame and :func:`accelcal.model.params_from_m` gives its angles; ``Q`` is
  the rotation between the pose frame and the sensor frame, which accelcal does not
  estimate.  There is no accelcal counterpart on these data.

imucal is imported inside :func:`ferraris_comparison` only, so that the core library
does not depend on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal import bias_lls, bias_nlls
from accelcal.errors import AccelcalError
from accelcal.formats.imucal import IMUCAL_RATE_HZ
from accelcal.model import params_from_m
from .sources import FERRARIS_STATIC

AXES = ("x", "y", "z")
NONORTH = ("xy", "zx", "zy")


@dataclass(frozen=True)
class FerrarisModel:
    """imucal's accelerometer parameters and their image in accelcal's parametrisation."""

    b_a: np.ndarray
    K_a: np.ndarray
    R_a: np.ndarray
    L: np.ndarray
    Q: np.ndarray

    @property
    def scale_factors(self) -> np.ndarray:
        return np.diag(self.K_a) - 1.0

    @property
    def nonorthogonality_deg(self) -> np.ndarray:
        return np.rad2deg(params_from_m(self.L)[1])


def lq(A) -> tuple[np.ndarray, np.ndarray]:
    """``A = L Q`` with ``L`` lower triangular (positive diagonal) and ``Q`` orthogonal."""
    Qt, Rt = np.linalg.qr(np.asarray(A, float).T)
    d = np.sign(np.diag(Rt))
    d[d == 0] = 1.0
    return (Rt.T * d), (d[:, None] * Qt.T)


def run_imucal(data: pd.DataFrame, sections: pd.DataFrame, grav: float, rate_hz: float) -> FerrarisModel:
    """imucal's Ferraris calibration as in its ``basic_ferraris`` example; only the
    accelerometer part is kept (the gyroscope part needs the rotations, which it gets)."""
    try:
        from imucal import FerrarisCalibration, ferraris_regions_from_section_list
    except ImportError:
        raise AccelcalError("the imucal package is needed for the peer comparison "
                            "(pip install accelcal[peer])") from None
    regions = ferraris_regions_from_section_list(data, sections)
    info = FerrarisCalibration(grav=grav).compute(regions, sampling_rate_hz=rate_hz, from_acc_unit="m/s^2",
                                                  from_gyr_unit="deg/s")
    L, Q = lq(info.K_a @ info.R_a)
    return FerrarisModel(np.asarray(info.b_a, float), np.asarray(info.K_a, float), np.asarray(info.R_a, float), L, Q)


def _axis_of_pose(key: str) -> int:
    return AXES.index(key[0])


def implied_scale(residuals, keys, g: float) -> np.ndarray:
    """Scale factor of each axis implied by bias-only residuals of the six Ferraris poses:
    the mean residual of the ``*_p`` and ``*_a`` poses of the axis, divided by g."""
    r = np.asarray(residuals, float)
    out = np.empty(3)
    for i in range(3):
        sel = [k for k, key in enumerate(keys) if _axis_of_pose(key) == i]
        out[i] = np.mean(r[sel]) / g
    return out


def _pose_set_rows(data: pd.DataFrame, acc: np.ndarray, sections: pd.DataFrame, poses: str, iv: dict,
                   grav: float, rate_hz: float) -> list[dict]:
    """:func:`ferraris_comparison`'s rows of one set of static intervals ``iv``: imucal's
    Ferraris calibration and accelcal's bias-only estimators on the same poses."""
    rows = []

    def add(parameter, unit, tool, method, values, axes=AXES):
        for i, a in enumerate(axes):
            rows.append({"parameter": parameter, "axis": a, "unit": unit, "tool": tool, "method": method,
                         "poses": poses, "value": float(values[i])})

    sec = sections.copy()
    for k, (a, b) in iv.items():
        sec.loc[k, ["start", "end"]] = (a, b)
    fm = run_imucal(data, sec, grav, rate_hz)
    add("bias", "m/s^2", "imucal", "ferraris", fm.b_a)
    add("scale_factor", "1", "imucal", "ferraris", fm.scale_factors)
    add("nonorth", "deg", "imucal", "ferraris (LQ to accelcal frame)", fm.nonorthogonality_deg, axes=NONORTH)
    z = np.array([acc[a:b].mean(axis=0) for a, b in (iv[k] for k in FERRARIS_STATIC)])
    for name, est in (("bias_lls", bias_lls), ("bias_nlls", bias_nlls)):
        r = est(z, grav)
        add("bias", "m/s^2", "accelcal", name, r.bias)
        add("scale_factor", "1", "accelcal", f"{name} residuals", implied_scale(r.residuals, FERRARIS_STATIC, grav))
    return rows


def ferraris_comparison(session_csv, section_list_json, *, grav: float = 9.81, rate_hz: float = IMUCAL_RATE_HZ,
                        detected: dict[str, tuple[int, int]] | None = None) -> pd.DataFrame:
    """Run imucal's Ferraris calibration and accelcal's bias-only estimators on the same poses.

    Parameters
    ----------
    session_csv, section_list_json : path
        imucal's example session and section list (read as imucal's example does).
    grav : float
        Gravity used by both (imucal's default and example: 9.81 m/s²).
    rate_hz : float
        Sampling rate of the session (only imucal's gyroscope part uses it).
    detected : dict, optional
        ``{x_p: (start, stop), ...}``: the rests accelcal's static detection matched to
        the six static sections.  If given, both tools are also run on them, which
        separates the effect of the interval choice from that of the method.

    Returns
    -------
    DataFrame
        Tidy rows ``parameter, axis, unit, tool, method, poses, value, diff_to_imucal``
        (``diff_to_imucal`` against imucal on the section list's poses).
    """
    data = pd.read_csv(session_csv, header=0, index_col=0)
    sections = pd.read_json(section_list_json).T
    missing = [k for k in FERRARIS_STATIC if k not in sections.index]
    if missing:
        raise AccelcalError(f"{section_list_json}: section list lacks {', '.join(missing)}")
    acc = data[["acc_x", "acc_y", "acc_z"]].to_numpy(float)

    pose_sets = {"section_list": {k: (int(sections.loc[k, "start"]), int(sections.loc[k, "end"]))
                                  for k in FERRARIS_STATIC}}
    if detected is not None:
        pose_sets["detected"] = {k: tuple(int(v) for v in detected[k]) for k in FERRARIS_STATIC}

    rows = []
    for poses, iv in pose_sets.items():
        rows += _pose_set_rows(data, acc, sections, poses, iv, grav, rate_hz)
    df = pd.DataFrame(rows)
    ref = df[(df.tool == "imucal") & (df.poses == "section_list")].set_index(["parameter", "axis"])["value"]
    df["diff_to_imucal"] = [v - ref.get((p, a), np.nan) for p, a, v in zip(df.parameter, df.axis, df.value)]
    return df


__all__ = ["FerrarisModel", "ferraris_comparison", "implied_scale", "lq", "run_imucal"]
