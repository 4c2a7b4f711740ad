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
  (``bias_wander``) on every axis, of size ``σ_w`` (data unit) per axis, correlated
  between the axes by ``φ`` (below): a first-order Gauss–Markov process (variance
  ``σ_w²``, correlation time ``τ``, covariance ``σ_w² exp(-|t - t'|/τ)``) or, as ``τ → ∞``
  at fixed ``K² = 2 σ_w²/τ``, a random walk ``K² min(t, t')`` (the grid of ``τ`` ends
  with it).

The covariance of two interval means is exact (:func:`accelcal.discrepancy.stochastic.
pose_difference_variance` gives the variogram ``D_ij = Var(β̄_i − β̄_j)`` in closed form;
``−D/2`` is a generalised covariance, equal to the covariance up to terms ``f_i + f_j``
that the per-axis bias of the model absorbs, which is why the random walk and the flicker
floor need no stationary variance).  A pose residual ``r_i = ‖x_i‖ − g`` moves by
``∇_i · ē_i`` with ``∇_i = ∂r_i/∂z_i`` (≈ the unit gravity direction in the sensor frame,
through ``M⁻ᵀ``), so, with ``σ_i² = Σ_k ∇_ik² se_ik²`` and ``C`` the correlation of the
wander between the axes (``Cov(β_a(t), β_b(t')) = σ_w² C_ab k_τ(t, t')``)::

    Cov(r_i, r_j) = s σ_i² δ_ij + σ_w² (∇_iᵀ C ∇_j) k_τ(i, j),   k_τ = −D_τ/2 (unit size).

Axes that wander together.  A real sensor's axes often drift together (one supply,
reference or temperature drives all channels: on the ADIS16405 record, 5 s deviations of
the three axes from their local level correlate by 0.35-0.69).  Such a wander moves the
residual of a pose whose gravity points along the shared direction more than that of a
pose across it, which the independent-axes kernel ``∇_i · ∇_j`` cannot express.  Of a
general ``C`` (six parameters) the ~25 contrasts of a session support one: the wander is
modelled as an independent part plus a common-mode part shared by the three axes,
``C_φ = (1 − φ) I + φ 11ᵀ`` (correlation ``φ`` between any two axes, ``0 ≤ φ ≤ 1``, the
same sign on the three sensor axes), so the pair factor is ``(1 − φ) ∇_i · ∇_j + φ (Σ_a
∇_ia)(Σ_b ∇_jb)`` (:func:`axis_gram`).  ``φ = 0`` is the independent-axes model.
``φ`` is estimated by REML with ``(s, q, τ)`` on the grid :data:`COMMON_GRID` (each
``(φ, τ)`` kernel diagonalised once, as one stack: :func:`fit_common`), once per round under
the current model; the round's tests, MDEs and LOPO then stand at ``φ̂``.  Per-axis
sizes that differ, or correlations of other signs or strengths between different pairs
of axes, are approximated by the nearest member.

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
random walk); each model's columns are projected out once per ``τ`` (:class:`Basis`: the
contrasts the model leaves free, in which its GLS residual projector is diagonal), so
every likelihood on the grid costs ``O(n)``.

Estimation (REML).  The noise ``(s, q, τ)`` is estimated jointly with the calibration by
restricted maximum likelihood: ``−2ℓ_R = log|Σ| + log|XᵀΣ⁻¹X| + yᵀ P y``, ``s``
profiled analytically (``ŝ = yᵀPy/(m − p)`` at ``Σ = s (I + q K_τ)``).  Confidence
intervals are profile-likelihood intervals: the range of a quantity over the set where
``−2ℓ_R`` is within ``χ²₁(0.95) = 3.84`` of its minimum; the estimate and the intervals
are taken on a fine grid (ten values per decade of ``τ`` and of ``q``: a resolution of
±12 %, well inside any interval the poses give).  Intervals that reach the ends of the
grid are reported open (the data cannot bound them); a wander the contrasts cannot see
is reported as not estimated with the reason, never replaced by white noise silently.

Tests (likelihood ratio, parametric bootstrap).  Current model vs current + effect: the
likelihood ratio ``LR = −2 (ℓ₀ − ℓ₁)`` of the maximum likelihoods over the parameters
*and* the noise, each model re-estimating ``(s, q, τ)`` (``s`` analytically, ``(q, τ)`` on
the same grid).  Its null distribution is not χ²₃: maximum likelihood underestimates a
variance by the share of the fixed effects, more so for the larger model, and the wander
trades off against slow effects, so ``LR`` is stretched (by 1.2–1.6 for most effects and
up to 3 for ``bias_drift`` under a random-walk-like wander: ``bartlett`` in the output).
The p-value comes from ``n_boot`` data sets simulated under the fitted null (the current
model with its REML noise) and refitted with both models exactly as the data:
``p = (1 + #{LR* ≥ LR})/(n_boot + 1)``, or, for a test that reaches ``h`` exceedances
first, Besag & Clifford's (1991) sequential ``p = h/ℓ`` after ``ℓ`` replicates (``h`` is
chosen so that such a test could not pass at level α with every replicate: it only saves
the replicates of clearly insignificant tests).  Because ``LR`` is invariant to the fixed effects
of the null and to the scale ``s``, the bootstrap needs only ``(q, τ)``; and since ``LR``
is asymptotically pivotal (χ²₃ whatever the noise parameters), the bootstrap p-value is
second-order accurate (a scale-only, Bartlett-type correction was tried and rejected: on
sessions with three Gauss–Markov components it gave 8 % false positives at α = 5 %).
The bootstrap draws under ``φ̂`` and refits ``(s, q, τ)`` in each
replicate, not ``φ``: the statistic is the likelihood ratio at the round's ``φ̂`` (a plug-in:
the estimation error of ``φ̂`` is not propagated; re-estimating it per replicate would need
every candidate's :class:`Basis` for every ``φ``, five times the cost; the benchmark
measures what holding it costs).  Its
guarantee: effect-free recordings whose noise is of this family get an effect named
with probability ≤ α (up to the Monte Carlo error of a finite ``n_boot`` and of ``φ̂``),
however large the wander.  A wander outside the family (several Gauss–Markov components,
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
same size on the three axes (data unit), equicorrelated between the axes by ``φ ≥ 0`` (a
common-mode share), of the Gauss–Markov / random-walk family (a sum of components or a
flicker floor is approximated by its nearest member: the tests measure what that
costs); the poses' gradients at the linearisation point.  The per-pose standard errors
are computed from the pose's own samples, so noise with a correlation time near the pose
durations is partly counted in both (it then shows as a smaller ``σ_w`` or ``s``); the
interval-mean covariance is exact for the wander as modelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from .stochastic.implication import pose_difference_variance  # noqa: F401 (re-exported for the loop)

#: Relative wander variance ``q`` (over the white variance of the contrasts) the tests
#: profile over: 0, then three per decade (the likelihood is smooth in log q: the grid
#: maximum is within a few hundredths of the continuous one, the same for data and replicates).
Q_REL_GRID = np.concatenate([[0.0], np.logspace(-2.0, 3.0, 16)])
#: Correlation times per decade of the grid of the tests, and of the report's profile.
TAU_PER_DECADE = 5
TAU_PER_DECADE_FINE = 10
#: ``χ²₁`` quantile of the 95 % profile-likelihood intervals.
CHI2_95 = float(dist.chi2_isf(0.05, 1))
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


def axis_gram(grad, common: float = 0.0) -> np.ndarray:
    """``∇_iᵀ C_φ ∇_j`` (n, n): how the wander of the three axes reaches two pose residuals.

    ``C_φ = (1 − φ) I + φ 11ᵀ`` is the correlation of the wander between the sensor axes
    (unit variance per axis, correlation ``φ`` between any two; module docstring), so the
    result is ``(1 − φ) ∇_i · ∇_j + φ (Σ_a ∇_ia)(Σ_b ∇_jb)``.
    """
    grad = np.asarray(grad, float)
    G = grad @ grad.T
    if common:
        s = grad.sum(axis=1)
        G = (1.0 - common) * G + common * np.outer(s, s)
    return G


def axis_weight(grad, common: float = 0.0) -> np.ndarray:
    """The diagonal of :func:`axis_gram` (n,): the wander's variance in each pose residual per unit
    wander variance per axis."""
    grad = np.asarray(grad, float)
    return (1.0 - common) * np.sum(grad**2, axis=1) + common * grad.sum(axis=1) ** 2


def wander_kernel(tau: float, starts, durations, grad, common: float = 0.0) -> np.ndarray:
    """Generalised covariance of the pose residuals from a unit-size wander (module docstring).

    ``tau`` finite: Gauss–Markov of unit variance; ``inf``: random walk with ``K = 1``;
    ``common``: the correlation ``φ`` of the wander between the axes (:func:`axis_gram`).
    Returns ``(∇_iᵀ C_φ ∇_j) (−D_ij / 2)`` (n, n).
    """
    return wander_kernels(np.array([tau], float), starts, durations, grad, common)[0]


def wander_kernels(taus, starts, durations, grad, common: float = 0.0) -> np.ndarray:
    """:func:`wander_kernel` of every correlation time of ``taus`` (T, n, n), in one pass.

    ``D`` is :func:`accelcal.discrepancy.stochastic.pose_difference_variance`'s
    (``gauss_markov`` of unit size, ``random_walk`` with ``K = 1``), its formulas evaluated
    for all ``τ`` at once.
    """
    return -0.5 * axis_gram(grad, common)[None] * _variograms(taus, starts, durations)


def _variograms(taus, starts, durations) -> np.ndarray:
    """``D_ij = Var(β̄_i − β̄_j)`` of a unit wander for every ``τ`` of ``taus`` (T, n, n)."""
    taus = np.asarray(taus, float)
    a, T = np.asarray(starts, float), np.asarray(durations, float)
    first_end = np.where(a[:, None] <= a[None, :], (a + T)[:, None], (a + T)[None, :])
    gap = np.maximum(np.maximum(a[:, None], a[None, :]) - first_end, 0.0)      # (n, n)
    D = np.empty((taus.size,) + gap.shape)
    rw = np.isinf(taus)
    D[rw] = gap + (T[:, None] + T[None, :]) / 3
    tc = taus[~rw][:, None]                                                      # (T', 1)
    W = 2 * (tc * T + tc**2 * np.expm1(-T / tc)) / T**2                          # (T', n)
    E = -np.expm1(-T / tc) / T                                                   # (T', n)
    cov = tc[:, :, None] ** 2 * E[:, :, None] * E[:, None, :] * np.exp(-gap / tc[:, :, None])
    D[~rw] = W[:, :, None] + W[:, None, :] - 2 * cov
    idx = np.arange(gap.shape[0])
    D[:, idx, idx] = 0.0
    return D


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
    common : float
        Correlation ``φ`` of the wander between the axes the kernels are built with
        (:func:`axis_gram`).
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
    common: float = 0.0

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
        K = wander_kernel(tau, self.starts, self.durations, self.grad, self.common)
        Kw = K / self.sigma[:, None] / self.sigma[None, :]
        return self.L.T @ Kw @ self.L

    def with_taus(self, taus) -> Problem:
        """The same problem on another grid of correlation times."""
        return self._rebuilt(np.asarray(taus, float), self.common)

    def with_common(self, common: float) -> Problem:
        """The same problem with the wander's axis correlation ``φ = common``."""
        return self if common == self.common else self._rebuilt(self.taus, float(common))

    def _rebuilt(self, taus, common):
        lam, V, scale = _eigen(self, taus, common)
        return Problem(self.y, self.X0, self.L, self.sigma, self.grad, self.starts, self.durations,
                       taus, lam, V, scale, self.notes, common)

    def sigma_c(self, t: int, q: float) -> np.ndarray:
        """Contrast covariance ``I + q K_τ`` at grid point ``(t, q)`` (relative ``q``)."""
        V = self.V[t]
        return (V * (1.0 + q * self.lam[t])) @ V.T


def _eigen(prob, taus, common):
    """Eigenvalues (scaled by their mean), eigenvectors and mean of the contrast kernels of
    every ``τ`` of ``taus``; ``common`` a float (T kernels) or an array of ``φ`` (len(common)
    × T kernels, ``φ`` outermost: the kernel is linear in ``φ``, the variograms are shared)."""
    D = _variograms(taus, prob.starts, prob.durations) / np.outer(prob.sigma, prob.sigma)[None]
    phis = np.atleast_1d(np.asarray(common, float))
    G = prob.grad @ prob.grad.T
    Kc = prob.L.T[None] @ (-0.5 * G[None] * D) @ prob.L
    if np.any(phis != 0):
        sg = prob.grad.sum(axis=1)
        Kcom = prob.L.T[None] @ (-0.5 * np.outer(sg, sg)[None] * D) @ prob.L
        Kc = ((1.0 - phis)[:, None, None, None] * Kc[None] + phis[:, None, None, None] * Kcom[None])
        Kc = Kc.reshape((-1,) + Kc.shape[2:])
    ev, V = np.linalg.eigh(0.5 * (Kc + np.swapaxes(Kc, 1, 2)))
    ev = np.clip(ev, 0.0, None)  # round-off: the projected kernel is positive semi-definite
    s = ev.mean(axis=1)
    scale = np.where(s > 0, s, 1.0)
    return ev / scale[:, None], V, scale


def problem(r, J, sigma, grad, starts, durations, taus=None, notes=(), common: float | None = 0.0) -> Problem:
    """Build the :class:`Problem` of a fit: residuals ``r`` (n,), Jacobian ``J`` (n, q) whose
    first three columns are the bias, ``σ`` (n,), gradients ``∇`` (n, 3), pose intervals,
    the wander's axis correlation ``common`` (:func:`axis_gram`; None: the kernels are not
    diagonalised, for :func:`fit_common`, which does it for every ``φ`` of its grid).

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
                   np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0), tuple(notes), float("nan"))
    return prob if common is None else prob._rebuilt(prob.taus, float(common))


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


def _neg2ll_min(quad, nu, logdet):
    """Minimum over the grid of :func:`_neg2ll` per data set: ``quad`` (B, T, Q), ``logdet`` (T, Q).

    The same number with one logarithm per data set instead of one per grid point: where
    the white scale is above its floor, ``−2ℓ = ν (log(x e^{logdet/ν}) + 1)`` (``x = quad/ν``)
    is smallest where the product is; below it, ``−2ℓ`` is linear in ``quad``.
    """
    quad = np.clip(quad.reshape(quad.shape[0], -1), 1e-300, None)
    ld = logdet.reshape(-1)
    floored = quad < MIN_WHITE_SCALE * nu
    prod = np.where(floored, np.inf, quad * np.exp(ld / nu)[None]).min(axis=1)
    with np.errstate(divide="ignore"):
        free = nu * (np.log(prod / nu) + 1.0)
    if not floored.any():
        return free
    lin = np.where(floored, quad / MIN_WHITE_SCALE + ld[None], np.inf).min(axis=1) + nu * math.log(MIN_WHITE_SCALE)
    return np.minimum(free, lin)


@dataclass(frozen=True)
class Surface:
    """Likelihood of data sets over the grid of ``(τ, q)``, the white scale ``s`` profiled out.

    ``quad`` (B, T, Q): ``yᵀ P y`` with ``P`` the GLS residual projector of ``I + q K_τ``;
    ``logdet`` (T, Q): ``log|I + q K_τ|``; ``logdet_a`` (T, Q): ``log|Xᵀ(I + q K_τ)⁻¹X|``;
    ``m`` contrasts, ``p`` columns; ``shift_quad`` (B, T, Q, n) or None: ``quad`` of the
    model with a free shift of each pose; ``best_shift_quad`` (B, T, Q) or None: the
    smallest of those over the poses.  With ``Σ = s (I + q K_τ)``, ``s`` at its optimum
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
    best_shift_quad: np.ndarray | None = None

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
        return _neg2ll_min(self.quad, self.m, self.logdet)

    def shift_ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` of the model with pose ``i`` shifted, per data set (B, n)."""
        ml = _neg2ll(self.shift_quad, self.m, self.logdet[None, :, :, None])
        return ml.reshape(ml.shape[0], -1, ml.shape[-1]).min(axis=1)

    def best_shift_ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` of the best single-pose shift, per data set (B,): the
        minimum over the poses of :meth:`shift_ml_min` (at each grid point ``−2ℓ`` grows
        with ``quad``, so the best pose there is the one with the smallest ``quad``)."""
        return _neg2ll_min(self.best_shift_quad, self.m, self.logdet)


@dataclass(frozen=True)
class Basis:
    """The contrasts left free by a model's columns ``X`` (m, p), per correlation time.

    ``K`` (m, r): orthonormal basis of the complement of ``X`` (``r = m − p``); ``U``, ``mu``
    (T, r, r), (T, r): eigenvectors and eigenvalues of ``Kᵀ K_τ K`` (the kernel as
    ``prob.lam`` scales it); ``logdet_xx``: ``log|XᵀX|``.  The GLS residual projector of
    ``I + q K_τ`` is ``K U diag(1/(1 + q μ)) Uᵀ Kᵀ`` (the REML identity), so the likelihood
    of a data set costs ``O(r)`` per grid point once ``Kᵀ y`` is rotated.
    """

    K: np.ndarray
    U: np.ndarray
    mu: np.ndarray
    logdet_xx: float


def basis(prob: Problem, X: np.ndarray) -> Basis:
    """The :class:`Basis` of columns ``X`` on ``prob``'s grid of ``τ``.

    Raises
    ------
    numpy.linalg.LinAlgError
        The columns are collinear (no GLS fit exists).
    """
    m, p = X.shape
    if p:
        Uf, s, _ = np.linalg.svd(X, full_matrices=True)
        if s[-1] <= 1e-12 * s[0]:
            raise np.linalg.LinAlgError("collinear columns: the model has no unique GLS fit")
        K, logdet_xx = Uf[:, p:], 2.0 * float(np.log(s).sum())
    else:
        K, logdet_xx = np.eye(m), 0.0
    A = np.swapaxes(prob.V, 1, 2) @ K                            # (T, m, r): Vᵀ K
    R = np.swapaxes(A, 1, 2) @ (prob.lam[:, :, None] * A)        # (T, r, r): Kᵀ K_τ K
    mu, U = np.linalg.eigh(0.5 * (R + np.swapaxes(R, 1, 2)))
    return Basis(K, U, np.clip(mu, 0.0, None), logdet_xx)


def profile(prob: Problem, X: np.ndarray, Y: np.ndarray, qrel, shifts: bool = False,
            best_shift: bool = False, bas: Basis | None = None) -> Surface:
    """The likelihood :class:`Surface` of data sets ``Y`` (B, m) under the model with columns
    ``X`` (m, p), over the grid ``prob.taus`` × ``qrel`` ((Q,), or (T, Q): one row per τ).

    The quadratic forms are taken in the model's own contrasts (:class:`Basis`, computed
    here unless given as ``bas``): ``yᵀ P y = Σ_j ỹ_j² / (1 + q μ_j)`` with ``ỹ = Uᵀ Kᵀ y``,
    and ``log|XᵀΣ⁻¹X| = log|KᵀΣK| + log|XᵀX| − log|Σ|``.

    ``shifts``: also the model with a free shift of pose ``i``'s residual, for every pose
    (the outlier model): ``quad − (P r)_i²/P_ii`` (a rank-one update of the GLS fit, ``P``
    the residual projector in the pose space); ``best_shift``: only the smallest of those
    over the poses (what the outlier family's statistic needs).
    """
    bas = basis(prob, X) if bas is None else bas
    qrel = np.asarray(qrel, float)
    Y = np.atleast_2d(Y)
    T = prob.taus.size
    q = np.broadcast_to(qrel, (T, qrel.shape[-1]))              # (T, Q)
    p = X.shape[1]
    Yt = (Y @ bas.K)[None] @ bas.U                              # (T, B, r): rotated free contrasts
    one = 1.0 + q[:, :, None] * bas.mu[:, None, :]              # (T, Q, r)
    w = 1.0 / one
    quad = ((Yt * Yt) @ w.transpose(0, 2, 1)).transpose(1, 0, 2)   # (B, T, Q)
    logdet = np.log(1.0 + q[:, :, None] * prob.lam[:, None, :]).sum(axis=2)
    logdet_a = np.log(one).sum(axis=2) + bas.logdet_xx - logdet if p else np.zeros(q.shape)
    shift_quad = best = None
    if shifts or best_shift:
        M = (prob.L @ bas.K)[None] @ bas.U                      # (T, n, r): poses from rotated contrasts
        d = np.clip((M * M) @ w.transpose(0, 2, 1), 1e-300, None)   # (T, n, Q): P_ii
        # (P r)_i / sqrt(P_ii) for all (q, i) as one matrix product per τ (Q n × r times r × B)
        A = M[:, None] * w[:, :, None, :] / np.sqrt(d.transpose(0, 2, 1))[..., None]   # (T, Q, n, r)
        z = A.reshape(T, -1, A.shape[-1]) @ Yt.transpose(0, 2, 1)                     # (T, Q n, B)
        gain = np.square(z, out=z).reshape(T, q.shape[1], -1, Y.shape[0])             # (T, Q, n, B)
        if shifts:
            shift_quad = np.clip(quad.transpose(1, 2, 0)[:, :, None, :] - gain, 1e-300, None).transpose(3, 0, 1, 2)
        if best_shift:
            best = np.clip(quad - gain.max(axis=2).transpose(2, 0, 1), 1e-300, None)   # (B, T, Q)
    return Surface(quad, logdet, logdet_a, prob.m, p, shift_quad, best)


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
    the random walk), ``size`` its std, ``K`` its short-lag random-walk coefficient (per
    axis).  ``common`` is the wander's correlation ``φ`` between the axes the fit stands at,
    ``common_ci`` its 95 % profile interval on :data:`COMMON_GRID` and ``common_profile``
    the profiled ``−2ℓ_R`` at each grid value (:func:`fit_common`; empty when ``φ`` was not
    estimated).
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
    common: float = 0.0
    common_ci: tuple = ()
    common_profile: tuple = ()

    @property
    def present(self) -> bool:
        return self.q_rel > 0


#: Relative variances of the report's grid: 0, then ten per decade.
Q_REL_FINE = np.concatenate([[0.0], np.logspace(-3.0, 4.0, 71)])
#: White-scale factors (over the conditional estimate) the report's intervals scan.
S_FACTORS = np.logspace(-1.0, 1.0, 81)


def fit_wander(prob: Problem, X: np.ndarray, fine: bool = True, bas: Basis | None = None) -> WanderFit:
    """REML estimate of ``(s, q, τ)`` for fixed-effect columns ``X``, with 95 % profile intervals.

    ``fine``: estimate and intervals on a grid of ten ``τ`` and ten ``q`` per decade (what
    the report uses); otherwise the test grid, without intervals (``bas``: the
    :class:`Basis` of ``X`` on it, if known).
    """
    if not fine:
        sf = profile(prob, X, prob.y[None], Q_REL_GRID, bas=bas)
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
    # the full deviance over (τ, q, s), s = f ŝ(τ, q) on a scan around the optimum (above the
    # floor), at the grid points whose profiled deviance is inside the region (the others have
    # no s inside it: the deviance at ŝ is its minimum over the allowed s)
    ct, cq = np.nonzero(dev <= best + CHI2_95 + 1e-9)
    s_full = s_hat[ct, cq][:, None] * S_FACTORS[None, :]                     # (N, S)
    dev_full = nu * np.log(s_full) + quad[ct, cq][:, None] / s_full + (sf.logdet + sf.logdet_a)[ct, cq][:, None]
    inside = (dev_full <= best + CHI2_95) & (s_full >= MIN_WHITE_SCALE * (1 - 1e-12))
    taus, T = fp.taus, fp.taus.size
    tv, qv = taus[ct][:, None], Q_REL_FINE[cq][:, None]
    q_abs = s_full * qv / fp.scale[ct][:, None]
    rw = np.isinf(tv)
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.where(rw, np.inf, np.sqrt(q_abs))
        K = np.where(rw, np.sqrt(q_abs), np.sqrt(2 * q_abs / np.where(rw, 1.0, tv)))
    # the residual excess the model predicts on average: sqrt(s (1 + q)) (mean eigenvalue 1)
    excess = np.sqrt(s_full * (1.0 + qv))
    wander = inside & (qv > 0)
    bound = []
    if inside[cq == Q_REL_FINE.size - 1].any():
        bound.append("size: upper end of the grid (q_rel 1e4)")
    if wander[ct >= T - 2].any():
        bound.append("tau: the interval reaches the random walk (no upper bound)")
    if wander[ct == 0].any():
        bound.append("tau: lower end of the grid")
    if inside[:, 0].any() or inside[:, -1].any():
        bound.append("white scale: end of the scanned range (x0.1 - x10 of its estimate)")
    if np.isclose(s_hat[tf, kf], MIN_WHITE_SCALE):
        bound.append(f"white scale: at its floor {MIN_WHITE_SCALE:g}")

    def rng(a, mask):
        v = a[mask]
        return (float(np.min(v)), float(np.max(v))) if v.size else (float("nan"), float("nan"))

    tau_ci = rng(np.broadcast_to(tv, inside.shape), wander)
    size_ci, K_ci = rng(size, inside), rng(K, inside)
    if inside[cq == 0].any():  # q = 0 inside the region: the lower ends are 0
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
                     size_ci=nan2, tau_ci=nan2, K_ci=nan2, white_scale_ci=nan2, excess_ci=nan2, at_bound=(),
                     common=float(prob.common))


#: Correlations ``φ`` of the wander between the sensor axes that :func:`fit_common` chooses
#: from: independent axes, then a common-mode share of a third to all of the wander (four
#: values: each costs one diagonalisation of the kernels per round; with five the loop was
#: 1.3x slower than with independent axes on sessions with effects).
COMMON_GRID = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])


def fit_common(prob: Problem, X: np.ndarray, grid=None) -> tuple[Problem, Basis, WanderFit]:
    """REML of the wander's axis correlation ``φ`` jointly with ``(s, q, τ)`` on the test grid.

    The kernels of every ``(φ, τ)`` are diagonalised as one stack and profiled in one pass
    (the grid of ``τ`` repeated per ``φ``), so the cost is that of one profile on a grid
    ``len(grid)`` times longer.

    Parameters
    ----------
    prob : Problem
        The linearised problem (any ``common``).
    X : ndarray (m, p)
        Fixed-effect columns of the model whose noise is estimated.
    grid : array_like, optional
        Values of ``φ`` (default :data:`COMMON_GRID`; ``0`` first: a tie, e.g. no wander at
        all, keeps independent axes).

    Returns
    -------
    Problem, Basis, WanderFit
        The problem rebuilt at the estimate ``φ̂``, the :class:`Basis` of ``X`` on it, and
        the REML noise there (``fit_wander(..., fine=False)``) with ``common_ci`` (the grid
        values within ``χ²₁(0.95)`` of the minimum) and ``common_profile``.
    """
    grid = np.asarray(COMMON_GRID if grid is None else grid, float)
    T = prob.taus.size
    lam, V, scale = _eigen(prob, prob.taus, grid)
    stack = Problem(prob.y, prob.X0, prob.L, prob.sigma, prob.grad, prob.starts, prob.durations,
                    np.tile(prob.taus, grid.size), lam, V, scale, prob.notes, float("nan"))
    bas = basis(stack, X)
    dev = profile(stack, X, prob.y[None], Q_REL_GRID, bas=bas).reml[0].reshape(grid.size, -1).min(axis=1)
    k = int(np.argmin(dev))
    sl = slice(k * T, (k + 1) * T)
    p = Problem(prob.y, prob.X0, prob.L, prob.sigma, prob.grad, prob.starts, prob.durations, prob.taus,
                lam[sl], V[sl], scale[sl], prob.notes, float(grid[k]))
    b = Basis(bas.K, bas.U[sl], bas.mu[sl], bas.logdet_xx)
    w = fit_wander(p, X, fine=False, bas=b)
    inside = grid[dev <= dev[k] + CHI2_95]
    w = WanderFit(**{**w.__dict__, "common_ci": (float(inside.min()), float(inside.max())),
                     "common_profile": tuple(float(v) for v in dev)})
    return p, b, w


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
    bases: tuple = ()           # Basis of the current model, then of each alternative


#: Bootstrap replicates are drawn in batches of these sizes (then repeating the last), so
#: that a test can stop early (:func:`round_tests`); the draws do not depend on them.
BATCHES = (25, 25, 50, 100)


def stop_count(alpha: float, n: int) -> int:
    """Exceedances after which a test stops (Besag & Clifford 1991): the smallest ``h`` with
    ``h/n > α``.  A test stopped at its ``h``-th exceedance after ``ℓ ≤ n`` replicates has the
    p-value ``h/ℓ > α``, and with all ``n`` it would have had ``(k + 1)/(n + 1) > α`` too
    (``k ≥ h``): stopping never changes whether it can pass at level ``α``."""
    return int(math.floor(alpha * n)) + 1


def round_tests(prob: Problem, X_alts: list, rng: np.random.Generator, n_boot: int,
                outliers: bool = True, extend=None, n_boot_max: int | None = None,
                alpha: float = 0.05, null: WanderFit | None = None, bas0: Basis | None = None) -> RoundTests:
    """Likelihood-ratio tests current (``prob.X0``) vs current + each ``X_alts[k]``
    (contrast columns, appended to X0) and the outlier family, all calibrated on the same
    replicates simulated under the current model with its REML noise.

    Sequential Monte Carlo p-values (Besag & Clifford 1991): a test stops at its
    :func:`stop_count`-th exceedance, with ``p = h/ℓ`` (``ℓ`` replicates used); one that
    runs to the end has ``p = (1 + k)/(n + 1)``.  Both are valid p-values, and a stopped
    test could not have passed at level ``alpha`` with every replicate either; what stopping
    saves is the replicates of tests that are clearly not significant.

    ``extend(counts, n, final)`` (optional): given the exceedance counts of the tests (the
    outlier family last) and the p-values of those that stopped (``final``, NaN while
    running) after ``n`` replicates, the mask of the tests for which more replicates could
    change a decision.  If any, those tests grow to ``n_boot_max`` replicates (their first
    ``n_boot`` are the same draws either way) and every other test keeps its p-value.
    ``null``, ``bas0``: the current model's REML noise (``fit_wander(prob, prob.X0,
    fine=False)``) and :class:`Basis`, if the caller has them."""
    X0 = prob.X0
    Xs = [np.hstack([X0, Xa]) for Xa in X_alts]
    bases = [basis(prob, X0) if bas0 is None else bas0] + [basis(prob, X1) for X1 in Xs]
    sf0 = profile(prob, X0, prob.y[None], Q_REL_GRID, shifts=outliers, bas=bases[0])
    m0 = float(sf0.ml_min()[0])
    # the bootstrap simulates the REML noise of the current model.  (Estimating it with the
    # most outlying pose free, against masking, was tried: under a random-walk wander it
    # lowered the simulated noise and raised the outlier family's false positives from
    # 7.5 % to 11 % and the candidates' from 5.3 % to 7.2 %, 120 sessions each.)
    null = fit_wander(prob, X0, fine=False) if null is None else null
    lr = np.array([max(m0 - float(profile(prob, X1, prob.y[None], Q_REL_GRID, bas=b).ml_min()[0]), 0.0)
                   for X1, b in zip(Xs, bases[1:])])
    lr_pose = np.maximum(m0 - sf0.shift_ml_min()[0], 0.0) if outliers else np.zeros(0)
    o_i = int(np.argmax(lr_pose)) if outliers else -1
    o_lr = float(lr_pose[o_i]) if outliers else float("nan")
    observed = np.concatenate([lr, [o_lr] if outliers else []])
    # replicates drawn through the Cholesky factor of the null covariance: unique, unlike the
    # eigenvectors (whose signs depend on the LAPACK routine), so the replicates are too
    root = np.linalg.cholesky(null.white_scale * prob.sigma_c(null.t, null.q_rel))
    seq = _Sequential(len(X_alts) + outliers, stop_count(alpha, n_boot))
    cap, k = n_boot, 0
    while True:
        batch = min(BATCHES[min(k, len(BATCHES) - 1)], cap - seq.n)
        Ystar = rng.standard_normal((batch, prob.m)) @ root.T
        seq.add(_bootstrap_batch(prob, bases, Xs, Ystar, seq.running, outliers), observed)
        k += 1
        if not seq.running.any():
            break
        if seq.n == cap:
            grow = (extend(seq.counts, seq.n, seq.final) if cap == n_boot and extend is not None
                    and n_boot_max is not None and n_boot_max > n_boot else None)
            if grow is None or not np.any(grow):
                break
            seq.freeze(~np.asarray(grow, bool))   # the others keep their p-value at n_boot
            cap = n_boot_max
            seq.h = stop_count(alpha, n_boot_max)   # the running tests have fewer exceedances than that
    p_all = seq.p_values()
    t_obs, _ = studentised(prob, X0, null.t, null.q_rel, scale=null.white_scale)
    return RoundTests(lr=lr, p_values=p_all[: len(X_alts)], bartlett=seq.mean_lr(X_alts),
                      outlier_t=t_obs[0], outlier_p=float(p_all[-1]) if outliers else float("nan"),
                      outlier_pose=o_i, outlier_lr=o_lr, null_wander=null, n_boot=int(seq.n), bases=tuple(bases))


class _Sequential:
    """Exceedance counts of tests that stop at their ``h``-th exceedance (:func:`round_tests`)."""

    def __init__(self, k: int, h: int):
        self.counts = np.zeros(k, dtype=np.int64)
        self.used = np.zeros(k, dtype=np.int64)     # replicates each test has used
        self.sums = np.zeros(k)                     # sum of its replicate statistics
        self.final = np.full(k, np.nan)             # p-value of a stopped test
        self.n, self.h = 0, h

    @property
    def running(self) -> np.ndarray:
        return np.isnan(self.final)

    def add(self, stats_: np.ndarray, observed: np.ndarray) -> None:
        """Replicate statistics ``stats_`` (b, k) (NaN for the stopped tests) against the
        observed ones: count, and stop the tests that reach ``h`` exceedances."""
        tol = 1e-9 * np.maximum(1.0, np.nan_to_num(observed, nan=0.0))
        for j in np.flatnonzero(self.running):
            x = stats_[:, j]
            cum = self.counts[j] + np.cumsum(x >= observed[j] - tol[j])
            hit = np.flatnonzero(cum >= self.h)
            last = int(hit[0]) + 1 if hit.size else x.size
            self.counts[j], self.used[j] = cum[last - 1], self.used[j] + last
            self.sums[j] += float(np.sum(x[:last]))
            if hit.size:
                self.final[j] = self.h / self.used[j]
        self.n += stats_.shape[0]

    def freeze(self, mask: np.ndarray) -> None:
        """Stop the running tests of ``mask`` at their current p-value."""
        keep = mask & self.running
        self.final[keep] = ((1 + self.counts) / (self.used + 1))[keep]

    def p_values(self) -> np.ndarray:
        return np.where(self.running, (1 + self.counts) / (self.used + 1), self.final)

    def mean_lr(self, X_alts) -> np.ndarray:
        if not X_alts:
            return np.zeros(0)
        k = len(X_alts)
        return self.sums[:k] / np.maximum(self.used[:k], 1) / np.array([Xa.shape[1] for Xa in X_alts])


def _bootstrap_batch(prob: Problem, bases: list, Xs: list, Ystar: np.ndarray,
                     running: np.ndarray, outliers: bool) -> np.ndarray:
    """Replicates ``Ystar`` (B, m) drawn under the null, refitted as the data: per replicate the LR of each candidate and, last, the largest mean-shift LR over the
    poses (the noise re-estimated with the shift, so an outlier cannot hide by inflating
    it), NaN for the tests no longer ``running``."""
    out = np.full((Ystar.shape[0], len(running)), np.nan)
    best = outliers and bool(running[-1])
    sfs = profile(prob, prob.X0, Ystar, Q_REL_GRID, best_shift=best, bas=bases[0])
    m0s = sfs.ml_min()
    for k, (X1, b) in enumerate(zip(Xs, bases[1:])):
        if running[k]:
            out[:, k] = np.maximum(m0s - profile(prob, X1, Ystar, Q_REL_GRID, bas=b).ml_min(), 0.0)
    if best:
        out[:, -1] = np.maximum(m0s - sfs.best_shift_ml_min(), 0.0)
    return out


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


def simulate_interval_means(rng: np.random.Generator, terms: dict, starts, durations, size: int = 3,
                            axis_corr=None) -> np.ndarray:
    """Exact Gaussian draws of the interval means of a noise model on ``size`` axes.

    Parameters
    ----------
    terms : dict
        Noise model ``{term: coefficient}`` as :func:`accelcal.noise.model_avar`
        takes it (two-parameter terms: ``(coefficient, shape)``); for several components of
        one term pass a list of values, e.g. ``{"gauss_markov": [(s1, 3.0), (s2, 30.0)]}``.
    starts, durations : array_like (n,)
    size : int
        Axes.
    axis_corr : array_like (size, size), optional
        Correlation of the process between the axes (default: independent axes); each
        axis keeps the variance of ``terms``.

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
    z = rng.standard_normal((n, size))
    if axis_corr is not None:
        z = z @ np.linalg.cholesky(np.asarray(axis_corr, float)).T
    return root @ z


__all__ = ["CHI2_95", "COMMON_GRID", "Problem", "axis_gram", "axis_weight", "fit_common", "contrast_covariance",
           "Q_REL_GRID", "at", "RoundTests", "Surface", "WanderError", "WanderFit", "effect_information",
           "excess_distribution", "fit_wander", "gls_projector", "gls_step", "gm_variance", "problem", "profile",
           "round_tests", "simulate_interval_means", "studentised", "tau_grid", "wander_kernel"]
