"""Gyro calibration from rotations of known angle (the Ferraris protocol, as imucal runs it).

The sensor rests, then turns by a known angle ``θ_j`` about an axis ``a_j`` (once about
each of three axes), then rests.  The calibrated, integrated gyro must give exactly that
rotation::

    log R_j(C) = s_j θ_j a_j          (3 equations per rotation, 9 for three)

``s_j = ±1`` is the turning sense, taken from the data (imucal fixes it with
``expected_angle = -360``).  The axis ``a_j``:

* when the accelerometer is known, the gravity direction during the rotation (the
  sensor lies on a face and turns on the table, i.e. about the vertical): then ``C`` is
  in the accelerometer frame, as for the multi-position fit;
* otherwise the nominal axis ``e_j`` (imucal's assumption, and the only one possible for
  a gyro-only record such as the CTU rig's): the frame is then that of the rotation axes.

The estimate is imucal's linear one, with measured axes instead of assumed ones: for a
rotation about an axis fixed in the sensor the integral of the rate is exactly ``C⁻¹ θ_j
a_j`` whatever the angle, so the plain sums ``Y_j = h Σ y`` give ``C = [s_j θ_j a_j]
[Y_j]⁻¹`` in one solve.  No product integrator and no iteration: the end rotation of a
full turn is the identity for *every* axis (``exp(2π [a]×) = I``), so it cannot
determine the axis, and a rotation-vector fit of it is singular at 360 deg (its right
Jacobian vanishes across the axis); the integral of the rate is the quantity that
carries the axis.  Three rotations determine the nine parameters exactly (no residual,
no χ²): the standard errors come from the noise alone (the angle random walk of each
sum, the bias error times the rotation's duration, the axis direction's noise, and
``angle_std``, the uncertainty of the stated angles).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..registry import estimator
from .rests import accel_directions
from .errors import RotationAngleError, TooFewMotionsError
from .model import GyroModel, RAW_UNITS
from .rests import fit_bias, rest_noise, rest_statistics, sample_interval
from .result import GyroQuality
from .unit_evidence import unit_from_rotations

#: Rotations the nine parameters need: three equations each, exactly determined (registry: ``gyro_ferraris``).
N_ROTATIONS = 3


@dataclass(frozen=True)
class FerrarisFit:
    """A gyro matrix from rotations of known angle."""

    estimator: str
    C: np.ndarray  #: (3, 3) rad/s per raw unit
    cov: np.ndarray  #: (9, 9) covariance of vec(C)
    senses: np.ndarray  #: (3,) ±1 turning sense of each rotation
    angles_deg: np.ndarray  #: (3,) angle of each rotation by the fitted gyro
    nominal_angles_deg: np.ndarray  #: (3,) angle by the nominal gyro (the check on the stated angle)
    iterations: int

    def to_dict(self) -> dict:
        return {"estimator": self.estimator, "C": self.C.tolist(), "cov": self.cov.tolist(),
                "senses": self.senses.tolist(), "angles_deg": self.angles_deg.tolist(),
                "nominal_angles_deg": self.nominal_angles_deg.tolist(), "iterations": self.iterations}


def fit_ferraris(segments, h: float, angles_deg, axes=None, *, nominal: float = 1.0, y_var=None, bias_var=None,
                 axis_cov=None, angle_std_deg: float = 0.0, angle_tolerance: float = 0.1,
                 names=("x", "y", "z")) -> FerrarisFit:
    """Fit ``C`` from three rotations (module docstring).

    Parameters
    ----------
    segments : sequence of arrays (k_j, 3), at least 3
        Gyro samples of each rotation, bias removed, raw unit (rests around it may be
        included: they add only noise).  Three rotations determine ``C`` exactly; more are
        fitted in least squares.
    h : float
        Sample interval [s].
    angles_deg : array_like (r,)
        Stated rotation angles (magnitudes) [deg].
    axes : array_like (r, 3), optional
        Unit rotation axis of each rotation (rows) in the output frame; default identity.
    nominal : float
        Nominal rad/s per raw unit (the stated-angle check).
    y_var, bias_var : array_like (3,), optional
        Per-sample variance for sums and variance of the removed bias (raw unit²);
        ``bias_var`` may be (r, 3), one per rotation (runs that rest, and have a bias,
        each on their own).
    axis_cov : array_like (3, 3, 3), optional
        Covariance of each axis direction.
    angle_std_deg : float
        Uncertainty of each stated angle.
    angle_tolerance : float
        Relative difference between the nominal gyro's angle and the stated one above which
        the rotation is refused (:class:`RotationAngleError`).
    """
    segs = [np.asarray(s, float) for s in segments]
    if len(segs) < N_ROTATIONS:
        raise TooFewMotionsError(f"{len(segs)} rotations of known angle; the gyro's 9 parameters need at least "
                                 f"{N_ROTATIONS}, one about each axis (x_rot, y_rot, z_rot in the section list)")
    theta = np.deg2rad(np.abs(np.asarray(angles_deg, float)))
    A = np.eye(3)[np.arange(len(segs)) % 3] if axes is None else np.asarray(axes, float)
    A = A / np.linalg.norm(A, axis=1, keepdims=True)
    Y = np.array([h * s.sum(axis=0) for s in segs])  # (r, 3): row j = plain sum of rotation j
    nominal_deg = np.rad2deg(abs(nominal) * np.linalg.norm(Y, axis=1))
    _check_angles(nominal_deg, np.rad2deg(theta), angle_tolerance, names)
    senses = np.where(np.sum(Y * A, axis=1) * nominal >= 0, 1.0, -1.0)
    target = (senses * theta)[:, None] * A
    P = Y @ np.linalg.inv(Y.T @ Y)  # C Yᵀ = targetᵀ in least squares; three rotations: P = Y⁻ᵀ, exact
    C = target.T @ P
    cov = np.zeros((9, 9))
    yv = np.zeros(3) if y_var is None else np.asarray(y_var, float)
    bv = np.broadcast_to(np.zeros(3) if bias_var is None else np.asarray(bias_var, float), (len(segs), 3))
    for j, s in enumerate(segs):
        dur = h * len(s)
        covY = np.diag(h * h * len(s) * yv + dur * dur * bv[j])
        covT = np.deg2rad(angle_std_deg) ** 2 * np.outer(A[j], A[j])
        if axis_cov is not None:
            covT = covT + theta[j] ** 2 * np.asarray(axis_cov, float)[j]
        Jj = np.kron(np.eye(3), P[j][:, None])  # vec(δC) = Σ_j (δT_j - C δY_j) ⊗ row j of P
        cov += Jj @ (C @ covY @ C.T + covT) @ Jj.T
    return FerrarisFit("gyro_ferraris", C, cov, senses, np.rad2deg(np.linalg.norm(Y @ C.T, axis=1)), nominal_deg, 1)


def _check_angles(nominal_deg, stated_deg, tolerance: float, names) -> None:
    """Each rotation's angle by the nominal gyro scale within ``tolerance`` (relative) of the
    stated one, else one line naming the rotation and what to check."""
    for j, (turned, stated) in enumerate(zip(nominal_deg, stated_deg)):
        if abs(turned - stated) > tolerance * stated:
            name = names[j] if j < len(names) else f"#{j + 1}"
            raise RotationAngleError(
                f"the {name} rotation turns {turned:.1f} deg by the nominal gyro scale, not the stated "
                f"{stated:.1f} deg: check the rotation angle (--rotation-angle), the section of that "
                "rotation in the section list, or the gyro unit (--gyro-unit, --gyro-sensitivity)")


def rotation_singular_values(segments, h: float) -> np.ndarray:
    """Singular values of the integrated rates of the rotations (rows ``h Σ y``, raw unit × s):
    the registry's conditioning of the Ferraris fit (a near-zero one: two rotations about
    one axis)."""
    return np.linalg.svd(np.array([h * np.asarray(s, float).sum(axis=0) for s in segments]), compute_uv=False)


#: imucal's section names: static holds and rotations.
REST_SECTIONS = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
ROTATION_SECTIONS = ("x_rot", "y_rot", "z_rot")


def calibrate_ferraris_session(t, gyro, sections: dict, *, raw_unit: str = "deg/s", angles_deg=360.0, accel=None,
                               acc=None, nominal_sensitivity=None, angle_std_deg: float = 0.0,
                               rest_names=REST_SECTIONS, rotation_names=ROTATION_SECTIONS):
    """Calibrate the gyro of a Ferraris session (static holds and three rotations of known angle).

    Parameters
    ----------
    t : array_like (n,)
        Time [s] (a constant step is taken from it).
    gyro : array_like (n, 3)
        Raw gyro samples.
    sections : dict
        ``{name: (start, stop)}`` half-open sample ranges (imucal's section list); the rests
        ``rest_names`` give the bias, the rotations ``rotation_names`` the scale.
    angles_deg : float or sequence of 3
        Stated angle of each rotation (magnitudes; the sense comes from the data).
    accel, acc
        An accelerometer calibration (``apply(raw) -> m/s²``) and the raw accelerometer
        samples: the rotation axes are then the gravity directions during the rotations and
        ``C`` is in the accelerometer frame; without them the nominal axes (imucal's
        assumption).
    nominal_sensitivity : float, optional
        Raw units per rad/s (counts).
    raw_unit : {'rad/s', 'deg/s', 'counts'} or None
        None: not stated; the rotations' summed rate against their stated angles decides it
        (:mod:`accelcal.gyro.unit_evidence`), or a one-line refusal.

    Returns
    -------
    GyroCalibration
        Exactly determined: no residual, ``dof = 0``; the standard errors come from the
        noise (module docstring).
    """

    missing = [k for k in (*rest_names, *rotation_names) if k not in sections]
    if missing:
        raise RotationAngleError(f"the section list lacks {', '.join(missing)}: a Ferraris session needs the rests "
                                 f"{', '.join(rest_names)} and the rotations {', '.join(rotation_names)} (--intervals)")
    gyro = np.asarray(gyro, float)
    tb = sample_interval(t)
    rs = rest_statistics(t, gyro, np.array([sections[k] for k in rest_names]))
    best = fit_bias(rs, "all")
    segs = [gyro[slice(*sections[k])] - best.bias for k in rotation_names]
    raw_unit, unit_from, nominal = _nominal_scale(raw_unit, nominal_sensitivity, segs, tb.h, angles_deg, gyro)
    axes, axis_cov = None, None
    if accel is not None and acc is not None:
        axes, axis_cov = _rotation_axes(accel, [np.asarray(acc, float)[slice(*sections[k])] for k in rotation_names])
    angles = np.broadcast_to(np.asarray(angles_deg, float), (3,))
    fit = fit_ferraris(segs, tb.h, angles, axes, nominal=nominal, y_var=rest_noise(rs),
                       bias_var=best.bias_se ** 2, axis_cov=axis_cov, angle_std_deg=angle_std_deg,
                       names=tuple(n.split("_")[0] for n in rotation_names))
    settings = {"bias_mode": "all", "time_base": {"h": tb.h, "rate": tb.rate, "jitter": tb.jitter},
                "angles_deg": angles.tolist(), "axes": None if axes is None else np.asarray(axes).tolist(),
                "nominal_from": f"unit {raw_unit}" if unit_from == "stated" else unit_from}
    return ferraris_calibration(fit, best.bias, best.bias_se * max(1.0, best.excess), raw_unit, nominal,
                                nominal_axes=axes is None, settings=settings)


def standard_errors(fit: FerrarisFit, nominal: float) -> dict:
    """Standard errors of ``C``, of the misalignment ``T = C K⁻¹`` and of the scale factors (per
    ``nominal`` rad/s per raw unit), from ``fit.cov`` (row-major ``vec C``).  ``T`` by the delta
    method: ``T_ij = C_ij / C_jj``, so ``∂T_ij/∂C_ij = 1/C_jj`` and ``∂T_ij/∂C_jj = -C_ij/C_jj²``
    (``T_ii = 1``: no error); variances rounded below zero count as zero."""
    se_C = np.sqrt(np.clip(np.diag(fit.cov), 0, None)).reshape(3, 3)
    Jt = np.zeros((9, 9))
    for i in range(3):
        for j in range(3):
            if i != j:
                Jt[3 * i + j, 3 * i + j] = 1.0 / fit.C[j, j]
                Jt[3 * i + j, 4 * j] = -fit.C[i, j] / fit.C[j, j] ** 2
    return {"C": se_C, "T": np.sqrt(np.clip(np.diag(Jt @ fit.cov @ Jt.T), 0, None)).reshape(3, 3),
            "scale_factors": np.diag(se_C) / abs(nominal)}


def _nominal_scale(raw_unit, nominal_sensitivity, segs, h: float, angles_deg, gyro):
    """The gyro's raw unit, who said it (``'stated'``, or the rotations of known angle) and its
    nominal rad/s per raw unit; raw counts without a sensitivity refused in one line."""
    unit_from = "stated"
    if raw_unit is None and nominal_sensitivity is not None:
        raw_unit = "counts"  # a sensitivity is counts per rad/s
    if raw_unit is None:  # not stated: the rotations of known angle decide it
        raw_unit, unit_from = unit_from_rotations(segs, h, angles_deg, gyro)
    nominal = 1.0 / float(nominal_sensitivity) if nominal_sensitivity is not None else RAW_UNITS[raw_unit]
    if nominal is None:
        raise RotationAngleError("raw counts need the nominal gyro sensitivity (--gyro-sensitivity) to check the "
                                 "rotation angles")
    return raw_unit, unit_from, nominal


def _rotation_axes(accel, seg_acc):
    """Each rotation's axis measured by the calibrated accelerometer (the mean direction of
    gravity during it) and its covariance."""
    means = np.array([s.mean(axis=0) for s in seg_acc])
    se = np.array([s.std(axis=0, ddof=1) / np.sqrt(len(s)) for s in seg_acc])
    axes, axis_cov, _ = accel_directions(accel, means, se)
    return axes, axis_cov


def ferraris_calibration(fit: FerrarisFit, bias, bias_se, raw_unit: str, nominal: float, *, nominal_axes: bool,
                         settings: dict, motions=None, warnings=()):
    """The :class:`~accelcal.gyro.result.GyroFerrarisCalibration` of a fit: the misalignment's and
    the scale factors' standard errors from ``fit.cov``, the warnings of an exact fit."""

    model = GyroModel(fit.C, np.asarray(bias, float), None, raw_unit)
    se = {**standard_errors(fit, nominal), "bias": np.asarray(bias_se, float)}
    n = len(fit.senses)
    warnings = list(warnings)
    if n == N_ROTATIONS:
        warnings.insert(0, "three rotations determine the nine parameters exactly: no residual checks the fit; the ± "
                           "rest on the noise alone (and on --rotation-angle's uncertainty)")
    if nominal_axes:
        warnings.append("the rotation axes are assumed to be the sensor's x, y and z (imucal's assumption; measured "
                        "ones need a full accelerometer calibration): the misalignments are relative to them")
    quality = GyroQuality(n_motions=n, n_parameters=9, dof=3 * n - 9, chi2=float("nan"), p_value=float("nan"),
                          excess=float("nan"), residual_rms_deg=0.0, predicted_rms_deg=float("nan"),
                          axis_turn_deg=tuple(float(a) for a in fit.angles_deg), warnings=tuple(warnings),
                          flags=("exactly_determined",) if n == N_ROTATIONS else ())
    settings = {"estimator": fit.estimator, "integrator": "sum", "nominal": nominal, "senses": fit.senses.tolist(),
                "nominal_angles_deg": fit.nominal_angles_deg.tolist(), "iterations": 1, **settings}
    return estimator(fit.estimator).load_calibration()(model, se, quality, dict(motions or {}), settings)


__all__ = ["FerrarisFit", "N_ROTATIONS", "REST_SECTIONS", "ROTATION_SECTIONS", "calibrate_ferraris_session",
           "ferraris_calibration", "fit_ferraris", "rotation_singular_values", "standard_errors"]
