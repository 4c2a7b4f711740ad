"""Generalised least squares on a linearised problem: the likelihood over the grid of ``(τ, q)``.

:func:`profile` gives the likelihood :class:`Surface` of data sets under a model's
columns (its :class:`Basis`: the contrasts it leaves free, where its GLS residual
projector is diagonal); :func:`gls_projector` and :func:`studentised` the GLS residuals,
outlier statistics and leave-one-pose-out errors; :func:`effect_information`,
:func:`gls_step` and :func:`excess_distribution` the information of an effect, the GLS
estimate and the distribution of the least-squares χ² under the noise (package
docstring, "Linear model", "Outliers" and "Leave-one-pose-out").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ... import kernels
from .problem import Problem

#: The compiled kernel of :func:`grid_ml_min` (:mod:`._grid_kernels`).
_KERNELS = "discrepancy.wander._grid_kernels"

#: Relative wander variance ``q`` (over the white variance of the contrasts) the tests
#: profile over: 0, then three per decade (the likelihood is smooth in log q: the grid
#: maximum is within a few hundredths of the continuous one, the same for data and replicates).
Q_REL_GRID = np.concatenate([[0.0], np.logspace(-2.0, 3.0, 16)])


#: Smallest white scale ``s`` the noise model may take.  The rests measure the white noise
#: of each pose directly (hundreds of samples per pose); the static detection's standard
#: errors overestimate it by 10-25 % in variance (Geyer's sum of positive autocorrelation
#: pairs: residual excess 0.81-0.87 on simulated white noise).  Without a floor the model
#: could explain a deterministic trend as a large random walk with almost no white noise,
#: which the rests contradict.
MIN_WHITE_SCALE = 0.5
#: Largest white scale: the rests' standard errors off by a factor of two.  They come from
#: the pose's own samples, so what they miss is noise that is constant within a pose and
#: changes between poses (a per-placement offset, a wander): the noise model's second term,
#: which must carry it (a white scale of 24-230 once stood for the FXOS8700 sessions'
#: per-placement offsets, whose rests agree with their standard errors within 0.8-1.0).
MAX_WHITE_SCALE = 4.0


def _neg2ll(quad, nu, logdet):
    """``−2 log`` likelihood with the white scale at its optimum ``quad/nu`` clipped to
    [:data:`MIN_WHITE_SCALE`, :data:`MAX_WHITE_SCALE`] (``nu log s + quad/s + logdet``,
    constants dropped)."""
    quad = np.clip(quad, 1e-300, None)
    s = np.clip(quad / nu, MIN_WHITE_SCALE, MAX_WHITE_SCALE)
    return nu * np.log(s) + quad / s + logdet


def _neg2ll_min(quad, nu, logdet):
    """Minimum over the grid of :func:`_neg2ll` per data set: ``quad`` (B, T, Q), ``logdet`` (T, Q).

    The same number with one logarithm per data set instead of one per grid point: where
    the white scale is inside its range, ``−2ℓ = ν (log(x e^{logdet/ν}) + 1)`` (``x = quad/ν``)
    is smallest where the product is; at either end of the range ``−2ℓ`` is linear in ``quad``.
    """
    quad = np.clip(quad.reshape(quad.shape[0], -1), 1e-300, None)
    ld = logdet.reshape(-1)
    floored = quad < MIN_WHITE_SCALE * nu
    capped = quad > MAX_WHITE_SCALE * nu
    ld0 = float(ld.min())  # the rests' deviance (:mod:`.rests`) can make logdet large: scaled
    with np.errstate(over="ignore"):
        prod = np.where(floored | capped, np.inf, quad * np.exp((ld - ld0) / nu)[None]).min(axis=1)
    with np.errstate(divide="ignore"):
        out = nu * (np.log(prod / nu) + 1.0) + ld0
    for end, mask in ((MIN_WHITE_SCALE, floored), (MAX_WHITE_SCALE, capped)):
        if mask.any():
            lin = np.where(mask, quad / end + ld[None], np.inf).min(axis=1) + nu * math.log(end)
            out = np.minimum(out, lin)
    return out


@dataclass(frozen=True)
class Surface:
    """Likelihood of data sets over the grid of ``(τ, q)``, the white scale ``s`` profiled out.

    ``quad`` (B, T, Q): ``yᵀ P y`` with ``P`` the GLS residual projector of ``I + q K_τ``;
    ``logdet`` (T, Q): ``log|I + q K_τ|``; ``logdet_a`` (T, Q): ``log|Xᵀ(I + q K_τ)⁻¹X|``;
    ``m`` contrasts, ``p`` columns; ``shift_quad`` (B, T, Q, n) or None: ``quad`` of the
    model with a free shift of each pose.  With ``Σ = s (I + q K_τ)``, ``s`` at its optimum
    ``ŝ = quad/ν`` clipped to [MIN_WHITE_SCALE, MAX_WHITE_SCALE], ``ν = m`` (ML) or ``m − p`` (REML)::

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
        return np.clip(self.quad / (self.m - self.p if reml else self.m), MIN_WHITE_SCALE, MAX_WHITE_SCALE)

    def ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` per data set (B,)."""
        return _neg2ll_min(self.quad, self.m, self.logdet)

    def shift_ml_min(self) -> np.ndarray:
        """Grid minimum of ``−2ℓ`` of the model with pose ``i`` shifted, per data set (B, n)."""
        ml = _neg2ll(self.shift_quad, self.m, self.logdet[None, :, :, None])
        return ml.reshape(ml.shape[0], -1, ml.shape[-1]).min(axis=1)


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

    @cached_property
    def grid_weights(self) -> np.ndarray:
        """``1/(1 + q μ_j)`` (T, Q, r) over :data:`Q_REL_GRID`: the same for every data set
        (a round's bootstrap refits each model on several batches of replicates)."""
        q = np.broadcast_to(Q_REL_GRID, (self.U.shape[0], Q_REL_GRID.size))
        return 1.0 / (1.0 + q[:, :, None] * self.mu[:, None, :])


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
            bas: Basis | None = None) -> Surface:
    """The likelihood :class:`Surface` of data sets ``Y`` (B, m) under the model with columns
    ``X`` (m, p), over the grid ``prob.taus`` × ``qrel`` ((Q,), or (T, Q): one row per τ);
    with ``prob.rests``, the rests' deviance joins ``logdet`` (:mod:`.rests`).

    The quadratic forms are taken in the model's own contrasts (:class:`Basis`, computed
    here unless given as ``bas``): ``yᵀ P y = Σ_j ỹ_j² / (1 + q μ_j)`` with ``ỹ = Uᵀ Kᵀ y``,
    and ``log|XᵀΣ⁻¹X| = log|KᵀΣK| + log|XᵀX| − log|Σ|``.

    ``shifts``: also the model with a free shift of pose ``i``'s residual, for every pose
    (the outlier model): ``quad − (P r)_i²/P_ii`` (a rank-one update of the GLS fit, ``P``
    the residual projector in the pose space).
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
    logdet = _with_rests(prob, logdet, q)
    shift_quad = None
    if shifts:
        M = (prob.L @ bas.K)[None] @ bas.U                      # (T, n, r): poses from rotated contrasts
        d = np.clip((M * M) @ w.transpose(0, 2, 1), 1e-300, None)   # (T, n, Q): P_ii
        # (P r)_i / sqrt(P_ii) for all (q, i) as one matrix product per τ (Q n × r times r × B)
        A = M[:, None] * w[:, :, None, :] / np.sqrt(d.transpose(0, 2, 1))[..., None]   # (T, Q, n, r)
        z = A.reshape(T, -1, A.shape[-1]) @ Yt.transpose(0, 2, 1)                     # (T, Q n, B)
        gain = np.square(z, out=z).reshape(T, q.shape[1], -1, Y.shape[0])             # (T, Q, n, B)
        shift_quad = np.clip(quad.transpose(1, 2, 0)[:, :, None, :] - gain, 1e-300, None).transpose(3, 0, 1, 2)
    return Surface(quad, logdet, logdet_a, prob.m, p, shift_quad)


def _with_rests(prob: Problem, logdet: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``logdet`` with the rests' deviance when the likelihood borrows from them (:mod:`.rests`:
    it rides on ``log|Σ|``)."""
    return logdet if prob.rests is None else logdet + prob.rests.deviance_grid(prob.taus, prob.scale, q)


def grid_logdet(prob: Problem, qrel=Q_REL_GRID) -> np.ndarray:
    """``log|I + q K_τ|`` (T, Q) over ``prob.taus`` × ``qrel``, with the rests' deviance
    (:func:`profile`'s ``logdet``: the same for every model's columns on ``prob``)."""
    qrel = np.asarray(qrel, float)
    q = np.broadcast_to(qrel, (prob.taus.size, qrel.shape[-1]))
    return _with_rests(prob, np.log(1.0 + q[:, :, None] * prob.lam[:, None, :]).sum(axis=2), q)


def grid_ml_min(bases: list, Y: np.ndarray, logdet: np.ndarray, m: int) -> np.ndarray:
    """Grid minimum of ``−2ℓ`` (G, B) of data sets ``Y`` (B, m) under each of ``G`` models of
    as many free contrasts (their :class:`Basis` on one problem's grid of ``τ`` ×
    :data:`Q_REL_GRID`; ``logdet`` its :func:`grid_logdet`): :meth:`Surface.ml_min` of
    :func:`profile` for every model at once, without the surface.

    The compiled kernel (:mod:`._grid_kernels`) keeps running minima over the grid instead
    of building the quadratic forms of every grid point (models × τ × data sets × q); the
    exponentials and logarithms of both paths are numpy's."""
    K = np.stack([b.K for b in bases])                              # (G, m, r)
    U = np.stack([b.U for b in bases])                              # (G, T, r, r)
    w = np.stack([b.grid_weights for b in bases])                   # (G, T, Q, r)
    Y = np.atleast_2d(Y)
    Yt = (Y[None] @ K)[:, None] @ U                                 # (G, T, B, r)
    G, B = U.shape[0], Y.shape[0]
    kern = kernels.compiled(_KERNELS)
    if kern is None:
        quad = ((Yt * Yt) @ w.transpose(0, 1, 3, 2)).transpose(0, 2, 1, 3)   # (G, B, T, Q)
        return _neg2ll_min(quad.reshape((G * B,) + quad.shape[2:]), m, logdet).reshape(G, B)
    ld = np.asarray(logdet, float)
    ld0 = float(ld.min())
    with np.errstate(over="ignore"):
        ex = np.exp((ld - ld0) / m)
    prod, low, high = kern.grid_minima(Yt, w, ex, ld, m, MIN_WHITE_SCALE, MAX_WHITE_SCALE)
    with np.errstate(divide="ignore"):
        out = m * (np.log(prod / m) + 1.0) + ld0
    for end, lin in ((MIN_WHITE_SCALE, low), (MAX_WHITE_SCALE, high)):
        out = np.minimum(out, lin + m * math.log(end))
    return out


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



# --------------------------------------------------------------------------- information, MDE, GLS


@dataclass(frozen=True)
class EffectInformation:
    """Fisher information of an effect block profiled over the current model (k, k) under
    three noise models: the wander one (``wander``), white noise (``white``) and white
    noise of the same mean variance (``scaled_white``: what a common scale factor would give)."""

    wander: np.ndarray
    white: np.ndarray
    scaled_white: np.ndarray


def effect_information(prob: Problem, X0: np.ndarray, Xe: np.ndarray, t: int | None = None, q: float = 0.0,
                       sigma_c: np.ndarray | None = None) -> EffectInformation:
    """:class:`EffectInformation` of an effect block ``Xe`` profiled over ``X0``, the wander
    noise being the wander ``(t, q)`` or the contrast covariance ``sigma_c``."""
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
    return EffectInformation(wander=info(Si), white=I_white, scaled_white=I_white / mean_var)



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



def excess_distribution(prob: Problem, X: np.ndarray, t: int, q: float, scale: float = 1.0) -> np.ndarray:
    """Eigenvalues ``μ`` of ``(I − H) Σ_c (I − H)`` (``H`` the unweighted hat of ``X``,
    ``Σ_c = scale (I + q K_τ)``): under the noise model the weighted χ² of the least-squares
    residuals is ``Σ μ_k χ²₁``."""
    Q, _ = np.linalg.qr(X) if X.shape[1] else (np.zeros((prob.m, 0)), None)
    R = np.eye(prob.m) - Q @ Q.T
    S = scale * prob.sigma_c(t, q)
    mu = np.linalg.eigvalsh(R @ S @ R)
    return np.clip(mu, 0.0, None)


__all__ = ["MAX_WHITE_SCALE", "MIN_WHITE_SCALE", "Q_REL_GRID", "Basis", "EffectInformation", "Surface", "basis",
           "effect_information", "excess_distribution", "gls_projector", "gls_step", "grid_logdet", "grid_ml_min",
           "profile", "studentised"]
