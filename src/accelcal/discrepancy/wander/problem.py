"""The wander null's noise model of the pose means and the linearised problem it is tested on.

The kernels of the wander (interval-mean variograms, their projection through the poses'
gradients and the axis correlation) and :class:`Problem`: the pose residuals in whitened
contrast coordinates, with the kernels diagonalised on a grid of correlation times
(package docstring, "Noise model of the pose means" and "Linear model").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import AccelcalError
from .members import MEMBERS, column_members, member_of
from .rests import RestAllan

#: Correlation times per decade of the grid of the tests, and of the report's profile.
TAU_PER_DECADE = 5
TAU_PER_DECADE_FINE = 10
#: Residual degrees of freedom (poses − parameters) the wander's two parameters need at
#: least (a variance from 6 degrees of freedom has a relative standard error of 58 %).
MIN_WANDER_DOF = 6
#: Instantaneous poses (no intervals known) are given this duration [s].
POINT_DURATION = 1e-3


class WanderError(AccelcalError):
    """The pose residuals cannot support the wander null (too few poses, degenerate design)."""



# --------------------------------------------------------------------------- kernels


def is_timed(taus) -> np.ndarray:
    """Whether each member of a grid has a correlation time (Gauss–Markov or random walk,
    not the per-placement offset nor flicker: :attr:`.members.GridMember.timed`)."""
    taus = np.asarray(taus, float)
    out = np.zeros(taus.shape, bool)
    for m, own in column_members(taus):
        out |= own & m.timed
    return out


def tau_grid(durations, span: float, per_decade: int = TAU_PER_DECADE, members=None) -> np.ndarray:
    """The wander's grid: the codes of each member of :data:`.members.MEMBERS` (``members``:
    their ids, default all), in table order — flicker (:data:`~.members.FLICKER`), the per-placement
    offset (:data:`~.members.PLACEMENT`), correlation times [s], ``per_decade`` per decade from a
    tenth of the shortest pose to ten session lengths, then ``inf`` (the random walk)."""
    lo = 0.1 * max(float(np.min(durations)), POINT_DURATION)
    hi = 10.0 * max(span, 10 * lo)
    chosen = MEMBERS.values() if members is None else [m for m in MEMBERS.values() if m.id in members]
    return np.concatenate([m.codes(lo, hi, per_decade) for m in chosen])


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
    """``D_ij = Var(β̄_i − β̄_j)`` of a unit wander for every code of ``taus`` (T, n, n):
    each member's own (:meth:`.members.GridMember.variogram`)."""
    taus = np.asarray(taus, float)
    a, T = np.asarray(starts, float), np.asarray(durations, float)
    first_end = np.where(a[:, None] <= a[None, :], (a + T)[:, None], (a + T)[None, :])
    gap = np.maximum(np.maximum(a[:, None], a[None, :]) - first_end, 0.0)      # (n, n)
    D = np.empty((taus.size,) + gap.shape)
    for m, own in column_members(taus):
        D[own] = m.variogram(taus[own], a, T, gap)
    idx = np.arange(gap.shape[0])
    D[:, idx, idx] = 0.0
    return D


def gm_variance(q_abs: float, tau: float) -> tuple[float, float]:
    """``(s, K)`` of a wander: Gauss–Markov std ``s`` and its short-lag random-walk
    coefficient ``K = sqrt(2 s²/τ)``; for ``tau = inf``, ``q_abs`` is ``K²`` and ``s = inf``;
    for the per-placement offset (``tau = 0``) ``s`` its std and ``K`` NaN (no time scale);
    for flicker (``tau = −1``) ``s`` its coefficient ``B`` and ``K`` NaN (the member's
    :meth:`~.members.GridMember.size_K`)."""
    return member_of(tau).size_K(q_abs, tau)


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
    rests : RestAllan or None
        The rests' own samples, when the likelihood borrows from them (:mod:`.rests`).
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
    rests: RestAllan | None = None

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

    def _rebuilt(self, taus, common):
        lam, V, scale = kernel_eigensystems(self, taus, common)
        return Problem(self.y, self.X0, self.L, self.sigma, self.grad, self.starts, self.durations,
                       taus, lam, V, scale, self.notes, common, self.rests)

    def sigma_c(self, t: int, q: float) -> np.ndarray:
        """Contrast covariance ``I + q K_τ`` at grid point ``(t, q)`` (relative ``q``)."""
        V = self.V[t]
        return (V * (1.0 + q * self.lam[t])) @ V.T


def kernel_eigensystems(prob, taus, common):
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


def problem(r, J, sigma, grad, starts, durations, taus=None, notes=(), common: float | None = 0.0,
            rests: RestAllan | None = None) -> Problem:
    """Build the :class:`Problem` of a fit: residuals ``r`` (n,), Jacobian ``J`` (n, q) whose
    first three columns are the bias, ``σ`` (n,), gradients ``∇`` (n, 3), pose intervals,
    the wander's axis correlation ``common`` (:func:`axis_gram`; None: the kernels are not
    diagonalised, for :func:`fit_common`, which does it for every ``φ`` of its grid), and
    the rests' Allan variances ``rests`` if the likelihood borrows from them.

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
                   np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0), tuple(notes), float("nan"), rests)
    return prob if common is None else prob._rebuilt(prob.taus, float(common))



__all__ = ["MIN_WANDER_DOF", "POINT_DURATION", "TAU_PER_DECADE", "TAU_PER_DECADE_FINE", "Problem", "WanderError",
           "axis_gram", "axis_weight", "gm_variance", "is_timed", "kernel_eigensystems", "problem", "tau_grid",
           "wander_kernel", "wander_kernels"]
