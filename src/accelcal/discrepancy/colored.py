"""Colored noise in the null: pose residuals whose errors share a slowly wandering bias.

Pose means taken minutes apart share the sensor's slowly wandering bias, so their errors
are correlated, and a trend in them is not by itself evidence of a deterministic drift.
This module is the statistical core of the ``colored`` null of
:func:`accelcal.discrepancy.detect.discrepancy`: the covariance of the pose residuals
implied by a noise model, generalised least squares (GLS) under it, restricted maximum
likelihood (REML) of the wander jointly with the calibration, and nested tests whose
null distribution is calibrated by a parametric bootstrap.

Noise model of the pose means.  Pose ``i`` averages the samples of ``[a_i, a_i + T_i]``;
its mean error on axis ``k`` is ``ē_ik = w̄_ik + β̄_ik`` with

* ``w̄_ik`` the short-term (white, quantization, …) part, independent between poses, of
  variance ``s · se_ik²``: ``se_ik`` the standard error the static detection computed
  from the pose's own samples (Geyer's autocorrelation time, :mod:`accelcal.static`),
  ``s`` a common white scale (≥ :data:`MIN_WHITE_SCALE`), estimated;
* ``β̄_ik`` the interval mean of a slow bias process ``β_k(t)``, the same process
  (``bias_wander``) on every axis, independent between axes, of size ``σ_w`` (data
  unit): a first-order Gauss–Markov process (variance ``σ_w²``, correlation time ``τ``,
  covariance ``σ_w² exp(-|t - t'|/τ)``) or, as ``τ → ∞`` at fixed ``K² = 2 σ_w²/τ``, a
  random walk ``K² min(t, t')`` (the grid of ``τ`` ends with it).

The covariance of two interval means is exact (:func:`accelcal.discrepancy.stochastic.
pose_difference_variance` gives the variogram ``D_ij = Var(β̄_i − β̄_j)`` in closed form;
``−D/2`` is a generalised covariance, equal to the covariance up to terms ``f_i + f_j``
that the per-axis bias of the model absorbs, which is why the random walk and the flicker
floor need no stationary variance).  A pose residual ``r_i = ‖x_i‖ − g`` moves by
``∇_i · ē_i`` with ``∇_i = ∂r_i/∂z_i`` (≈ the unit gravity direction in the sensor frame,
through ``M⁻ᵀ``), so, with ``σ_i² = Σ_k ∇_ik² se_ik²``::

    Cov(r_i, r_j) = s σ_i² δ_ij + σ_w² (∇_i · ∇_j) k_τ(i, j),   k_τ = −D_τ/2 (unit size).

``s`` absorbs a white excess (pose-to-pose disturbances, noise faster than the poses that
the standard errors miss); small ``τ`` (below the pose durations) makes the wander extra
white noise too (``Var ≈ 2 σ_w² τ / T_i``); ``τ`` of the order of the spacing of the poses
is a per-pose (nugget-like) excess; long ``τ`` a slow wander shared by neighbouring
poses.  At ``σ_w = 0`` the model is the ``white`` null's (a common scale).

Linear model.  The test statistics use the model linearised at the current weighted
least-squares fit ``p₀`` (:func:`accelcal.discrepancy.fit.fit`): ``r(p) ≈ r₀ + J (p − p₀)``.
The neglected terms are of the order of (noise / g)² relative (≈ 1e-8 for a MEMS pose
mean), far below anything the tests resolve.  Whitened by ``σ`` and projected on the
``n − 3`` orthonormal contrasts ``L`` orthogonal to the three bias columns (which removes
the bias and, with it, the ambiguity of the generalised covariance), the data are
``y = Lᵀ r₀/σ ~ N(−X β, s (I + q K_τ))`` with ``X`` the other columns (six scale and
misalignment parameters, the named effects, the candidate) and ``q`` the wander
variance relative to the white one, the whole times the white scale ``s``.  ``K_τ`` is
diagonalised once per ``τ`` of a grid
(five per decade from a tenth of the shortest pose to ten session lengths, then the
random walk), so every likelihood on the grid costs ``O(n p)``.

Estimation (REML).  The noise ``(s, q, τ)`` is estimated jointly with the calibration by
restricted maximum likelihood: ``−2ℓ_R = log|Σ| + log|XᵀΣ⁻¹X| + yᵀ P y``, ``s``
profiled analytically (``ŝ = yᵀPy/(m − p)`` at ``Σ = s (I + q K_τ)``).  Confidence
intervals are profile-likelihood intervals: the range of a quantity over the set where
``−2ℓ_R`` is within ``χ²₁(0.95) = 3.84`` of its minimum; the estimate and the intervals
are taken on a fine grid (ten values per decade of ``τ`` and of ``q``: a resolution of
±12 %, well inside any interval the poses give).  Intervals that reach the ends of the grid are reported open (the data cannot
bound them); a wander the contrasts cannot see is reported as not estimated with the
reason, never replaced by white noise silently.

Tests (likelihood ratio, parametric bootstrap).  Current model vs current + effect: the
likelihood ratio ``LR = −2 (ℓ₀ − ℓ₁)`` of the maximum likelihoods over the parameters
*and* the noise, each model re-estimating ``(s, q, τ)`` (``s`` analytically, ``(q, τ)`` on
the same grid).  Its null distribution is not χ²₃: maximum likelihood underestimates a
variance by the share of the fixed effects, more so for the larger model, and the wander
trades off against slow effects, so ``LR`` is stretched (by 1.2–1.6 for most effects and
up to 3 for ``bias_drift`` under a random-walk-like wander: ``bartlett`` in the output).
The p-value comes from ``n_boot`` data sets simulated under the fitted null (the current
model with its REML noise) and refitted with both models exactly as the data:
``p = (1 + #{LR* ≥ LR})/(n_boot + 1)``.  Because ``LR`` is invariant to the fixed effects
of the null and to the scale ``s``, the bootstrap needs only ``(q, τ)``; and since ``LR``
is asymptotically pivotal (χ²₃ whatever the noise parameters), the bootstrap p-value is
second-order accurate (a scale-only, Bartlett-type correction was tried and rejected: on
sessions with three Gauss–Markov components it gave 8 % false positives at α = 5 %).
Its guarantee: effect-free recordings whose noise is of this family get an effect named
with probability ≤ α (up to the Monte Carlo error of a finite ``n_boot``), however
large the wander.  A wander outside the family (several Gauss–Markov components,
flicker) is approximated by the nearest member; the tests check the false-positive rate
on such sessions.

Outliers.  Pose ``i`` is an outlier when its residual is shifted: the mean-shift model
adds a free shift to that pose alone (equivalent to leaving it out).  Its likelihood
ratio against the current model, with the wander re-estimated under both (so that an
outlier cannot hide by inflating the wander estimate), is ``(P r)_i² / P_ii``
minimised over the grid (a rank-one update of the GLS fit; ``P`` the GLS residual
projector, ``(P r)_i / sqrt(P_ii)`` the studentised residual).  The family of the ``n``
poses is tested with the largest of these ratios against the same statistic on the
bootstrap replicates, which accounts for the multiplicity and the correlation between
poses exactly.

Leave-one-pose-out.  ``(P r)_i / P_ii`` is the error of predicting pose ``i`` from the
others under the GLS model, including the wander's conditional mean given the
neighbouring poses (kriging); its RMS in units of ``σ`` is the colored LOPO gap.

Assumptions.  Gaussian errors; the per-pose standard errors of the rests are right for
the short-term noise up to the common factor ``s ≥ 0.5``; one wander process, of the
same size on the three axes (data unit), independent between axes, of the Gauss–Markov /
random-walk family (a sum of components or a flicker floor is approximated by its nearest
member: the tests measure what that costs); the poses' gradients at the linearisation
point.  The per-pose standard errors are computed from the pose's own samples, so noise
with a correlation time near the pose durations is partly counted in both (it then
shows as a smaller ``σ_w`` or ``s``); the interval-mean covariance is exact for the
wander as modelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ..errors import AccelcalError
from .stochastic import pose_difference_variance  # noqa: F401 (re-exported for the loop)

#: Relative wander variance ``q`` (over the white variance of the contrasts) the tests
#: profile over: 0, then three per decade (the likelihood is smooth in log q: the grid
#: maximum is within a few hundredths of the continuous one, the same for data and replicates).
Q_REL_GRID = np.concatenate([[0.0], np.logspace(-2.0, 3.0, 16)])
#: Correlation times per decade of the grid of the tests, and of the report's profile.
TAU_PER_DECADE = 5
TAU_PER_DECADE_FINE = 10
#: ``χ²₁`` quantile of the 95 % profile-likelihood intervals.
CHI2_95 = float(stats.chi2.isf(0.05, 1))
#: Residual degrees of freedom (poses − parameters) the wander's two parameters need at
#: least (a variance from 6 degrees of freedom has a relative standard error of 58 %).
MIN_WANDER_DOF = 6
#: Instantaneous poses (no intervals known) are given this duration [s].
POINT_DURATION = 1e-3


class WanderError(AccelcalError):
    """The pose residuals cannot support the colored null (too few poses, degenerate design)."""


# --------------------------------------------------------------------------- kernels


def tau_grid(durations, span: float, per_decade: int = TAU_PER_DECADE) -> np.ndarray:
    """Correlation times [s]: ``per_decade`` per decade from a tenth of the shortest pose
    to ten session lengths, then ``inf`` (the random walk)."""
    lo = 0.1 * max(float(np.min(durations)), POINT_DURATION)
    hi = 10.0 * max(span, 10 * lo)
    k = int(math.ceil(math.log10(hi / lo) * per_decade))
    return np.concatenate([np.geomspace(lo, hi, k + 1), [np.inf]])


def wander_kernel(tau: float, starts, durations, grad) -> np.ndarray:
    """Generalised covariance of the pose residuals from a unit-size wander (module docstring).

    ``tau`` finite: Gauss–Markov of unit variance; ``inf``: random walk with ``K = 1``.
    Returns ``(∇_i · ∇_j) (−D_ij / 2)`` (n, n).
    """
    if np.isinf(tau):
        D = pose_difference_variance("random_walk", 1.0, starts, durations)
    else:
        D = pose_difference_variance("gauss_markov", (1.0, float(tau)), starts, durations)
    return -0.5 * (grad @ grad.T) * D


def gm_variance(q_abs: float, tau: float) -> tuple[float, float]:
    """``(s, K)`` of a wander: Gauss–Markov std ``s`` and its short-lag random-walk
    coefficient ``K = sqrt(2 s²/τ)``; for ``tau = inf``, ``q_abs`` is ``K²`` and ``s = inf``."""
    if np.isinf(tau):
        return float("inf") if q_abs > 0 else 0.0, math.sqrt(max(q_abs, 0.0))
    return math.sqrt(max(q_abs, 0.0)), math.sqrt(2.0 * max(q_abs, 0.0) / tau)


# --------------------------------------------------------------------------- the linearised problem


@dataclass(frozen=True)
class Problem:
    """One linearisation of the pose residuals in whitened contrast coordinates.

    Attributes
    ----------
    y : ndarray (m,)
        ``Lᵀ r₀/σ``, ``m = n − 3``.
    X0 : ndarray (m, p)
        Columns of the current model other than the bias, ``Lᵀ J/σ``.
    L : ndarray (n, m)
        Orthonormal contrasts (whitened space) orthogonal to the bias columns.
    sigma, grad : ndarray
        ``σ_i`` (n,) and ``∇_i`` (n, 3).
    starts, durations : ndarray (n,)
    taus : ndarray (T,)
    lam : ndarray (T, m)
        Eigenvalues of the kernels in the contrasts, divided by their mean ``scale``.
    V : ndarray (T, m, m)
        Their eigenvectors.
    scale : ndarray (T,)
        Mean eigenvalue of each kernel (``q_abs = q / scale``).
    """

    y: np.ndarray
    X0: np.ndarray
    L: np.ndarray
    sigma: np.ndarray
    grad: np.ndarray
    starts: np.ndarray
    durations: np.ndarray
    taus: np.ndarray
    lam: np.ndarray
    V: np.ndarray
    scale: np.ndarray
    notes: tuple = field(default_factory=tuple)

    @property
    def m(self) -> int:
        return self.y.shape[0]

    @property
    def span(self) -> float:
        return float(np.max(self.starts + self.durations) - np.min(self.starts))

    def columns(self, J) -> np.ndarray:
        """Contrast columns of unweighted Jacobian columns ``J`` (n, k)."""
        return self.L.T @ (np.asarray(J, float) / self.sigma[:, None])

    def kernel(self, tau: float) -> np.ndarray:
        """Contrast kernel (m, m) of a unit wander with correlation time ``tau``."""
        K = wander_kernel(tau, self.starts, self.durations, self.grad)
        Kw = K / self.sigma[:, None] / self.sigma[None, :]
        return self.L.T @ Kw @ self.L

    def with_taus(self, taus) -> Problem:
        """The same problem on another grid of correlation times."""
        lam, V, scale = _eigen(self, taus)
        return Problem(self.y, self.X0, self.L, self.sigma, self.grad, self.starts, self.durations,
                       np.asarray(taus, float), lam, V, scale, self.notes)

    def sigma_c(self, t: int, q: float) -> np.ndarray:
        """Contrast covariance ``I + q K_τ`` at grid point ``(t, q)`` (relative ``q``)."""
        V = self.V[t]
        return (V * (1.0 + q * self.lam[t])) @ V.T


def _eigen(prob, taus):
    m = prob.L.shape[1]
    lam = np.empty((len(taus), m))
    V = np.empty((len(taus), m, m))
    scale = np.empty(len(taus))
    for i, tau in enumerate(taus):
        Kc = prob.kernel(tau)
        Kc = 0.5 * (Kc + Kc.T)
        ev, vec = np.linalg.eigh(Kc)
        ev = np.clip(ev, 0.0, None)  # round-off: the projected kernel is positive semi-definite
        s = float(ev.mean())
        scale[i] = s if s > 0 else 1.0
        lam[i], V[i] = ev / scale[i], vec
    return lam, V, scale


def problem(r, J, sigma, grad, starts, durations, taus=None, notes=()) -> Problem:
    """Build the :class:`Problem` of a fit: residuals ``r`` (n,), Jacobian ``J`` (n, q) whose
    first three columns are the bias, ``σ`` (n,), gradients ``∇`` (n, 3), pose intervals.

    Raises
    ------
    WanderError
        Fewer contrasts than columns + 2 (nothing left to estimate the wander from).
    """
    r, J, sigma, grad = (np.asarray(a, float) for a in (r, J, sigma, grad))
    n = r.shape[0]
    starts, durations = np.asarray(starts, float), np.asarray(durations, float)
    Jb = J[:, :3] / sigma[:, None]
    U, s, _ = np.linalg.svd(Jb, full_matrices=True)
    if s.size < 3 or s[-1] <= 1e-12 * s[0]:
        raise WanderError("the poses do not determine the three biases (degenerate orientations)")
    L = U[:, 3:]
    X0 = L.T @ (J[:, 3:] / sigma[:, None])
    if n - J.shape[1] < MIN_WANDER_DOF:
        raise WanderError(f"{n} poses leave {n - J.shape[1]} residual degrees of freedom for {J.shape[1]} "
                          f"parameters: the bias wander (size and correlation time) needs at least "
                          f"{MIN_WANDER_DOF}, i.e. {J.shape[1] + MIN_WANDER_DOF} poses")
    y = L.T @ (r / sigma)
    taus = tau_grid(durations, float(np.max(starts + durations) - np.min(starts))) if taus is None else taus
    prob = Problem(y, X0, L, sigma, grad, starts, durations, np.asarray(taus, float),
                   np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0), tuple(notes))
    return prob.with_taus(prob.taus)


# --------------------------------------------------------------------------- likelihood on the grid


#: Smallest white scale ``s`` the noise model may take.  The rests measure the white noise
#: of each pose directly (hundreds of samples per pose); the static detection's standard
#: errors overestimate it by 10-25 % in variance (Geyer's sum of positive autocorrelation
#: pairs: residual excess 0.81-0.87 on simulated white noise).  Without a floor the model
#: could explain a deterministic trend as a large random walk with almost no white noise,
#: which the rests contradict.
MIN_WHITE_SCALE = 0.5


def _neg2ll(quad, nu, logdet):
    """``−2 log`` likelihood with the white scale at its optimum ``max(quad/nu, MIN_WHITE_SCALE)``
    (``nu log s + quad/s + logdet``, constants dropped)."""
    quad = np.clip(quad, 1e-300, None)
    s = np.maximum(quad / nu, MIN_WHITE_SCALE)
    return nu * np.log(s) + quad / s + logdet


@dataclass(frozen=True)
class Surface:
    """Likelihood of data sets over the grid of ``(τ, q)``, the white scale ``s`` profiled out.

    ``quad`` (B, T, Q): ``yᵀ P y`` with ``P`` the GLS residual projector of ``I + q K_τ``;
    ``logdet`` (T, Q): ``log|I + q K_τ|``; ``logdet_a`` (T, Q): ``log|Xᵀ(I + q K_τ)⁻¹X|``;
    ``m`` contrasts, ``p`` columns; ``shift_quad`` (B, T, Q, n) or None: ``quad`` of the
    model with a free shift of each pose.  With ``Σ = s (I + q K_τ)``, ``s`` at its optimum
    ``ŝ = max(quad/ν, MIN_WHITE_SCALE)``, ``ν = m`` (ML) or ``m − p`` (REML)::

        −2ℓ   = m log ŝ + quad/ŝ + logdet                  (+ constants)
        −2ℓ_R = (m − p) log ŝ + quad/ŝ + logdet + logdet_a
    """

    quad: np.ndarray
    logdet: np.ndarray
    logdet_a: np.ndarray
    m: int
    p: int
    shift_quad: np.ndarray | None = None

    @property
    def ml(self) -> np.ndarray:
        return _neg2ll(self.quad, self.m, self.logdet[None])

    @property
    def reml(self) -> np.ndarray:
        return _neg2ll(self.quad, self.m - self.p, self.logdet[None]) + self.logdet_a[None]

    def white_scale(self, reml: bool = True) -> np.ndarray:
        """``ŝ`` at every grid point (B, T, Q)."""
        return np.maximum(self.quad / (self.m - self.p if reml else self.m), MIN_WHITE_SCALE)

    def ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` per data set (B,)."""
        return self.ml.reshape(self.ml.shape[0], -1).min(axis=1)

    def shift_ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` of the model with pose ``i`` shifted, per data set (B, n)."""
        ml = _neg2ll(self.shift_quad, self.m, self.logdet[None, :, :, None])
        return ml.reshape(ml.shape[0], -1, ml.shape[-1]).min(axis=1)


def profile(prob: Problem, X: np.ndarray, Y: np.ndarray, qrel, shifts: bool = False) -> Surface:
    """The likelihood :class:`Surface` of data sets ``Y`` (B, m) under the model with columns
    ``X`` (m, p), over the grid ``prob.taus`` × ``qrel`` ((Q,), or (T, Q): one row per τ).

    ``shifts``: also the model with a free shift of pose ``i``'s residual, for every pose
    (the outlier model): ``quad − (P r)_i²/P_ii`` (a rank-one update of the GLS fit, ``P``
    the residual projector in the pose space).
    """
    qrel = np.asarray(qrel, float)
    Y = np.atleast_2d(Y)
    T = prob.taus.size
    q = np.broadcast_to(qrel, (T, qrel.shape[-1]))            # (T, Q)
    p = X.shape[1]
    Yr = Y[None] @ prob.V                                      # (T, B, m): rotated data
    one = 1.0 + q[:, :, None] * prob.lam[:, None, :]           # (T, Q, m)
    w = 1.0 / one
    quad = (Yr * Yr) @ w.transpose(0, 2, 1)                    # (T, B, Q)
    logdet = np.log(one).sum(axis=2)                           # (T, Q)
    logdet_a = np.zeros(q.shape)
    resid = Yr.transpose(0, 2, 1)[:, None]                     # (T, 1, m, B) before the fixed effects
    if p:
        Xr = prob.V.transpose(0, 2, 1) @ X                     # (T, m, p)
        B = Y.shape[0]
        # A = Xrᵀ diag(w) Xr and b = Xrᵀ diag(w) Yrᵀ for every q, each as one product
        # over m (one matrix product per τ: BLAS, not a batch of small ones)
        XX = (Xr[:, :, :, None] * Xr[:, :, None, :]).reshape(T, -1, p * p)
        A = (w @ XX).reshape(T, -1, p, p)                      # (T, Q, p, p)
        XY = (Xr[:, :, :, None] * Yr.transpose(0, 2, 1)[:, :, None, :]).reshape(T, -1, p * B)
        b = (w @ XY).reshape(T, -1, p, B)                      # (T, Q, p, B)
        ci = np.linalg.inv(np.linalg.cholesky(A))
        u = ci @ b                                             # c⁻¹ b
        quad = quad - np.einsum("tqpb,tqpb->tbq", u, u)
        logdet_a = -2.0 * np.log(np.diagonal(ci, axis1=2, axis2=3)).sum(axis=2)
    quad = quad.transpose(1, 0, 2)                             # (B, T, Q)
    shift_quad = None
    if shifts:
        LV = prob.L @ prob.V                                   # (T, n, m): poses from rotated contrasts
        if p:
            beta = np.swapaxes(ci, 2, 3) @ u                   # (T, Q, p, B)
            resid = resid - Xr[:, None] @ beta                 # (T, Q, m, B)
            H = np.swapaxes(Xr[:, None] * w[:, :, :, None], 2, 3) @ np.swapaxes(LV, 1, 2)[:, None]
            CH = ci @ H                                        # (T, Q, p, n)
            d = np.swapaxes((LV * LV) @ np.swapaxes(w, 1, 2), 1, 2) - np.einsum("tqpn,tqpn->tqn", CH, CH)
        else:
            d = np.swapaxes((LV * LV) @ np.swapaxes(w, 1, 2), 1, 2)
        z = LV[:, None] @ (w[:, :, :, None] * resid)           # (T, Q, n, B): (P r)_i
        gain = z * z / np.clip(d, 1e-300, None)[..., None]
        shift_quad = np.clip(quad.transpose(1, 2, 0)[:, :, None, :] - gain, 1e-300, None)  # (T, Q, n, B)
        shift_quad = shift_quad.transpose(3, 0, 1, 2)          # (B, T, Q, n)
    return Surface(quad, logdet, logdet_a, prob.m, p, shift_quad)


def gls_projector(prob: Problem, X: np.ndarray, t: int, q: float) -> np.ndarray:
    """GLS residual projector in the whitened pose space, ``L P_c Lᵀ`` (n, n), at ``(t, q)``
    for the unit white scale: ``P_c = Σ⁻¹ − Σ⁻¹X(XᵀΣ⁻¹X)⁻¹XᵀΣ⁻¹``, ``Σ = I + q K_τ`` in the
    contrasts.  ``(P r/σ)_i`` is the GLS residual of pose ``i`` in precision form (bias
    included as a fixed effect)."""
    V = prob.V[t]
    w = 1.0 / (1.0 + q * prob.lam[t])
    Si = (V * w) @ V.T
    if X.shape[1]:
        SX = Si @ X
        Pc = Si - SX @ np.linalg.solve(X.T @ SX, SX.T)
    else:
        Pc = Si
    return prob.L @ Pc @ prob.L.T


def studentised(prob: Problem, X: np.ndarray, t: int, q: float, Y=None, scale: float = 1.0):
    """GLS studentised residuals ``(P r)_i/sqrt(s P_ii)`` and leave-one-pose-out prediction
    errors ``(P r)_i/P_ii`` (in units of σ) of data ``Y`` (B, m) (default: the data), at the
    wander ``(t, q)`` and white scale ``s``."""
    P = gls_projector(prob, X, t, q)
    d = np.clip(np.diag(P), 1e-300, None)
    Y = prob.y[None] if Y is None else np.atleast_2d(Y)
    Pr = (Y @ prob.L.T) @ P.T                       # (B, n)
    return Pr / np.sqrt(scale * d), Pr / d


# --------------------------------------------------------------------------- fitted wander


@dataclass(frozen=True)
class WanderFit:
    """REML estimate of the noise model ``s (I + q K_τ)`` under one model, with its
    profile-likelihood intervals.

    ``white_scale`` = ``ŝ`` (variance of the white part over the rests' prediction);
    ``q_rel`` the wander's variance relative to the white one in the contrasts (the tests'
    scale), ``q_abs`` in the data unit squared (``s_w²``, the wander's variance; ``K²`` for
    the random walk), ``size`` its std, ``K`` its short-lag random-walk coefficient.
    """

    t: int
    q_rel: float
    tau: float
    q_abs: float
    size: float
    K: float
    white_scale: float
    reml: float
    size_ci: tuple
    tau_ci: tuple
    K_ci: tuple
    white_scale_ci: tuple
    excess_ci: tuple
    at_bound: tuple

    @property
    def present(self) -> bool:
        return self.q_rel > 0


#: Relative variances of the report's grid: 0, then ten per decade.
Q_REL_FINE = np.concatenate([[0.0], np.logspace(-3.0, 4.0, 71)])
#: White-scale factors (over the conditional estimate) the report's intervals scan.
S_FACTORS = np.logspace(-1.0, 1.0, 81)


def fit_wander(prob: Problem, X: np.ndarray, fine: bool = True) -> WanderFit:
    """REML estimate of ``(s, q, τ)`` for fixed-effect columns ``X``, with 95 % profile intervals.

    ``fine``: estimate and intervals on a grid of ten ``τ`` and ten ``q`` per decade (what
    the report uses); otherwise the test grid, without intervals.
    """
    if not fine:
        sf = profile(prob, X, prob.y[None], Q_REL_GRID)
        reml = sf.reml[0]
        t, k = np.unravel_index(int(np.argmin(reml)), reml.shape)
        return _wander_at(prob, int(t), float(Q_REL_GRID[k]), float(sf.white_scale()[0, t, k]), float(reml[t, k]))
    fp = prob.with_taus(tau_grid(prob.durations, prob.span, TAU_PER_DECADE_FINE))
    sf = profile(fp, X, fp.y[None], Q_REL_FINE)
    nu = max(sf.m - sf.p, 1)
    quad = sf.quad[0]                                           # (T, Q)
    dev = sf.reml[0]
    tf, kf = np.unravel_index(int(np.argmin(dev)), dev.shape)
    best = float(dev[tf, kf])
    s_hat = sf.white_scale()[0]
    # the full deviance over (τ, q, s), s = f ŝ(τ, q) on a scan around the optimum (above the floor)
    s_full = s_hat[:, :, None] * S_FACTORS[None, None, :]
    dev_full = (nu * np.log(s_full) + quad[:, :, None] / s_full + sf.logdet[:, :, None]
                + sf.logdet_a[:, :, None])
    inside = (dev_full <= best + CHI2_95) & (s_full >= MIN_WHITE_SCALE * (1 - 1e-12))   # (T, Q, S)
    taus = fp.taus
    q_abs = s_full * Q_REL_FINE[None, :, None] / fp.scale[:, None, None]
    rw = np.isinf(taus)[:, None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.where(rw, np.inf, np.sqrt(q_abs))
        K = np.where(rw, np.sqrt(q_abs), np.sqrt(2 * q_abs / np.where(rw, 1.0, taus[:, None, None])))
    # the residual excess the model predicts on average: sqrt(s (1 + q)) (mean eigenvalue 1)
    excess = np.sqrt(s_full * (1.0 + Q_REL_FINE[None, :, None]))
    wander = inside & (Q_REL_FINE[None, :, None] > 0)
    bound = []
    if inside[:, -1].any():
        bound.append("size: upper end of the grid (q_rel 1e4)")
    if wander[-1].any() or wander[-2].any():
        bound.append("tau: the interval reaches the random walk (no upper bound)")
    if wander[0].any():
        bound.append("tau: lower end of the grid")
    if inside[:, :, 0].any() or inside[:, :, -1].any():
        bound.append("white scale: end of the scanned range (x0.1 - x10 of its estimate)")
    if np.isclose(s_hat[tf, kf], MIN_WHITE_SCALE):
        bound.append(f"white scale: at its floor {MIN_WHITE_SCALE:g}")

    def rng(a, mask):
        v = a[mask]
        return (float(np.min(v)), float(np.max(v))) if v.size else (float("nan"), float("nan"))

    tau_ci = rng(np.broadcast_to(taus[:, None, None], inside.shape), wander)
    size_ci, K_ci = rng(size, inside), rng(K, inside)
    if inside[:, 0, :].any():  # q = 0 inside the region: the lower ends are 0
        size_ci, K_ci = (0.0, size_ci[1]), (0.0, K_ci[1])
    out = _wander_at(fp, int(tf), float(Q_REL_FINE[kf]), float(s_hat[tf, kf]), best)
    return WanderFit(**{**out.__dict__, "size_ci": size_ci, "tau_ci": tau_ci, "K_ci": K_ci,
                        "white_scale_ci": rng(s_full, inside), "excess_ci": rng(excess, inside),
                        "at_bound": tuple(bound)})


def _wander_at(prob: Problem, t: int, q_rel: float, s_hat: float, reml: float) -> WanderFit:
    tau = float(prob.taus[t])
    q_abs = s_hat * q_rel / float(prob.scale[t])
    size, K = gm_variance(q_abs, tau)
    nan2 = (float("nan"), float("nan"))
    return WanderFit(t=t, q_rel=q_rel, tau=tau, q_abs=q_abs, size=size, K=K, white_scale=s_hat, reml=reml,
                     size_ci=nan2, tau_ci=nan2, K_ci=nan2, white_scale_ci=nan2, excess_ci=nan2, at_bound=())


# --------------------------------------------------------------------------- tests


@dataclass(frozen=True)
class RoundTests:
    """Bootstrap tests of one round: every candidate's LR and the outlier family."""

    lr: np.ndarray              # (k,) observed LR per candidate
    p_values: np.ndarray        # (k,) bootstrap p-values (1 + #{LR* ≥ LR})/(n_boot + 1)
    bartlett: np.ndarray        # (k,) mean(LR*)/3: how much estimating the noise stretches LR
    outlier_t: np.ndarray       # (n,) studentised residuals of the data (current model, null noise)
    outlier_p: float            # bootstrap p-value of the largest mean-shift LR
    outlier_pose: int           # index (into the current pose set) of the largest mean-shift LR
    outlier_lr: float           # that likelihood ratio
    null_wander: WanderFit      # the noise the bootstrap simulates (current model, REML)
    n_boot: int


def round_tests(prob: Problem, X_alts: list, rng: np.random.Generator, n_boot: int,
                outliers: bool = True, extend=None, n_boot_max: int | None = None) -> RoundTests:
    """Likelihood-ratio tests current (``prob.X0``) vs current + each ``X_alts[k]``
    (contrast columns, appended to X0) and the outlier family, all calibrated on the same
    ``n_boot`` data sets simulated under the current model with its REML noise.

    ``extend(counts, n)`` (optional): given the exceedance counts of the candidates (and,
    last, of the outlier family) after ``n`` replicates, True when more replicates could
    change a decision; the bootstrap then grows to ``n_boot_max`` replicates (the first
    ``n_boot`` are the same draws either way)."""
    X0 = prob.X0
    sf0 = profile(prob, X0, prob.y[None], Q_REL_GRID, shifts=outliers)
    m0 = float(sf0.ml_min()[0])
    # the bootstrap simulates the REML noise of the current model.  (Estimating it with the
    # most outlying pose free, against masking, was tried: under a random-walk wander it
    # lowered the simulated noise and raised the outlier family's false positives from
    # 7.5 % to 11 % and the candidates' from 5.3 % to 7.2 %, 120 sessions each.)
    null = fit_wander(prob, X0, fine=False)
    Xs = [np.hstack([X0, Xa]) for Xa in X_alts]
    lr = np.array([max(m0 - float(profile(prob, X1, prob.y[None], Q_REL_GRID).ml_min()[0]), 0.0) for X1 in Xs])
    lr_pose = np.maximum(m0 - sf0.shift_ml_min()[0], 0.0) if outliers else np.zeros(0)
    o_i = int(np.argmax(lr_pose)) if outliers else -1
    o_lr = float(lr_pose[o_i]) if outliers else float("nan")
    counts, lr_sum, n, batch = np.zeros(len(Xs) + 1, dtype=np.int64), np.zeros(len(Xs)), 0, n_boot
    while batch > 0:
        c, s = _bootstrap_batch(prob, X0, Xs, null, lr, o_lr, rng.standard_normal((batch, prob.m)), outliers)
        counts, lr_sum, n = counts + c, lr_sum + s, n + batch
        more = extend is not None and n_boot_max is not None and n < n_boot_max
        batch = n_boot_max - n if more and extend(counts[: len(Xs) + outliers], n) else 0
    p = (1 + counts[: len(Xs)]) / (n + 1)
    scale = lr_sum / n / np.array([Xa.shape[1] for Xa in X_alts]) if X_alts else np.zeros(0)
    o_p = float((1 + counts[-1]) / (n + 1)) if outliers else float("nan")
    t_obs, _ = studentised(prob, X0, null.t, null.q_rel, scale=null.white_scale)
    return RoundTests(lr=lr, p_values=p, bartlett=scale, outlier_t=t_obs[0], outlier_p=o_p, outlier_pose=o_i,
                      outlier_lr=o_lr, null_wander=null, n_boot=int(n))


def _bootstrap_batch(prob: Problem, X0, Xs, null: WanderFit, lr, o_lr: float, Z: np.ndarray, outliers: bool):
    """Replicates ``y* = V diag(sqrt(s (1 + q λ))) z`` under the null, refitted as the data:
    per candidate (and, last, the outlier family) the count of replicate statistics at or
    above the observed one, and per candidate the sum of the replicate LRs."""
    V, lam = prob.V[null.t], prob.lam[null.t]
    Ystar = (Z * np.sqrt(null.white_scale * (1.0 + null.q_rel * lam))[None, :]) @ V.T
    sfs = profile(prob, X0, Ystar, Q_REL_GRID, shifts=outliers)
    m0s = sfs.ml_min()
    tol = 1e-9 * max(1.0, float(np.max(lr, initial=0.0)))
    counts, sums = np.zeros(len(Xs) + 1, dtype=np.int64), np.zeros(len(Xs))
    for k, X1 in enumerate(Xs):
        lrs = np.maximum(m0s - profile(prob, X1, Ystar, Q_REL_GRID).ml_min(), 0.0)
        counts[k], sums[k] = np.sum(lrs >= lr[k] - tol), float(np.sum(lrs))
    if outliers:
        # the mean-shift likelihood ratio of each pose, the noise re-estimated with the
        # shift (so an outlier cannot hide by inflating it): its maximum over the poses
        # against the same statistic on the replicates
        lrs_max = np.maximum(m0s[:, None] - sfs.shift_ml_min(), 0.0).max(axis=1)
        counts[-1] = np.sum(lrs_max >= o_lr - 1e-9 * max(1.0, o_lr))
    return counts, sums


# --------------------------------------------------------------------------- information, MDE, GLS


def effect_information(prob: Problem, X0: np.ndarray, Xe: np.ndarray, t: int | None = None, q: float = 0.0,
                       sigma_c: np.ndarray | None = None) -> dict:
    """Fisher information of an effect block ``Xe`` profiled over ``X0``: under the wander
    ``(t, q)`` or the contrast covariance ``sigma_c`` (``colored``), under white noise
    (``white``) and under white noise of the same mean variance (``scaled_white``: what a
    common scale factor would give)."""
    if sigma_c is None:
        V = prob.V[t]
        w = 1.0 / (1.0 + q * prob.lam[t])
        Si = (V * w) @ V.T
        mean_var = float(np.mean(1.0 + q * prob.lam[t]))
    else:
        Si = np.linalg.inv(sigma_c)
        mean_var = float(np.trace(sigma_c)) / prob.m

    def info(S):
        SX = S @ X0
        P = S - SX @ np.linalg.solve(X0.T @ SX, SX.T) if X0.shape[1] else S
        return Xe.T @ P @ Xe

    I_white = info(np.eye(prob.m))
    return {"colored": info(Si), "white": I_white, "scaled_white": I_white / mean_var}


def contrast_covariance(prob: Problem, terms: dict) -> np.ndarray:
    """Contrast covariance ``I + K`` of the white per-pose noise plus a noise model ``terms``
    (as :func:`simulate_interval_means` takes it, several components allowed) projected
    like the wander: the truth of a simulation, for its MDE."""
    S = np.eye(prob.m)
    for k, v in terms.items():
        for vi in (v if isinstance(v, list) else [v]):
            D = pose_difference_variance(k, vi, prob.starts, prob.durations)
            K = -0.5 * (prob.grad @ prob.grad.T) * D / prob.sigma[:, None] / prob.sigma[None, :]
            S = S + prob.L.T @ K @ prob.L
    return S


def gls_step(prob: Problem, X: np.ndarray, t: int, q: float, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """GLS estimate of the linearised parameter change ``β`` (``y ≈ −X β``) and its covariance
    under ``scale (I + q K_τ)``."""
    V = prob.V[t]
    w = 1.0 / (1.0 + q * prob.lam[t])
    Si = (V * w) @ V.T
    A = X.T @ Si @ X
    cov = np.linalg.inv(A)
    beta = -cov @ (X.T @ Si @ prob.y)
    return beta, scale * cov


def at(prob: Problem, w: WanderFit) -> tuple[Problem, float]:
    """The one-τ problem of a fitted noise ``w`` and its relative wander variance there
    (``q_abs = s q / scale_τ``: the same wander whatever the grid it was found on)."""
    p1 = prob.with_taus([w.tau])
    return p1, float(w.q_abs * p1.scale[0] / w.white_scale) if w.white_scale > 0 else 0.0


def excess_distribution(prob: Problem, X: np.ndarray, t: int, q: float, scale: float = 1.0) -> np.ndarray:
    """Eigenvalues ``μ`` of ``(I − H) Σ_c (I − H)`` (``H`` the unweighted hat of ``X``,
    ``Σ_c = scale (I + q K_τ)``): under the noise model the weighted χ² of the least-squares
    residuals is ``Σ μ_k χ²₁``."""
    Q, _ = np.linalg.qr(X) if X.shape[1] else (np.zeros((prob.m, 0)), None)
    R = np.eye(prob.m) - Q @ Q.T
    S = scale * prob.sigma_c(t, q)
    mu = np.linalg.eigvalsh(R @ S @ R)
    return np.clip(mu, 0.0, None)



# --------------------------------------------------------------------------- simulation


def simulate_interval_means(rng: np.random.Generator, terms: dict, starts, durations, size: int = 3) -> np.ndarray:
    """Exact Gaussian draws of the interval means of a noise model, ``size`` independent axes.

    Parameters
    ----------
    terms : dict
        Noise model ``{term: coefficient}`` as :func:`accelcal.discrepancy.stochastic.model_avar`
        takes it (two-parameter terms: ``(coefficient, shape)``); for several components of
        one term pass a list of values, e.g. ``{"gauss_markov": [(s1, 3.0), (s2, 30.0)]}``.
    starts, durations : array_like (n,)

    Returns
    -------
    ndarray (n, size)
        Interval means up to a common constant per axis (what a model with a bias sees):
        drawn from ``−D/2 + c 11ᵀ`` with ``D`` the exact variogram of the interval means
        and ``c`` large enough to make it positive definite.
    """
    starts, durations = np.asarray(starts, float), np.asarray(durations, float)
    D = np.zeros((starts.size, starts.size))
    for k, v in terms.items():
        for vi in (v if isinstance(v, list) else [v]):
            D = D + pose_difference_variance(k, vi, starts, durations)
    n = starts.size
    c = float(np.max(D)) * n + 1e-300
    Cv = -0.5 * D + c
    ev, vec = np.linalg.eigh(0.5 * (Cv + Cv.T))
    root = vec * np.sqrt(np.clip(ev, 0.0, None))
    return root @ rng.standard_normal((n, size))


__all__ = ["CHI2_95", "Problem", "contrast_covariance", "Q_REL_GRID", "at", "RoundTests", "Surface", "WanderError", "WanderFit", "effect_information",
           "excess_distribution", "fit_wander", "gls_projector", "gls_step", "gm_variance", "problem", "profile",
           "round_tests", "simulate_interval_means", "studentised", "tau_grid", "wander_kernel"]
