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
  the standard error ``se_ik`` the static detection computed from the pose's own samples
  (Geyer's autocorrelation time: :mod:`accelcal.static`);
* ``β̄_ik`` the interval mean of a slow bias process ``β_k(t)``, the same process
  (``bias_wander``) on every axis, independent between axes, of size ``s`` (data unit):
  a first-order Gauss–Markov process (variance ``s²``, correlation time ``τ``,
  covariance ``s² exp(-|t - t'|/τ)``) or, as ``τ → ∞`` at fixed ``K² = 2 s²/τ``, a
  random walk ``K² min(t, t')`` (the grid of ``τ`` ends with it).

The covariance of two interval means is exact (:func:`accelcal.discrepancy.stochastic.
pose_difference_variance` gives the variogram ``D_ij = Var(β̄_i − β̄_j)`` in closed form;
``−D/2`` is a generalised covariance, equal to the covariance up to terms ``f_i + f_j``
that the per-axis bias of the model absorbs, which is why the random walk and the flicker
floor need no stationary variance).  A pose residual ``r_i = ‖x_i‖ − g`` moves by
``∇_i · ē_i`` with ``∇_i = ∂r_i/∂z_i`` (≈ the unit gravity direction in the sensor frame,
through ``M⁻ᵀ``), so, with ``σ_i² = Σ_k ∇_ik² se_ik²``::

    Cov(r_i, r_j) = σ_i² δ_ij + s² (∇_i · ∇_j) k_τ(i, j),   k_τ = −D_τ/2 (unit size).

Small ``τ`` (well below the pose durations) makes the wander extra white noise
(``Var ≈ 2 s² τ / T_i``): the family nests the common-scale excess of the ``white`` null;
``τ`` of the order of the spacing of the poses is a per-pose (nugget-like) excess; long
``τ`` a slow wander shared by neighbouring poses.

Linear model.  The test statistics use the model linearised at the current weighted
least-squares fit ``p₀`` (:func:`accelcal.discrepancy.fit.fit`): ``r(p) ≈ r₀ + J (p − p₀)``.
The neglected terms are of the order of (noise / g)² relative (≈ 1e-8 for a MEMS pose
mean), far below anything the tests resolve.  Whitened by ``σ`` and projected on the
``n − 3`` orthonormal contrasts ``L`` orthogonal to the three bias columns (which removes
the bias and, with it, the ambiguity of the generalised covariance), the data are
``y = Lᵀ r₀/σ ~ N(−X β, I + q K_τ)`` with ``X`` the other columns (six scale and
misalignment parameters, the named effects, the candidate) and ``q`` the wander
variance relative to the white one.  ``K_τ`` is diagonalised once per ``τ`` of a grid
(five per decade from a tenth of the shortest pose to ten session lengths, then the
random walk), so every likelihood on the grid costs ``O(n p)``.

Estimation (REML).  The wander ``(s, τ)`` is estimated jointly with the calibration by
restricted maximum likelihood: ``−2ℓ_R = log|Σ| + log|XᵀΣ⁻¹X| + yᵀ P y``.  Confidence
intervals are profile-likelihood intervals: the range of a quantity over the set where
``−2ℓ_R`` is within ``χ²₁(0.95) = 3.84`` of its minimum (on a fine grid: ten per
decade).  Intervals that reach the ends of the grid are reported open (the data cannot
bound them); a wander the contrasts cannot see is reported as not estimated with the
reason, never replaced by white noise silently.

Tests (likelihood ratio, parametric bootstrap).  Current model vs current + effect: the
likelihood ratio ``LR = −2 (ℓ₀ − ℓ₁)`` of the maximum likelihoods over the parameters
*and* the wander, each model re-estimating ``(q, τ)`` on the same grid.  Its null
distribution is not χ²₃ (estimated covariance, ``τ`` undefined at ``q = 0``, small
samples), so the p-value comes from ``n_boot`` data sets simulated under the fitted
null (the current model with its REML wander) and refitted with both models exactly as
the data: ``p = (1 + #{LR* ≥ LR})/(n_boot + 1)``.  Because ``LR`` is invariant to the
fixed effects of the null, the bootstrap needs only the noise model; and since ``LR`` is
asymptotically pivotal (χ²₃ whatever ``(q, τ)``), the bootstrap p-value is second-order
accurate.  Its guarantee: effect-free recordings whose noise is white + a wander of
this family get an effect named with probability ≤ α (up to the Monte Carlo error of
a finite ``n_boot``), however large the wander.  A wander outside the family (several
Gauss–Markov components, flicker) is approximated by the nearest member; the tests
check the false-positive rate on such sessions.

Outliers.  The GLS studentised residual of pose ``i``, ``t_i = (P r)_i / sqrt(P_ii)``
(the mean-shift statistic for that pose alone: ``N(0, 1)`` when the noise model is
right), with ``P`` the GLS residual projector at the REML wander; the family of the
``n`` poses is tested with ``max_i |t_i|`` against its bootstrap distribution (the
same replicates, each at its own REML wander), which accounts for the multiplicity and
the correlation between poses exactly.

Leave-one-pose-out.  ``(P r)_i / P_ii`` is the error of predicting pose ``i`` from the
others under the GLS model, including the wander's conditional mean given the
neighbouring poses (kriging); its RMS in units of ``σ`` is the colored LOPO gap.

Assumptions.  Gaussian errors; the per-pose standard errors of the rests are right for
the short-term noise; one wander process, of the same size on the three axes (data
unit), independent between axes; the poses' gradients at the linearisation point.  The
per-pose standard errors are computed from the pose's own samples, so a wander with
``τ`` shorter than the poses is partly counted in both (it then looks like a smaller
``s``); the interval-mean covariance is exact for the wander as modelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from ..errors import AccelcalError
from .stochastic import pose_difference_variance

#: Relative wander variance ``q`` (over the white variance of the contrasts) the tests profile over.
Q_REL_GRID = np.concatenate([[0.0], np.logspace(-2.0, 3.0, 31)])
#: Correlation times per decade of the grid of the tests, and of the report's profile.
TAU_PER_DECADE = 5
TAU_PER_DECADE_FINE = 10
#: ``χ²₁`` quantile of the 95 % profile-likelihood intervals.
CHI2_95 = float(stats.chi2.isf(0.05, 1))
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
    if n - J.shape[1] < 2:
        raise WanderError(f"{n} poses leave {n - J.shape[1]} residual degrees of freedom for {J.shape[1]} "
                          "parameters: the bias wander (2 parameters) cannot be estimated; need at least "
                          f"{J.shape[1] + 2} poses")
    y = L.T @ (r / sigma)
    taus = tau_grid(durations, float(np.max(starts + durations) - np.min(starts))) if taus is None else taus
    prob = Problem(y, X0, L, sigma, grad, starts, durations, np.asarray(taus, float),
                   np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0), tuple(notes))
    return prob.with_taus(prob.taus)


# --------------------------------------------------------------------------- likelihood on the grid


def profile(prob: Problem, X: np.ndarray, Y: np.ndarray, qrel) -> tuple[np.ndarray, np.ndarray]:
    """``−2 log`` likelihood (ML, constants dropped) of every data set over the grid.

    Parameters
    ----------
    prob : Problem
    X : ndarray (m, p)
        Fixed-effect columns of the model (contrasts).
    Y : ndarray (B, m)
        Data sets (contrasts).
    qrel : ndarray (Q,) or (T, Q)
        Relative wander variances (the same for every τ, or one row per τ).

    Returns
    -------
    ml : ndarray (B, T, Q)
        ``log|Σ| + yᵀ P y`` (P the GLS residual projector).
    reml_add : ndarray (T, Q)
        ``log|XᵀΣ⁻¹X|``: REML = ``ml + reml_add``.
    """
    qrel = np.asarray(qrel, float)
    Y = np.atleast_2d(Y)
    T = prob.taus.size
    Q = qrel.shape[-1]
    B = Y.shape[0]
    p = X.shape[1]
    ml = np.empty((B, T, Q))
    reml_add = np.empty((T, Q))
    for t in range(T):
        q = qrel[t] if qrel.ndim == 2 else qrel
        V = prob.V[t]
        Yr = Y @ V                                # (B, m)
        Xr = V.T @ X                              # (m, p)
        one = 1.0 + q[:, None] * prob.lam[t][None, :]   # (Q, m)
        w = 1.0 / one
        quad = (Yr * Yr) @ w.T                    # (B, Q)
        if p:
            WX = w[:, :, None] * Xr[None]         # (Q, m, p)
            A = Xr.T[None] @ WX                   # (Q, p, p)
            b = WX.transpose(0, 2, 1) @ Yr.T      # (Q, p, B)
            ci = np.linalg.inv(np.linalg.cholesky(A))
            u = ci @ b                            # c⁻¹ b
            quad = quad - np.sum(u * u, axis=1).T
            reml_add[t] = -2.0 * np.log(np.diagonal(ci, axis1=1, axis2=2)).sum(axis=1)
        else:
            reml_add[t] = 0.0
        ml[:, t, :] = np.log(one).sum(axis=1)[None, :] + quad
    return ml, reml_add


def gls_projector(prob: Problem, X: np.ndarray, t: int, q: float) -> np.ndarray:
    """GLS residual projector in the whitened pose space, ``L P_c Lᵀ`` (n, n), at ``(t, q)``:
    ``P_c = Σ⁻¹ − Σ⁻¹X(XᵀΣ⁻¹X)⁻¹XᵀΣ⁻¹`` in the contrasts.  ``(P r/σ)_i`` is the GLS
    residual of pose ``i`` in precision form (bias included as a fixed effect)."""
    V = prob.V[t]
    w = 1.0 / (1.0 + q * prob.lam[t])
    Si = (V * w) @ V.T
    if X.shape[1]:
        SX = Si @ X
        Pc = Si - SX @ np.linalg.solve(X.T @ SX, SX.T)
    else:
        Pc = Si
    return prob.L @ Pc @ prob.L.T


def studentised(prob: Problem, X: np.ndarray, t: int, q: float, Y=None) -> tuple[np.ndarray, np.ndarray]:
    """GLS studentised residuals ``(P r)_i/sqrt(P_ii)`` and leave-one-pose-out prediction
    errors ``(P r)_i/P_ii`` (both in units of σ) of data ``Y`` (B, m) (default: the data)."""
    P = gls_projector(prob, X, t, q)
    d = np.clip(np.diag(P), 1e-300, None)
    Y = prob.y[None] if Y is None else np.atleast_2d(Y)
    Pr = (Y @ prob.L.T) @ P.T                       # (B, n)
    return Pr / np.sqrt(d), Pr / d


# --------------------------------------------------------------------------- fitted wander


@dataclass(frozen=True)
class WanderFit:
    """REML estimate of the wander under one model, with its profile-likelihood intervals.

    ``q_rel`` relative to the white variance of the contrasts (the tests' scale),
    ``q_abs`` in the data unit squared (``s²``; ``K²`` for the random walk).
    """

    t: int
    q_rel: float
    tau: float
    q_abs: float
    size: float
    K: float
    reml: float
    ml_min: float
    size_ci: tuple
    tau_ci: tuple
    K_ci: tuple
    excess_ci: tuple
    at_bound: tuple
    estimable: bool
    reason: str

    @property
    def present(self) -> bool:
        return self.q_rel > 0


def fit_wander(prob: Problem, X: np.ndarray, fine: bool = True) -> WanderFit:
    """REML estimate of the wander for fixed-effect columns ``X``, with 95 % profile intervals.

    ``fine``: intervals on a grid of ten ``τ`` per decade and a fine absolute-size grid
    (what the report uses); otherwise the test grid only.
    """
    ml, add = profile(prob, X, prob.y[None], Q_REL_GRID)
    reml = ml[0] + add
    t, k = np.unravel_index(int(np.argmin(reml)), reml.shape)
    ml_min = float(ml[0].min())
    if not fine:
        return _wander_from(prob, int(t), float(Q_REL_GRID[k]), float(reml[t, k]), ml_min, (), (), (), (), (), True, "")
    # fine grid: τ ten per decade, absolute size around the estimate
    fp = prob.with_taus(tau_grid(prob.durations, prob.span, TAU_PER_DECADE_FINE))
    # absolute q grid per τ: q_rel from 1e-3 to 1e4 at 10 per decade, converted per τ
    qrel_fine = np.concatenate([[0.0], np.logspace(-3.0, 4.0, 71)])
    mlf, addf = profile(fp, X, fp.y[None], qrel_fine)
    dev = mlf[0] + addf
    tf, kf = np.unravel_index(int(np.argmin(dev)), dev.shape)
    best = float(dev[tf, kf])
    inside = dev <= best + CHI2_95
    taus = fp.taus
    qabs = qrel_fine[None, :] / fp.scale[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.where(np.isinf(taus)[:, None], np.inf, np.sqrt(qabs))
        K = np.where(np.isinf(taus)[:, None], np.sqrt(qabs), np.sqrt(2 * qabs / taus[:, None]))
    # excess: RMS of the wander's contribution relative to the white variance, sqrt(1 + q mean λ) = sqrt(1 + q)
    excess = np.broadcast_to(np.sqrt(1.0 + qrel_fine)[None, :], dev.shape)
    finite_q = inside & (qrel_fine[None, :] > 0)
    bound = []
    if inside[:, -1].any():
        bound.append("size: upper end of the grid (q_rel 1e4)")
    if finite_q[-1].any() or finite_q[-2].any():
        bound.append("tau: the interval reaches the random walk (no upper bound)")
    if finite_q[0].any():
        bound.append("tau: lower end of the grid")

    def rng(a, mask):
        v = a[mask]
        v = v[np.isfinite(v)] if not np.any(np.isinf(v)) else v
        return (float(np.min(v)), float(np.max(v))) if v.size else (float("nan"), float("nan"))

    tau_mask = finite_q
    tau_ci = rng(np.broadcast_to(taus[:, None], dev.shape), tau_mask) if tau_mask.any() else (float("nan"),) * 2
    size_ci = rng(size, inside)
    K_ci = rng(K, inside)
    if inside[:, 0].any():  # q = 0 inside the interval: the lower ends are 0
        size_ci, K_ci = (0.0, size_ci[1]), (0.0, K_ci[1])
    excess_ci = rng(excess, inside)
    # the point estimate: the fine grid's best, refined in (log q, log τ) unless at q = 0 or the random walk
    t_hat, q_hat = int(tf), float(qrel_fine[kf])
    out = _wander_from(fp, t_hat, q_hat, best, ml_min, size_ci, tau_ci, K_ci, excess_ci, tuple(bound), True, "")
    if q_hat > 0 and np.isfinite(fp.taus[t_hat]):
        out = _refine(prob, X, out)
    return out


def _wander_from(prob, t, q_rel, reml, ml_min, size_ci, tau_ci, K_ci, excess_ci, bound, ok, reason) -> WanderFit:
    tau = float(prob.taus[t])
    q_abs = q_rel / float(prob.scale[t])
    s, K = gm_variance(q_abs, tau)
    return WanderFit(t=t, q_rel=q_rel, tau=tau, q_abs=q_abs, size=s, K=K, reml=reml, ml_min=ml_min,
                     size_ci=tuple(size_ci), tau_ci=tuple(tau_ci), K_ci=tuple(K_ci), excess_ci=tuple(excess_ci),
                     at_bound=tuple(bound), estimable=ok, reason=reason)


def _refine(prob: Problem, X: np.ndarray, w: WanderFit) -> WanderFit:
    """Continuous REML optimum in (log q_abs, log τ) from the grid's best point."""
    def dev(v):
        tau, qa = math.exp(v[1]), math.exp(v[0])
        pp = prob.with_taus([tau])
        ml, add = profile(pp, X, pp.y[None], np.array([qa * pp.scale[0]]))
        return float(ml[0, 0, 0] + add[0, 0])

    x0 = np.array([math.log(w.q_abs), math.log(w.tau)])
    res = optimize.minimize(dev, x0, method="Nelder-Mead",
                            options={"xatol": 1e-3, "fatol": 1e-6, "maxiter": 200})
    if not (res.fun <= w.reml):
        return w
    tau, qa = math.exp(res.x[1]), math.exp(res.x[0])
    pp = prob.with_taus([tau])
    s, K = gm_variance(qa, tau)
    return WanderFit(t=w.t, q_rel=qa * float(pp.scale[0]), tau=tau, q_abs=qa, size=s, K=K, reml=float(res.fun),
                     ml_min=w.ml_min, size_ci=w.size_ci, tau_ci=w.tau_ci, K_ci=w.K_ci, excess_ci=w.excess_ci,
                     at_bound=w.at_bound, estimable=True, reason="")


# --------------------------------------------------------------------------- tests


@dataclass(frozen=True)
class RoundTests:
    """Bootstrap tests of one round: every candidate's LR and the outlier family."""

    lr: np.ndarray              # (k,) observed LR per candidate
    p_values: np.ndarray        # (k,) bootstrap p-values
    outlier_t: np.ndarray       # (n,) studentised residuals of the data (current model, REML wander)
    outlier_p: float            # bootstrap p-value of max |t|
    outlier_pose: int           # index (into the current pose set) of max |t|
    null_wander: WanderFit      # the wander the bootstrap simulates (current model, REML)
    n_boot: int


def round_tests(prob: Problem, X_alts: list, rng: np.random.Generator, n_boot: int,
                outliers: bool = True) -> RoundTests:
    """Likelihood-ratio tests current (``prob.X0``) vs current + each ``X_alts[k]``
    (contrast columns, appended to X0) and the outlier family, all calibrated on the same
    ``n_boot`` data sets simulated under the current model with its REML wander."""
    X0 = prob.X0
    null = fit_wander(prob, X0, fine=False)
    ml0, add0 = profile(prob, X0, prob.y[None], Q_REL_GRID)
    m0 = float(ml0[0].min())
    lr = np.empty(len(X_alts))
    Xs = [np.hstack([X0, Xa]) for Xa in X_alts]
    for k, X1 in enumerate(Xs):
        ml1, _ = profile(prob, X1, prob.y[None], Q_REL_GRID)
        lr[k] = max(m0 - float(ml1[0].min()), 0.0)
    # bootstrap under the null: y* = V diag(sqrt(1 + q λ)) z
    V, lam = prob.V[null.t], prob.lam[null.t]
    Z = rng.standard_normal((n_boot, prob.m))
    Ystar = (Z * np.sqrt(1.0 + null.q_rel * lam)[None, :]) @ V.T
    ml0s, _ = profile(prob, X0, Ystar, Q_REL_GRID)
    m0s = ml0s.reshape(n_boot, -1).min(axis=1)
    tol = 1e-9 * max(1.0, float(np.max(lr, initial=0.0)))
    p = np.empty(len(X_alts))
    for k, X1 in enumerate(Xs):
        ml1s, _ = profile(prob, X1, Ystar, Q_REL_GRID)
        lrs = np.maximum(m0s - ml1s.reshape(n_boot, -1).min(axis=1), 0.0)
        p[k] = (1 + np.sum(lrs >= lr[k] - tol)) / (n_boot + 1)
    t_obs, _ = studentised(prob, X0, null.t, null.q_rel)
    t_obs = t_obs[0]
    o_p, o_i = float("nan"), -1
    if outliers:
        # each replicate at its own REML wander (grid)
        reml_s = ml0s + add0[None]
        arg = reml_s.reshape(n_boot, -1).argmin(axis=1)
        ts, qs = np.unravel_index(arg, reml_s.shape[1:])
        tmax = np.empty(n_boot)
        for key in set(zip(ts.tolist(), qs.tolist())):
            sel = (ts == key[0]) & (qs == key[1])
            tt, _ = studentised(prob, X0, key[0], float(Q_REL_GRID[key[1]]), Ystar[sel])
            tmax[sel] = np.abs(tt).max(axis=1)
        o_i = int(np.argmax(np.abs(t_obs)))
        obs = float(np.abs(t_obs[o_i]))
        o_p = float((1 + np.sum(tmax >= obs * (1 - 1e-12))) / (n_boot + 1))
    return RoundTests(lr=lr, p_values=p, outlier_t=t_obs, outlier_p=o_p, outlier_pose=o_i, null_wander=null,
                      n_boot=int(n_boot))


# --------------------------------------------------------------------------- information, MDE, GLS


def effect_information(prob: Problem, X0: np.ndarray, Xe: np.ndarray, t: int, q: float) -> dict:
    """Fisher information of an effect block ``Xe`` profiled over ``X0``: under the wander
    ``(t, q)`` (``colored``), under white noise (``white``) and under white noise of the same
    mean variance (``scaled_white``: what a common scale factor would give)."""
    V = prob.V[t]
    w = 1.0 / (1.0 + q * prob.lam[t])
    Si = (V * w) @ V.T

    def info(S):
        SX = S @ X0
        P = S - SX @ np.linalg.solve(X0.T @ SX, SX.T) if X0.shape[1] else S
        return Xe.T @ P @ Xe

    I_white = info(np.eye(prob.m))
    mean_var = float(np.mean(1.0 + q * prob.lam[t]))
    return {"colored": info(Si), "white": I_white, "scaled_white": I_white / mean_var}


def gls_step(prob: Problem, X: np.ndarray, t: int, q: float) -> tuple[np.ndarray, np.ndarray]:
    """GLS estimate of the linearised parameter change ``β`` (``y ≈ −X β``) and its covariance."""
    V = prob.V[t]
    w = 1.0 / (1.0 + q * prob.lam[t])
    Si = (V * w) @ V.T
    A = X.T @ Si @ X
    cov = np.linalg.inv(A)
    beta = -cov @ (X.T @ Si @ prob.y)
    return beta, cov


def at(prob: Problem, tau: float, q_abs: float) -> tuple[Problem, float]:
    """The one-τ problem of a wander ``(τ, q_abs)`` and its relative variance there."""
    p1 = prob.with_taus([tau])
    return p1, float(q_abs * p1.scale[0])


def excess_distribution(prob: Problem, X: np.ndarray, t: int, q: float) -> np.ndarray:
    """Eigenvalues ``μ`` of ``(I − H) Σ_c (I − H)`` (``H`` the unweighted hat of ``X``):
    under the noise model the weighted χ² of the least-squares residuals is ``Σ μ_k χ²₁``."""
    Q, _ = np.linalg.qr(X) if X.shape[1] else (np.zeros((prob.m, 0)), None)
    R = np.eye(prob.m) - Q @ Q.T
    S = prob.sigma_c(t, q)
    mu = np.linalg.eigvalsh(R @ S @ R)
    return np.clip(mu, 0.0, None)


__all__ = ["CHI2_95", "Problem", "Q_REL_GRID", "at", "RoundTests", "WanderError", "WanderFit", "effect_information",
           "excess_distribution", "fit_wander", "gls_projector", "gls_step", "gm_variance", "problem", "profile",
           "round_tests", "studentised", "tau_grid", "wander_kernel"]
