"""Gyro scale and misalignment from the motions between static poses (IMU-TK's protocol).

Between rest ``a`` and the next rest ``b`` the sensor turns; the gyro, calibrated by
``C`` and integrated (:mod:`accelcal.gyro.integrate`), gives the rotation ``R(C)``
of that motion, and gravity seen at rest ``a`` (unit direction ``u_a`` in the
accelerometer frame, from the calibrated accelerometer) must be seen at rest ``b`` as
``R(C)ᵀ u_a = u_b``.  The residual of a motion is the two tangent components at
``u_b``::

    r_i = E(u_b)ᵀ R_i(C)ᵀ u_a          (≈ the angle between them [rad], 2 per motion)

IMU-TK minimises ``Σ |R_iᵀ u_a - u_b|²`` unweighted.  Here the residuals are weighted by
their covariance, predicted from the noise measured at the rests, not from the fit:

* the accelerometer noise of the pose means, through the accelerometer calibration, in
  ``u_a`` and ``u_b`` (``cov_u``); consecutive motions share a rest, so their residuals
  are correlated, and the covariance is block-tridiagonal, not diagonal;
* the gyro's white noise integrated over the motion (angle random walk ``Q_i``), and the
  error of the bias subtracted (``bias_var``).

With this covariance the weighted least squares on the residuals is, to first order,
the maximum-likelihood estimate with the true pose directions as nuisance parameters
(the residuals are a complete set of contrasts that eliminate them), so its covariance
``(Jᵀ Σ⁻¹ J)⁻¹`` is the Cramér–Rao bound (:func:`crlb`; checked against the explicit
nuisance form in the tests).

Estimators, both on ``vec(C)`` (9 unknowns):

* :func:`fit_iterative` — Gauss-Newton with the exact Jacobian of the product
  integrator (``dphi_dC``), backtracking on the weighted cost, until every step is below
  ``STEP_TOL`` (1 %) of its standard error (the fit is then within far less than that of
  its optimum: Gauss-Newton converges quadratically on these nearly linear residuals).
  IPOPT is not needed: the Jacobian is analytic
  (checked against finite differences in the tests) and each iteration costs one pass
  over the motions' samples; the repro compares both (same minimum).
* :func:`fit_one_step` — one linearised solve about the nominal model ``C0``: a single
  Gauss-Newton step, no iteration.  Its error is the second-order remainder of
  ``C - C0``; where that stays below the noise is measured
  (:mod:`accelcal_repro.gyro.montecarlo`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import NotConvergedError
from .errors import TooFewMotionsError
from .integrate import _increments, _step_index, expm_so3, integrate_intervals, log_so3, skew, total_products

#: Motions (those that turn most) on which the scalar start for raw counts is searched.
N_SCALE_MOTIONS = 8
#: Stop when every Gauss-Newton step is below this fraction of its parameter's standard error.
STEP_TOL = 1e-2
MAX_ITER = 50
#: Fewest motions the 9 parameters need: 2 residuals each, one more than the unknowns
#: (``accelcal.registry``: ``min_poses`` of the motion estimators).
MIN_MOTIONS = 5


@dataclass(frozen=True)
class MotionSet:
    """The data of the motion fit, as arrays (``n`` samples, ``m`` motions, ``p`` rests).

    Attributes
    ----------
    y : ndarray (n, 3)
        Gyro samples with the bias (and g-sensitivity) removed, raw unit: ``ω = C y``.
    h : float
        Sample interval [s].
    starts, stops : ndarray of int (m,)
        First and last sample of each motion (integration ``start -> stop``).
    rest_before, rest_after : ndarray of int (m,)
        Rest of each motion's start and end (indices into ``u``).
    u : ndarray (p, 3)
        Unit gravity direction of each rest, accelerometer frame.
    u_cov : ndarray (p, 3, 3)
        Covariance of each ``u`` (tangent to the sphere).
    y_var : ndarray (3,)
        Variance of one sample of ``y`` for sums: per-sample variance times the
        integrated autocorrelation time, raw unit².
    bias_var : ndarray (m, 3)
        Variance of the bias removed during each motion, raw unit².
    noise : MotionNoise, optional
        The noise between the rests beyond the rests' white noise
        (:mod:`accelcal.gyro.noise`): per-motion rotation errors, the bias's wander, the
        rests' direction errors; None: the rest noise alone.
    """

    y: np.ndarray
    h: float
    starts: np.ndarray
    stops: np.ndarray
    rest_before: np.ndarray
    rest_after: np.ndarray
    u: np.ndarray
    u_cov: np.ndarray
    y_var: np.ndarray
    bias_var: np.ndarray
    noise: object = None

    @property
    def n_motions(self) -> int:
        return len(self.starts)

    def subset(self, keep) -> MotionSet:
        """The same data with only the motions ``keep`` (bool mask or indices)."""
        idx = np.arange(self.n_motions)[keep]
        return MotionSet(self.y, self.h, self.starts[idx], self.stops[idx], self.rest_before[idx],
                         self.rest_after[idx], self.u, self.u_cov, self.y_var, self.bias_var[idx],
                         None if self.noise is None else self.noise.subset(idx))


def tangent_basis(u) -> np.ndarray:
    """Two orthonormal vectors perpendicular to each unit ``u`` (m, 3) -> (m, 3, 2)."""
    u = np.asarray(u, float)
    helper = np.where(np.abs(u[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(u, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.cross(u, t1)], axis=2)


@dataclass(frozen=True)
class Evaluation:
    """Residuals, Jacobian and covariance of the motions at one ``C``."""

    R: np.ndarray  #: (m, 3, 3) integrated rotations
    r: np.ndarray  #: (m, 2) residuals [rad]
    J: np.ndarray  #: (m, 2, 9) ∂r/∂vec(C)
    cov: np.ndarray  #: (2m, 2m) covariance of the stacked residuals
    chol: np.ndarray  #: its lower Cholesky factor

    @property
    def chi2(self) -> float:
        z = self.whiten(self.r.reshape(-1))
        return float(z @ z)

    def whiten(self, v) -> np.ndarray:
        """``L⁻¹ v`` for the Cholesky factor ``L`` of the residual covariance."""
        return np.linalg.solve(self.chol, v)  # numpy's LU on the (2m, 2m) factor: no scipy.linalg import

    def whitened(self) -> tuple[np.ndarray, np.ndarray]:
        """``L⁻¹ J`` (2m, 9) and ``L⁻¹ r`` (2m,)."""
        return self.whiten(self.J.reshape(-1, 9)), self.whiten(self.r.reshape(-1))

    @property
    def angles_deg(self) -> np.ndarray:
        """Per-motion misfit: angle between ``Rᵀ u_a`` and ``u_b`` [deg] (≈ |r_i|)."""
        return np.rad2deg(np.arcsin(np.clip(np.linalg.norm(self.r, axis=1), 0.0, 1.0)))

    @property
    def predicted_deg(self) -> np.ndarray:
        """Per-motion RMS misfit the noise alone predicts [deg]: ``sqrt(trace Σ_ii)``."""
        m = len(self.r)
        d = np.diagonal(self.cov).reshape(m, 2).sum(axis=1)
        return np.rad2deg(np.sqrt(d))


@dataclass(frozen=True)
class CovarianceParts:
    """The residual covariance at one ``C`` in pieces: ``cov = fixed + Σ_k θ_k V[k]`` for the
    variance components ``θ`` of :class:`accelcal.gyro.noise.MotionNoise` (its ``COMPONENTS``)."""

    R: np.ndarray  #: (m, 3, 3) integrated rotations
    r: np.ndarray  #: (m, 2) residuals [rad]
    J: np.ndarray  #: (m, 2, 9) ∂r/∂vec(C)
    rest: np.ndarray  #: (2m, 2m) from the rests' noise alone (gyro white noise, bias, pose means)
    fixed: np.ndarray  #: (2m, 2m) ``rest`` plus the noise model's fixed part (the bias's wander)
    V: tuple  #: per variance component (2m, 2m): the covariance of a unit component
    A: np.ndarray | None = None  #: (2m, 3p) ∂r/∂u of every rest's direction


def covariance_parts(ms: MotionSet, C, method: str = "magnus4") -> CovarianceParts:
    """Residuals, their Jacobian in ``vec(C)`` and their covariance in pieces at ``C``."""
    C = np.asarray(C, float)
    omega = ms.y @ C.T
    rate_cov = C @ np.diag(ms.y_var) @ C.T
    it = integrate_intervals(omega, ms.h, ms.starts, ms.stops, method, raw=ms.y, rate_cov=rate_cov)
    ua, ub = ms.u[ms.rest_before], ms.u[ms.rest_after]
    E = tangent_basis(ub)
    Rt = np.swapaxes(it.R, -1, -2)
    w = np.einsum("mij,mj->mi", Rt, ua)
    Et = np.swapaxes(E, -1, -2)
    EW = Et @ skew(w)  # (m, 2, 3): ∂r/∂φ_end
    r = np.einsum("mki,mi->mk", Et, w)
    J = EW @ it.dphi_dC
    m, p = ms.n_motions, len(ms.u)
    A = np.zeros((m, 2, p, 3))  # ∂r_i/∂u of every rest: E_iᵀ R_iᵀ at the start, -E_iᵀ at the end
    A[np.arange(m), :, ms.rest_before, :] += Et @ Rt
    A[np.arange(m), :, ms.rest_after, :] -= Et
    A2 = A.reshape(2 * m, 3 * p)
    idx = 2 * np.arange(m)[:, None, None] + np.arange(2)[None, :, None], 2 * np.arange(m)[:, None, None] + \
        np.arange(2)[None, None, :]

    def motion_block(per_motion):  # (m, 3, 3) rotation-vector covariance -> (2m, 2m) block diagonal
        out = np.zeros((2 * m, 2 * m))
        out[idx] = EW @ per_motion @ np.swapaxes(EW, -1, -2)
        return out

    def rest_part(u_cov):  # (p, 3, 3) covariance of the rests' directions -> (2m, 2m)
        return np.einsum("mkpi,pij->mkpj", A, u_cov).reshape(2 * m, 3 * p) @ A2.T

    GC = it.G @ C

    def bias_part(bias_var):
        return GC @ (bias_var[:, :, None] * np.swapaxes(GC, -1, -2))

    rest = rest_part(ms.u_cov) + motion_block(it.Q + bias_part(ms.bias_var))
    if ms.noise is None:
        return CovarianceParts(it.R, r, J, rest, rest, (), A2)
    fixed = rest + motion_block(bias_part(ms.noise.wander_var))
    P = np.eye(3)[None] - ms.u[:, :, None] * ms.u[:, None, :]
    # a per-motion error of C, δC = E C with E's entries iid (unit variance): δφ = D vec(E C), D = ∂φ/∂vec(C)
    per_motion_C = it.dphi_dC @ np.kron(np.eye(3), C.T @ C) @ np.swapaxes(it.dphi_dC, -1, -2)
    T = np.asarray(ms.noise.durations, float)
    V = (motion_block(per_motion_C), motion_block(T[:, None, None] * np.eye(3)), rest_part(P))
    return CovarianceParts(it.R, r, J, rest, fixed, V, A2)


def evaluate(ms: MotionSet, C, method: str = "magnus4", *, rest_only: bool = False) -> Evaluation:
    """Residuals, their Jacobian in ``vec(C)`` and their predicted covariance at ``C``
    (``rest_only``: from the rests' noise alone, without the noise model of ``ms``)."""
    parts = covariance_parts(ms, C, method)
    if rest_only or ms.noise is None:
        cov = parts.rest
    else:
        cov = parts.fixed + sum(v * V for v, V in zip(ms.noise.variances, parts.V))
    return Evaluation(parts.R, parts.r, parts.J, cov, np.linalg.cholesky(cov))


@dataclass(frozen=True)
class GyroFit:
    """One estimate of ``C`` with its covariance (first order, from the rest noise)."""

    method: str  #: the registry's name: 'gyro_iterative' or 'gyro_one_step'
    integrator: str
    C: np.ndarray
    cov: np.ndarray  #: (9, 9) of vec(C), not scaled by the excess
    chi2: float
    dof: int
    iterations: int
    seconds: float
    evaluation: Evaluation

    @property
    def excess(self) -> float:
        return math.sqrt(self.chi2 / self.dof) if self.dof > 0 else float("nan")


def _step(ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
    Jw, rw = ev.whitened()
    JtJ = Jw.T @ Jw
    cov = np.linalg.inv(JtJ)
    return -cov @ (Jw.T @ rw), cov


def _require_motions(ms: MotionSet) -> None:
    if ms.n_motions < MIN_MOTIONS:
        raise TooFewMotionsError(f"{ms.n_motions} motions between rests; the gyro's 9 parameters need at least "
                                 f"{MIN_MOTIONS}: record more poses (or shorter still phases: --min-duration)")


def fit_one_step(ms: MotionSet, C0, method: str = "magnus4") -> GyroFit:
    """One linearised solve about ``C0``: ``vec(C) = vec(C0) - (Jᵀ Σ⁻¹ J)⁻¹ Jᵀ Σ⁻¹ r`` at ``C0``."""
    _require_motions(ms)
    t0 = time.perf_counter()
    C0 = np.asarray(C0, float)
    ev0 = evaluate(ms, C0, method)
    d, cov = _step(ev0)
    C = C0 + d.reshape(3, 3)
    seconds = time.perf_counter() - t0
    ev = evaluate(ms, C, method)
    return GyroFit("gyro_one_step", method, C, cov, ev.chi2, 2 * ms.n_motions - 9, 1, seconds, ev)


def motion_residuals(ms: MotionSet, C, method: str) -> np.ndarray:
    """The stacked residuals (2m,) at ``C``, without Jacobian or covariance (line search)."""
    R = integrate_intervals(ms.y @ np.asarray(C, float).T, ms.h, ms.starts, ms.stops, method).R
    w = np.einsum("mji,mj->mi", R, ms.u[ms.rest_before])
    return np.einsum("mik,mi->mk", tangent_basis(ms.u[ms.rest_after]), w).reshape(-1)


def fit_iterative(ms: MotionSet, C0, method: str = "magnus4", max_iter: int = MAX_ITER) -> GyroFit:
    """Weighted Gauss-Newton from ``C0`` to convergence (module docstring).

    Each step is halved until the weighted cost (with the covariance of the current
    point) does not increase; the covariance is then re-evaluated at the new point.

    Raises
    ------
    NotConvergedError
        No convergence in ``max_iter`` iterations.
    TooFewMotionsError
        Fewer than :data:`MIN_MOTIONS` motions.
    """
    _require_motions(ms)
    t0 = time.perf_counter()
    C = np.asarray(C0, float)
    ev = evaluate(ms, C, method)
    for it in range(1, max_iter + 1):
        d, cov = _step(ev)
        se = np.sqrt(np.diag(cov))
        cost, lam = ev.chi2, 1.0
        while lam >= 1e-4:
            z = ev.whiten(motion_residuals(ms, C + lam * d.reshape(3, 3), method))
            if z @ z <= cost * (1 + 1e-12):
                break
            lam *= 0.5
        C = C + lam * d.reshape(3, 3)
        ev = evaluate(ms, C, method)
        if np.all(np.abs(lam * d) <= STEP_TOL * se):
            _, cov = _step(ev)
            return GyroFit("gyro_iterative", method, C, cov, ev.chi2, 2 * ms.n_motions - 9, it,
                           time.perf_counter() - t0, ev)
    raise NotConvergedError(f"gyro fit did not converge in {max_iter} Gauss-Newton iterations")


def crlb(ms: MotionSet, C, method: str = "magnus4") -> np.ndarray:
    """Cramér–Rao bound (9, 9) on ``vec(C)`` for noise-free data ``ms`` made with ``C``
    (first order; the pose directions are nuisance parameters, module docstring)."""
    ev = evaluate(ms, C, method)
    Jw, _ = ev.whitened()
    return np.linalg.inv(Jw.T @ Jw)


def motion_singular_values(ms: MotionSet, C, method: str = "magnus4") -> np.ndarray:
    """Singular values of the whitened Jacobian of the motion residuals at ``C`` (the
    registry's conditioning of the motion estimators): how well the motions determine the
    nine entries of ``C`` (a near-zero one: a rotation axis the motions never turn about)."""
    Jw, _ = evaluate(ms, C, method).whitened()
    return np.linalg.svd(Jw, compute_uv=False)


def initial_scale(ms: MotionSet, method: str = "magnus4", rate_range=(0.05, 60.0), n_grid: int = 31) -> float:
    """A scalar ``c`` with ``C ≈ c I`` when no nominal sensitivity is known (raw counts).

    The unweighted misfit ``Σ |Rᵀu_a - u_b|²`` of ``C = c I`` on a log grid of ``c``
    (both signs) such that the motions' 99th-percentile raw rate maps into ``rate_range``
    [rad/s], on the motions that turn most (grid steps of 27 %: a 90-180 deg motion stays in
    the right basin; a negative scale only if no positive one fits), then Brent's method
    around the best to 1e-4: a start for the Gauss-Newton fit, not an estimate.
    """
    turn = np.array([np.linalg.norm(ms.y[a:b + 1].sum(axis=0)) for a, b in zip(ms.starts, ms.stops)])
    mags = np.concatenate([np.linalg.norm(ms.y[a:b + 1], axis=1) for a, b in zip(ms.starts, ms.stops)])
    y99 = float(np.percentile(mags, 99))
    if not y99 > 0:
        return 1.0

    def scaled(sub):  # φ_k(c) = c φ1_k + c² φ2_k: the increments of C = c I, computed once
        k, mask = _step_index(sub.starts, sub.stops, len(sub.y))
        lin, _ = _increments(sub.y, sub.h, k, method)
        quad = 0.5 * (_increments(2.0 * sub.y, sub.h, k, method)[0] - 2.0 * lin)
        lin, quad = lin - quad, quad
        ua, ub = sub.u[sub.rest_before], sub.u[sub.rest_after]

        def misfit(c):
            R = total_products(expm_so3(np.where(mask[..., None], c * lin + c * c * quad, 0.0)), mask)
            return float(np.sum((np.einsum("mji,mj->mi", R, ua) - ub) ** 2))
        return misfit

    top = scaled(ms.subset(np.sort(np.argsort(turn)[::-1][:N_SCALE_MOTIONS])))
    grid = np.geomspace(rate_range[0] / y99, rate_range[1] / y99, n_grid)
    best = min((top(c), c) for c in grid)
    if best[0] > 0.1 * min(len(ms.starts), N_SCALE_MOTIONS):  # no good fit with a positive scale: try negative
        best = min(best, min((top(-c), -c) for c in grid))
    step = grid[1] / grid[0]
    return _golden(top, *sorted((best[1] / step, best[1] * step)), xtol=1e-4 * abs(best[1]))


def _golden(f, lo: float, hi: float, xtol: float) -> float:
    """Golden-section minimum of a unimodal ``f`` on ``[lo, hi]`` (no scipy.optimize import for one scalar)."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = f(a), f(b)
    while hi - lo > xtol:
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = f(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = f(b)
    return 0.5 * (lo + hi)


def rotation_angles_deg(R) -> np.ndarray:
    """Angle of each rotation (m, 3, 3) [deg]."""
    return np.rad2deg(np.linalg.norm(log_so3(R), axis=-1))


__all__ = ["CovarianceParts", "Evaluation", "GyroFit", "covariance_parts", "MIN_MOTIONS", "MotionSet", "crlb", "evaluate", "fit_iterative", "fit_one_step",
           "initial_scale", "motion_residuals", "motion_singular_values", "rotation_angles_deg", "tangent_basis"]
