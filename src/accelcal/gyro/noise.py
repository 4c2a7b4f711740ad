"""The gyro's noise between the rests: what carries the motion residuals beyond the rest noise.

The rests measure the gyro's white noise, and the motion fit (:mod:`accelcal.gyro.fit`)
predicts from it how far each motion's integrated rotation may miss the next rest's
gravity.  On real sessions the misfit is 1.7-53 times that, and the motions are not
independent of each other.  Four things carry the excess, each with a covariance of known
shape; the first's size comes from the rests, the others' from the motion residuals:

* **the bias's wander** (rate random walk, PSD ``q`` [raw²/s: rad²/s³ for rad/s] per
  axis), estimated from the rests alone (:func:`bias_wander`: REML on the rest means,
  whose covariance is their own noise plus ``q min(t_i, t_j)``).  The bias removed in a motion is interpolated
  from the rests; the walk's deviation from that interpolation, integrated over the
  motion, is a rotation error (:func:`wander_variance`; fixed, not fitted);
* **a per-motion error of the calibration matrix** (std ``rotation_rel`` of each entry of
  ``E`` in ``C_i = (I + E_i) C``, relative): the motion's rotation error grows with the
  path it turns; a time-stamp or sample-rate error of the motion, a scale or
  misalignment that differs between motions (rate-dependent or asymmetric scale, which
  the linear model cannot follow);
* **extra angle random walk during the motions** (``motion_rate`` [rad/√s]: variance
  growing with the motion's duration): vibration, a hand's tremor the rests do not see;
* **an error of each rest's gravity direction** (``rest_direction`` [rad] per tangent
  component): a rest that is not quite at rest, a placement the accelerometer model
  misses.  It couples the two motions that share a rest.

And **the accelerometer calibration's own uncertainty** (its frame is the gyro's): one
error of every rest's direction, common to the session
(:func:`accelcal.gyro.calibrate.accel_direction_cov`), propagated into the covariance of
``C`` (not into the weights: ``C`` stays in the frame of the accelerometer calibration it
is delivered with).  On SNU good2 the accelerometer's y-x non-orthogonality is ±0.45 deg
(7.9 mrad): the gyro's ``T_xy`` in that frame cannot be known better.

The last three of the list are variance components ``θ`` of the residual covariance
``Σ(θ) = Σ_0 + Σ_k θ_k V_k`` (:func:`accelcal.gyro.fit.covariance_parts`), estimated by
restricted maximum likelihood on the motion residuals (:func:`estimate_components`,
Fisher scoring, ``θ ≥ 0``).  The REML estimate accounts for the nine parameters fitted
to the same residuals; :func:`fit_with_noise` alternates it with the fit of ``C`` until
both settle, so that the weights of the fit and its standard errors come from the same
covariance; the covariance of ``C`` is then adjusted for the components' estimation error
(:func:`adjusted_covariance`, Kenward-Roger), and each parameter's 95 % interval is
``t(0.975, ν) s.e.`` with its Satterthwaite degrees of freedom ``ν``
(:meth:`accelcal.gyro.result.GyroCalibration.interval95`).  A Monte Carlo with a
wandering bias and per-motion errors (``accelcal_repro.gyro.coverage``, 16 motions per
session) covers 0.947 ± 0.004 over 400 sessions with a fitted accelerometer (scales 0.938,
misalignments 0.951; the rest noise alone, scaled by ``max(1, excess)``: 0.841) and
0.950 ± 0.004 over 300 with a perfect one (the rest noise alone: 0.922).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .. import distributions as dist
from .fit import GyroFit, MotionSet, _golden, covariance_parts

#: The variance components estimated from the motion residuals, in the order of ``MotionNoise.variances``.
COMPONENTS = ("rotation_rel", "motion_rate", "rest_direction")
#: Their units (as standard deviations).
UNITS = {"rotation_rel": "relative", "motion_rate": "rad/sqrt(s)", "rest_direction": "rad"}
#: Gauss-Legendre nodes per motion for the wander's integral.
N_QUAD = 24
MAX_ALTERNATIONS = 10
#: The alternation stops when no component's standard deviation moves by more than this fraction.
THETA_TOL = 1e-2


@dataclass(frozen=True)
class MotionNoise:
    """The noise model of the motions of a :class:`~accelcal.gyro.fit.MotionSet` (module docstring)."""

    durations: np.ndarray  #: (m,) duration of each motion [s]
    wander_var: np.ndarray  #: (m, 3) variance of the constant-equivalent bias error from the wander [raw²]
    variances: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(len(COMPONENTS)))  #: θ (3,)
    wander_q: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))  #: PSD of the walk [raw²/s: rad²/s³ for rad/s]
    #: (3p, 3p) joint covariance of the rests' directions from the accelerometer calibration's uncertainty, or None
    direction_cov: np.ndarray | None = None

    def subset(self, idx) -> MotionNoise:
        return dataclasses.replace(self, durations=self.durations[idx], wander_var=self.wander_var[idx])

    def with_variances(self, theta) -> MotionNoise:
        return dataclasses.replace(self, variances=np.asarray(theta, float))

    def to_dict(self) -> dict:
        """Standard deviations by name, and the wander's PSD per axis."""
        out = {k: float(math.sqrt(max(v, 0.0))) for k, v in zip(COMPONENTS, self.variances)}
        out["wander_psd"] = [float(v) for v in self.wander_q]
        out["units"] = dict(UNITS, wander_psd="(raw unit)^2/s")
        return out


# ----------------------------------------------------------------------------- the bias's wander
def _walk_kernel(ta, tb) -> np.ndarray:
    return np.minimum(np.asarray(ta, float)[:, None], np.asarray(tb, float)[None, :])


def _reml_1d(y, X, D, K, q) -> float:
    """REML log-likelihood of ``y ~ N(X β, diag(D) + q K)``."""
    S = np.diag(D) + q * K
    L = np.linalg.cholesky(S)
    Xw, yw = np.linalg.solve(L, X), np.linalg.solve(L, y)
    A = Xw.T @ Xw
    beta = np.linalg.solve(A, Xw.T @ yw)
    e = yw - Xw @ beta
    return -0.5 * (2 * np.sum(np.log(np.diag(L))) + np.linalg.slogdet(A)[1] + e @ e)


def _gls_chi2(y, X, D, K, q) -> float:
    S = np.diag(D) + q * K
    L = np.linalg.cholesky(S)
    Xw, yw = np.linalg.solve(L, X), np.linalg.solve(L, y)
    beta = np.linalg.lstsq(Xw, yw, rcond=None)[0]
    e = yw - Xw @ beta
    return float(e @ e)


def _best_q(y, X, D, K) -> float:
    """The REML ``q ≥ 0``: a log grid around the noise's scale, then golden section in ``log q``."""
    t_span = max(float(K.max() - K.min()), 1e-9)
    q0 = float(np.median(D)) / t_span
    grid = q0 * np.logspace(-4, 6, 41)
    ll = [_reml_1d(y, X, D, K, q) for q in grid]
    k = int(np.argmax(ll))
    if k == 0 and _reml_1d(y, X, D, K, 0.0) >= ll[0]:
        return 0.0
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, len(grid) - 1)])
    return math.exp(_golden(lambda x: -_reml_1d(y, X, D, K, math.exp(x)), lo, hi, 1e-3))


def bias_wander(means, mean_std, t_mid, f_rest=None) -> np.ndarray:
    """PSD ``q`` (3,) [raw²/s: rad²/s³ for rad/s] of the bias's random walk from the rest means (module
    docstring): per axis, REML of ``means ~ N(X β, diag(mean_std²) + q min(t_i, t_j))`` with
    ``X = [1]`` or, with the g-sensitivity, ``[1, f_rest]``."""
    means, se = np.asarray(means, float), np.maximum(np.asarray(mean_std, float), 1e-150)
    t = np.asarray(t_mid, float) - float(np.min(t_mid))
    X = np.ones((len(t), 1)) if f_rest is None else np.column_stack([np.ones(len(t)), np.asarray(f_rest, float)])
    if len(t) <= X.shape[1] + 1:
        return np.zeros(3)
    K = _walk_kernel(t, t)
    return np.array([_best_q(means[:, a], X, se[:, a] ** 2, K) for a in range(3)])


def g_sensitivity_test(means, mean_std, t_mid, f_rest) -> dict:
    """The nested F test of the g-sensitivity on the rest means with the bias's wander in
    their covariance: GLS fits of ``[1]`` and ``[1, f]`` per axis, ``q`` by REML under the
    larger model; ``F = (Δχ²/9) / (χ²_1/dof_1)``."""
    means, se = np.asarray(means, float), np.maximum(np.asarray(mean_std, float), 1e-150)
    t = np.asarray(t_mid, float) - float(np.min(t_mid))
    p = len(t)
    X1 = np.column_stack([np.ones(p), np.asarray(f_rest, float)])
    K = _walk_kernel(t, t)
    q = bias_wander(means, mean_std, t_mid, f_rest)
    chi0 = sum(_gls_chi2(means[:, a], X1[:, :1], se[:, a] ** 2, K, q[a]) for a in range(3))
    chi1 = sum(_gls_chi2(means[:, a], X1, se[:, a] ** 2, K, q[a]) for a in range(3))
    d1, d2 = 9, 3 * (p - 4)
    F = ((chi0 - chi1) / d1) / max(chi1 / d2, 1e-300)
    return {"F": float(F), "p_value": float(dist.f_sf(F, d1, d2)), "dof": [d1, d2],
            "wander_psd": [float(v) for v in q], "test": "GLS F test with the bias's random walk"}


def _interp_weights(t, t_mid) -> np.ndarray:
    """Weights ``a (k, p)`` with ``bias(t) = a @ rest_bias`` for linear interpolation between rest centres."""
    p = len(t_mid)
    return np.column_stack([np.interp(t, t_mid, np.eye(p)[j]) for j in range(p)])


def wander_variance(q, t_mid, t_start, t_end, weights=None, rest_windows=None) -> np.ndarray:
    """Variance (m, 3) of the constant-equivalent bias error of each motion ``[t_start, t_end]``
    from a random walk of PSD ``q`` (3,), when the bias removed is ``weights(t) @ rest means``
    (``weights``: a function of times (k,) -> (k, p); default the linear interpolation
    between the rest centres ``t_mid``, as the bias mode 'interpolated').  A rest mean is
    the walk averaged over its rest (``rest_windows`` (p, 2): first and last time), or its
    value at the centre when the windows are not given."""
    t_mid = np.asarray(t_mid, float)
    t0 = float(t_mid.min()) if rest_windows is None else float(np.min(rest_windows))
    x, wq = np.polynomial.legendre.leggauss(N_QUAD)
    if rest_windows is None:
        nodes, nw = (t_mid - t0)[:, None], np.ones((len(t_mid), 1))
    else:
        rw = np.asarray(rest_windows, float) - t0
        nodes = rw[:, :1] + 0.5 * (rw[:, 1:] - rw[:, :1]) * (x[None] + 1)  # (p, N_QUAD)
        nw = np.broadcast_to(0.5 * wq, nodes.shape)  # averages: the weights sum to 1
    p = len(t_mid)
    flat = nodes.reshape(-1)
    M = (nw.reshape(-1)[:, None] * _walk_kernel(flat, flat) * nw.reshape(-1)[None, :]).reshape(
        p, nodes.shape[1], p, nodes.shape[1]).sum(axis=(1, 3))  # cov of the rest means (unit q)
    out = np.zeros((len(t_start), 3))
    for i, (s1, s2) in enumerate(zip(np.asarray(t_start, float) - t0, np.asarray(t_end, float) - t0)):
        T = s2 - s1
        if T <= 0:
            continue
        tt = s1 + 0.5 * T * (x + 1)
        w = 0.5 * T * wq
        a = _interp_weights(tt + t0, t_mid) if weights is None else weights(tt + t0)
        m = (_walk_kernel(tt, flat) * nw.reshape(-1)[None, :]).reshape(len(tt), p, -1).sum(axis=2)
        k = _walk_kernel(tt, tt) - a @ m.T - m @ a.T + a @ M @ a.T  # cov of w(t) - a(t)·(rest means) per unit q
        out[i] = np.asarray(q, float) * float(w @ k @ w) / (T * T)
    return out


# ----------------------------------------------------------------------------- the components
def _reml_pieces(r, J, S):
    L = np.linalg.cholesky(S)
    Si = np.linalg.solve(L.T, np.linalg.solve(L, np.eye(len(S))))
    SJ = Si @ J
    A = J.T @ SJ
    P = Si - SJ @ np.linalg.solve(A, SJ.T)
    ll = -0.5 * (2 * np.sum(np.log(np.diag(L))) + np.linalg.slogdet(A)[1] + r @ P @ r)
    return P, ll


def estimate_components(parts, theta0=None, max_iter: int = 100) -> np.ndarray:
    """REML estimate of the variance components ``θ ≥ 0`` (module docstring) from the
    residuals of :func:`~accelcal.gyro.fit.covariance_parts` (at the fitted ``C``).

    Fisher scoring with an active set (a component at zero whose score points below zero
    stays there) and step halving on the REML likelihood."""
    r, J = parts.r.reshape(-1), parts.J.reshape(-1, 9)
    V = list(parts.V)
    k = len(V)
    scale = np.array([max(np.trace(parts.fixed) / max(np.trace(v), 1e-300), 1e-300) for v in V])
    theta = np.zeros(k) if theta0 is None else np.maximum(np.asarray(theta0, float), 0.0)
    if theta0 is None:  # start where each component alone would carry the excess, shared
        theta = scale * max(float(r @ np.linalg.solve(parts.fixed, r)) / max(len(r) - 9, 1) - 1.0, 0.0) / k

    def cov(th):
        return parts.fixed + sum(a * v for a, v in zip(th, V))

    P, ll = _reml_pieces(r, J, cov(theta))
    for _ in range(max_iter):
        Pr = P @ r
        PV = [P @ v for v in V]
        score = np.array([0.5 * (Pr @ v @ Pr - np.trace(pv)) for v, pv in zip(V, PV)])
        info = np.array([[0.5 * np.sum(a * b.T) for b in PV] for a in PV])
        free = ~((theta <= 0) & (score <= 0))
        step = np.zeros(k)
        if free.any():
            step[free] = np.linalg.lstsq(info[np.ix_(free, free)], score[free], rcond=None)[0]
        lam, improved = 1.0, False
        while lam > 1e-6:
            cand = np.maximum(theta + lam * step, 0.0)
            Pc, llc = _reml_pieces(r, J, cov(cand))
            if llc >= ll - 1e-10:
                improved = True
                break
            lam *= 0.5
        if not improved:
            break
        done = np.all(np.abs(cand - theta) <= 1e-4 * np.maximum(theta, 1e-3 * scale))
        theta, P, ll = cand, Pc, llc
        if done:
            break
    return theta


@dataclass(frozen=True)
class AdjustedCovariance:
    """The covariance of ``vec(C)`` with estimated variance components (:func:`adjusted_covariance`)
    and what the degrees of freedom of its entries need."""

    cov: np.ndarray  #: (9, 9) Kenward-Roger adjusted
    W: np.ndarray  #: (k, k) covariance of the components estimated (inverse REML information), k not at zero
    dPhi: tuple  #: per component not at zero: ``∂Φ/∂θ`` (9, 9)

    def dof(self, L) -> np.ndarray:
        """Satterthwaite degrees of freedom of the linear functions ``L (k, 9)`` of ``vec(C)``:
        ``2 var² / Var(var̂)`` (inf: no component estimated)."""
        L = np.atleast_2d(np.asarray(L, float))
        var = np.einsum("ki,ij,kj->k", L, self.cov, L)
        if not self.dPhi:
            return np.full(len(L), np.inf)
        g = np.array([np.einsum("ki,ij,kj->k", L, d, L) for d in self.dPhi])  # (c, k)
        v = np.einsum("ck,cd,dk->k", g, self.W, g)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(v > 0, 2.0 * var ** 2 / v, np.inf)


def adjusted_covariance(parts, theta) -> AdjustedCovariance:
    """Covariance (9, 9) of ``vec(C)`` with the variance components estimated: the
    Kenward-Roger (1997) adjustment of ``Φ = (Jᵀ Σ⁻¹ J)⁻¹`` for the estimation error of
    ``θ`` (``Φ + 2 Φ Λ Φ``, ``Λ = Σ_ij W_ij (Q_ij - P_i Φ P_j)``, ``W`` the inverse REML
    information of the components not at zero), and what the Satterthwaite degrees of
    freedom of its entries need.  With a few dozen motions and a component shaped like
    the parameters themselves (a per-motion error of ``C``) the plain ``Φ`` is 10-20 % too
    small (:mod:`accelcal_repro.gyro.coverage`)."""
    J = parts.J.reshape(-1, 9)
    S = parts.fixed + sum(a * v for a, v in zip(theta, parts.V))
    Si = np.linalg.inv(S)
    SJ = Si @ J
    Phi = np.linalg.inv(J.T @ SJ)
    on = [k for k, a in enumerate(theta) if a > 0]
    if not on:
        return AdjustedCovariance(Phi, np.zeros((0, 0)), ())
    P = Si - SJ @ Phi @ SJ.T
    PV = {k: P @ parts.V[k] for k in on}
    info = np.array([[0.5 * np.sum(PV[i] * PV[j].T) for j in on] for i in on])
    W = np.linalg.pinv(info)
    Pk = {k: -SJ.T @ parts.V[k] @ SJ for k in on}  # ∂(Jᵀ Σ⁻¹ J)/∂θ_k
    Lam = np.zeros((9, 9))
    for a, i in enumerate(on):
        for b, j in enumerate(on):
            Q = SJ.T @ parts.V[i] @ Si @ parts.V[j] @ SJ
            Lam += W[a, b] * (Q - Pk[i] @ Phi @ Pk[j])
    return AdjustedCovariance(Phi + 2.0 * Phi @ Lam @ Phi, W, tuple(-Phi @ Pk[k] @ Phi for k in on))


def fit_with_noise(fitter, ms: MotionSet, C0, method: str = "magnus4"
                   ) -> tuple[GyroFit, MotionSet, AdjustedCovariance]:
    """The fit of ``C`` (``fitter``: :func:`~accelcal.gyro.fit.fit_iterative` or the one-step)
    with the variance components of ``ms.noise`` estimated from its residuals, alternated
    until both settle (module docstring).  Returns the last fit (its ``cov`` adjusted),
    ``ms`` with the estimated components, and the adjusted covariance (degrees of freedom)."""
    fit = fitter(ms, C0, method)
    theta = None
    for _ in range(MAX_ALTERNATIONS):
        new = estimate_components(covariance_parts(ms, fit.C, method), theta)
        ms = dataclasses.replace(ms, noise=ms.noise.with_variances(new))
        moved = theta is None or np.any(np.abs(np.sqrt(new) - np.sqrt(theta)) > THETA_TOL * np.sqrt(
            np.maximum(np.maximum(new, theta), 1e-300)))
        theta = new
        fit = fitter(ms, fit.C if fitter.__name__ == "fit_iterative" else C0, method)
        if not moved:
            break
    parts = covariance_parts(ms, fit.C, method)
    adj = adjusted_covariance(parts, ms.noise.variances)
    if ms.noise.direction_cov is not None:
        adj = dataclasses.replace(adj, cov=adj.cov + _accel_part(parts, ms.noise))
    return dataclasses.replace(fit, cov=adj.cov), ms, adj


def _accel_part(parts, mn: MotionNoise) -> np.ndarray:
    """Covariance (9, 9) of ``vec(C)`` from the accelerometer calibration's error: ``D cov_u Dᵀ``
    with ``D = ∂Ĉ/∂u = -Φ Jᵀ Σ⁻¹ A``.  Propagated, not weighted: ``C`` stays in the frame of
    the accelerometer calibration it is delivered with."""
    J = parts.J.reshape(-1, 9)
    S = parts.fixed + sum(a * v for a, v in zip(mn.variances, parts.V))
    SJ = np.linalg.solve(S, J)
    D = np.linalg.solve(J.T @ SJ, SJ.T @ parts.A)
    return D @ mn.direction_cov @ D.T


__all__ = ["AdjustedCovariance", "COMPONENTS", "MotionNoise", "adjusted_covariance", "bias_wander", "estimate_components", "fit_with_noise",
           "g_sensitivity_test", "wander_variance"]
