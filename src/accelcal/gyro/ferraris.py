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

from .errors import RotationAngleError


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


def _stack(segments):
    """One array of the rotation segments (each (k_j, 3)), one guard sample apart, and their ranges."""
    y, starts, stops, pos = [], [], [], 0
    for s in segments:
        s = np.asarray(s, float)
        y += [s, np.zeros((1, 3))]
        starts.append(pos)
        stops.append(pos + len(s) - 1)
        pos += len(s) + 1
    return np.concatenate(y), np.array(starts), np.array(stops)


def fit_ferraris(segments, h: float, angles_deg, axes=None, *, nominal: float = 1.0, y_var=None, bias_var=None,
                 axis_cov=None, angle_std_deg: float = 0.0, angle_tolerance: float = 0.1,
                 names=("x", "y", "z")) -> FerrarisFit:
    """Fit ``C`` from three rotations (module docstring).

    Parameters
    ----------
    segments : sequence of 3 arrays (k_j, 3)
        Gyro samples of each rotation, bias removed, raw unit (rests around it may be
        included: they add only noise).
    h : float
        Sample interval [s].
    angles_deg : array_like (3,)
        Stated rotation angles (magnitudes) [deg].
    axes : array_like (3, 3), optional
        Unit rotation axis of each rotation (rows) in the output frame; default identity.
    nominal : float
        Nominal rad/s per raw unit (the stated-angle check).
    y_var, bias_var : array_like (3,), optional
        Per-sample variance for sums and variance of the removed bias (raw unit²).
    axis_cov : array_like (3, 3, 3), optional
        Covariance of each axis direction.
    angle_std_deg : float
        Uncertainty of each stated angle.
    angle_tolerance : float
        Relative difference between the nominal gyro's angle and the stated one above which
        the rotation is refused (:class:`RotationAngleError`).
    """
    segs = [np.asarray(s, float) for s in segments]
    theta = np.deg2rad(np.abs(np.asarray(angles_deg, float)))
    A = np.eye(3) if axes is None else np.asarray(axes, float)
    A = A / np.linalg.norm(A, axis=1, keepdims=True)
    Y = np.array([h * s.sum(axis=0) for s in segs])  # (3, 3): row j = plain sum of rotation j
    nominal_deg = np.rad2deg(abs(nominal) * np.linalg.norm(Y, axis=1))
    for j in range(3):
        if abs(nominal_deg[j] - np.rad2deg(theta[j])) > angle_tolerance * np.rad2deg(theta[j]):
            raise RotationAngleError(
                f"the {names[j]} rotation turns {nominal_deg[j]:.1f} deg by the nominal gyro scale, not the stated "
                f"{np.rad2deg(theta[j]):.1f} deg: check the rotation angle (--rotation-angle), the section of that "
                "rotation in the section list, or the gyro unit/sensitivity")
    senses = np.where(np.sum(Y * A, axis=1) * nominal >= 0, 1.0, -1.0)
    target = (senses * theta)[:, None] * A
    Yinv = np.linalg.inv(Y.T)  # C Y.T = target.T
    C = target.T @ Yinv
    cov = np.zeros((9, 9))
    yv = np.zeros(3) if y_var is None else np.asarray(y_var, float)
    bv = np.zeros(3) if bias_var is None else np.asarray(bias_var, float)
    for j, s in enumerate(segs):
        dur = h * len(s)
        covY = np.diag(h * h * len(s) * yv + dur * dur * bv)
        covT = np.deg2rad(angle_std_deg) ** 2 * np.outer(A[j], A[j])
        if axis_cov is not None:
            covT = covT + theta[j] ** 2 * np.asarray(axis_cov, float)[j]
        Jj = np.kron(np.eye(3), Yinv[j][:, None])  # vec(δC) = Σ_j (δT_j - C δY_j) ⊗ row j of Y⁻ᵀ
        cov += Jj @ (C @ covY @ C.T + covT) @ Jj.T
    return FerrarisFit("sum", C, cov, senses, np.rad2deg(np.linalg.norm(Y @ C.T, axis=1)), nominal_deg, 1)


__all__ = ["FerrarisFit", "fit_ferraris"]
