"""Fit of a noise model to a measured Allan variance (the Allan-deviation term fit).

Fit.  The model AVAR is linear in the squared coefficients ``c = (N², Q², …) ≥ 0`` (for
a given ``T_c`` or ``f₀``, which are profiled over their grids).  Each pooled AVAR point ``Â_j`` is treated as ``A_j χ²_{ν_j}/ν_j``
(Gamma, shape ``ν_j/2``) with ``ν_j`` the pooled white-FM edf of :mod:`.allan`; ``c``
maximises this likelihood subject to ``c ≥ 0`` (Fisher scoring = iteratively
reweighted non-negative least squares with weights ``ν_j/A_j²``).  Deviance
``D = Σ ν_j (Â_j/A_j − 1 − ln(Â_j/A_j))``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from .. import kernels
from .terms import TERMS, NoiseModelError, model_avar, noise_term


@dataclass(frozen=True)
class NoiseFit:
    """Gamma maximum-likelihood fit of an Allan-variance model (module docstring).

    ``c`` are the squared coefficients in the order of ``term_ids``; ``shape`` the
    nonlinear parameter of the model's two-parameter term (NaN without one);
    ``deviance`` the Gamma deviance over the τ points.
    """

    term_ids: tuple[str, ...]
    c: np.ndarray
    shape: float
    deviance: float

    @property
    def coefficients(self) -> dict[str, float]:
        """IEEE 952 coefficient of each term (σ for ``gauss_markov``, A for ``sinusoid``)."""
        return {k: float(math.sqrt(max(v, 0.0))) for k, v in zip(self.term_ids, self.c)}

    @property
    def model(self) -> dict[str, object]:
        """The model in the form :func:`simulate_segments` and :func:`model_avar` take."""
        return {k: ((v, self.shape) if TERMS[k].shape_key else v) for k, v in self.coefficients.items()}

    def avar(self, taus, fs: float) -> np.ndarray:
        return model_avar(self.model, taus, fs)


def gamma_deviance(avar_measured, avar_model, edf) -> np.ndarray:
    """``Σ ν (r − 1 − ln r)`` over the last axis, ``r = measured / model``."""
    r = np.asarray(avar_measured) / np.asarray(avar_model)
    return np.sum(np.asarray(edf) * (r - 1.0 - np.log(r)), axis=-1)


def _nnls_batch(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Non-negative least squares for a batch of small problems, ``A`` (G, k, p), ``b`` (G, k).

    The solution is the least-squares solution on its support, so the best feasible
    least-squares solution over all 2^p − 1 supports is the optimum (p ≤ 7 here).
    """
    G, _, p = A.shape
    best_x = np.zeros((G, p))
    bb = np.einsum("gk,gk->g", b, b)
    best = bb.copy()
    # the Gram matrix and Aᵀb once; a support's objective is bᵀb − 2 xᵀAᵀb + xᵀ(AᵀA)x
    gram_all = np.einsum("gki,gkj->gij", A, A)
    rhs_all = np.einsum("gki,gk->gi", A, b)
    for s in range(1, p + 1):
        for idx in combinations(range(p), s):
            gram = gram_all[:, idx][:, :, idx] + 1e-12 * np.eye(s)
            rhs = rhs_all[:, idx]
            x = np.linalg.solve(gram, rhs[..., None])[..., 0]
            obj = bb - 2 * np.einsum("gi,gi->g", x, rhs) + np.einsum("gi,gij,gj->g", x, gram_all[:, idx][:, :, idx], x)
            ok = np.all(x >= 0, axis=1) & (obj < best)
            best = np.where(ok, obj, best)
            best_x[ok] = 0.0
            best_x[np.ix_(ok, idx)] = x[ok]
    return best_x


def _irls(H: np.ndarray, y: np.ndarray, edf: np.ndarray, max_iter: int = 200, tol: float = 1e-10):
    """Gamma ML with identity link and ``c ≥ 0`` for a batch: ``H`` (G, k, p), ``y`` (G, k) → (c, deviance).

    Fisher scoring (weighted NNLS with weights ``ν/A²`` at the current model), with step
    halving whenever a step would raise the deviance (the Gamma deviance is not convex
    in ``c``, and plain scoring can cycle); each problem stops when its deviance changes
    by less than ``tol`` relative.
    """
    fast = kernels.compiled("noise._fast")
    if fast is not None:  # the same algorithm, compiled (accelcal[fast])
        return fast.irls_gamma(H, y, edf, max_iter, tol)
    G = y.shape[0]
    floor = 1e-12 * y.max(axis=1, keepdims=True)
    sw = np.sqrt(edf)
    c = np.zeros((G, H.shape[2]))
    model = y.copy()  # first weights from the data themselves
    dev = np.full(G, np.inf)
    active = np.arange(G)
    for _ in range(max_iter):
        Ha, ya, fa = H[active], y[active], floor[active]
        w = sw / model[active]
        A = Ha * w[:, :, None]
        scale = np.linalg.norm(A, axis=1)
        scale[scale == 0] = 1.0
        c_new = _nnls_batch(A / scale[:, None, :], ya * w) / scale
        m_new = np.maximum(np.einsum("gkp,gp->gk", Ha, c_new), fa)
        d_new = gamma_deviance(ya, m_new, edf)
        d_old = dev[active]
        for _ in range(30):  # step halving towards the previous (feasible) c
            worse = d_new > d_old
            if not worse.any():
                break
            c_new[worse] = 0.5 * (c_new[worse] + c[active][worse])
            m_new[worse] = np.maximum(np.einsum("gkp,gp->gk", Ha[worse], c_new[worse]), fa[worse])
            d_new[worse] = gamma_deviance(ya[worse], m_new[worse], edf)
        keep = d_new <= d_old
        c_new[~keep], m_new[~keep], d_new[~keep] = c[active][~keep], model[active][~keep], d_old[~keep]
        converged = np.abs(d_old - d_new) <= tol * (1.0 + np.abs(d_new))
        c[active], model[active], dev[active] = c_new, m_new, d_new
        active = active[~converged]
        if active.size == 0:
            break
    return c, dev


def fit_avar_batch(taus, avar, edf, term_ids: Sequence[str], fs: float) -> list[NoiseFit]:
    """:func:`fit_avar` for many data sets at once, ``avar`` shape (G, k)."""
    taus, edf = np.asarray(taus, dtype=float), np.asarray(edf, dtype=float)
    y = np.atleast_2d(np.asarray(avar, dtype=float))
    if y.shape[1] != taus.size or np.any(y <= 0) or not np.all(np.isfinite(y)):
        raise NoiseModelError("Allan variance must be positive and finite at every tau (constant data?)")
    term_ids = tuple(term_ids)
    for k in term_ids:
        noise_term(k)
    G = y.shape[0]
    shaped = [k for k in term_ids if TERMS[k].shape_key]
    if len(shaped) > 1:
        raise NoiseModelError(f"at most one two-parameter term per model, got {shaped}")
    if not shaped:
        H = np.column_stack([noise_term(k).basis(taus, fs) for k in term_ids])
        c, dev = _irls(np.broadcast_to(H, (G,) + H.shape), y, edf)
        return [NoiseFit(term_ids, c[g], float("nan"), float(dev[g])) for g in range(G)]
    grid = TERMS[shaped[0]].shape_grid(fs, taus.max())
    Hs = np.stack([np.column_stack([noise_term(k).basis(taus, fs, sh) for k in term_ids]) for sh in grid])
    H = np.broadcast_to(Hs[None], (G,) + Hs.shape).reshape(G * grid.size, *Hs.shape[1:])
    c, dev = _irls(H, np.repeat(y, grid.size, axis=0), edf)
    c, dev = c.reshape(G, grid.size, -1), dev.reshape(G, grid.size)
    best = np.argmin(dev, axis=1)
    return [NoiseFit(term_ids, c[g, best[g]], float(grid[best[g]]), float(dev[g, best[g]])) for g in range(G)]


def fit_avar(taus, avar, edf, term_ids: Sequence[str], fs: float) -> NoiseFit:
    """Fit ``AVAR(τ) = Σ c_k basis_k(τ)``, ``c ≥ 0``, by Gamma maximum likelihood.

    Parameters
    ----------
    taus, avar, edf : array_like, shape (k,)
        Averaging times [s], measured Allan variance (> 0) and its degrees of freedom.
    term_ids : sequence of str
        Terms of the model (ids of :data:`TERMS`); at most one two-parameter term,
        whose nonlinear parameter is profiled over :meth:`NoiseTerm.shape_grid`.
    fs : float
        Sampling rate [Hz] (the Gauss–Markov basis is that of the sampled process).
    """
    return fit_avar_batch(taus, np.asarray(avar, dtype=float)[None], edf, term_ids, fs)[0]


__all__ = ["NoiseFit", "fit_avar", "fit_avar_batch", "gamma_deviance"]
