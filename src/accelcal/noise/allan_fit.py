"""Fit of a noise model to a measured Allan variance (the Allan-deviation term fit), shared by the
discrepancy stochastic layer and the noise analysis of a static recording (:mod:`.report`).

Fit (:func:`fit_avar`).  The model AVAR is linear in the squared coefficients
``c = (N², Q², …) ≥ 0`` (for a given ``T_c`` or ``f₀``, which are profiled over their
grids).  Each pooled AVAR point ``Â_j`` is treated as ``A_j χ²_{ν_j}/ν_j`` (Gamma, shape
``ν_j/2``) with ``ν_j`` given weights (the stochastic layer: the pooled white-FM edf of
:mod:`.allan`); ``c`` maximises this likelihood subject to ``c ≥ 0`` (Fisher scoring =
iteratively reweighted non-negative least squares with weights ``ν_j/A_j²``).  Deviance
``D = Σ ν_j (Â_j/A_j − 1 − ln(Â_j/A_j))``.

The same fit with two refinements (:func:`fit_avar_model_error`, the noise analysis of a
long static record): the weights are the edf of the fitted model itself
(:func:`model_edf`: its terms' NIST edf mixed coherently, see there), and a model-error
variance is added where the terms cannot follow the data to within its sampling error.
The stochastic layer keeps the white-FM weights and no model error, and its error bars
the Satterthwaite mix (``model_edf(..., mix='satterthwaite')``): its outputs are
unchanged.  Its rests are short, white noise dominates their Allan variance, and its tests
are calibrated by a bootstrap of the time series with those weights.

Intervals (:func:`bootstrap_fits`): the coefficients refitted to correlated draws of the
fitted model's Allan variances (:func:`log_avar_covariance`, with the correlation of
``ln Â`` between octaves that each term carries,
:attr:`~accelcal.noise.terms.NoiseTerm.octave_correlation`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from .. import distributions as dist, kernels
from .allan import AllanVariance, allan_variance
from .simulation import simulate_noise
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


#: Gradient below which a column does not enter the passive set of :func:`_nnls_batch`
#: (the columns have unit norm; the compiled kernel uses the same).
_NNLS_TOL = 1e-13


def _nnls_batch(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Non-negative least squares for a batch of small problems, ``A`` (G, k, p), ``b`` (G, k).

    Lawson and Hanson's active-set method (Solving Least Squares Problems, 1974, ch. 23; as
    ``scipy.optimize.nnls`` and the compiled :func:`accelcal.noise._fast._nnls_small`), run on
    every problem of the batch at once on the Gram matrix ``AᵀA + 1e-12 I``: a column enters
    the passive set while the gradient ``Aᵀ(b − A x)`` is positive on it, a step that would
    make a passive coefficient negative stops at the boundary and frees it.  Each step is
    one stacked solve (a passive set's system is the Gram matrix with the rows and columns
    outside it replaced by the identity and ``Aᵀb`` by 0 there, whose solution is the
    sub-system's, zero outside).  About 2p solves of the batch instead of one of all its
    2^p − 1 supports (p = 5: 31 systems per problem): the same optimum, the problem being
    strictly convex (1e-14 apart on the ADIS record's report).
    """
    G, _, p = A.shape
    eye = np.eye(p)
    gram = np.einsum("gki,gkj->gij", A, A) + 1e-12 * eye
    rhs = np.einsum("gki,gk->gi", A, b)
    x = np.zeros((G, p))
    passive = np.zeros((G, p), dtype=bool)
    rows = np.arange(G)
    for _ in range(4 * p):
        w = np.where(passive, -np.inf, rhs - np.einsum("gij,gj->gi", gram, x))
        j = np.argmax(w, axis=1)  # the first of equal gradients, as the compiled scan keeps
        todo = np.flatnonzero(w[rows, j] > _NNLS_TOL)
        if todo.size == 0:
            break
        passive[todo, j[todo]] = True
        for _ in range(p + 1):
            todo = _nnls_step(gram, rhs, x, passive, todo)
            if todo.size == 0:
                break
    return x


def _nnls_step(gram, rhs, x, passive, todo) -> np.ndarray:
    """One inner step of :func:`_nnls_batch` for the problems ``todo``: the solution on the
    passive set taken where it is positive, else a step to the boundary (the blocking
    coefficient and any at zero freed); the problems that still step."""
    P = passive[todo]
    sub = np.where(P[:, :, None] & P[:, None, :], gram[todo], np.eye(P.shape[1]))
    s = np.linalg.solve(sub, np.where(P, rhs[todo], 0.0)[..., None])[..., 0]
    xt = x[todo]
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = np.where(P & (s <= 0.0), xt / (xt - s), np.inf)
    steps[np.isnan(steps)] = np.inf  # 0/0: a coefficient at zero that stays there blocks nothing
    block = np.argmin(steps, axis=1)
    alpha = steps[np.arange(len(todo)), block]
    done = np.isinf(alpha)
    x[todo[done]] = s[done]
    t, a = todo[~done], alpha[~done, None]
    xn = xt[~done] + a * (s[~done] - xt[~done])
    free = P[~done] & ((np.arange(P.shape[1]) == block[~done, None]) | (xn <= 0.0))
    xn[free] = 0.0
    passive[t] &= ~free
    x[t] = xn
    return t


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


#: How the terms' edf combine at one τ (:func:`model_edf`).
EDF_MIXES = ("coherent", "satterthwaite")


def model_edf(allan: AllanVariance, fit: NoiseFit, mix: str = "coherent") -> np.ndarray:
    """Edf of each τ for the fitted model, from its terms' NIST edf (:meth:`AllanVariance.edf_for`;
    ``gauss_markov``: random-walk-like below its ``T_c``, white-like above) weighted by their
    share ``w_t`` of the model's Allan variance.

    ``mix='coherent'`` (default): ``1/√ν = Σ_t w_t/√ν_t``.  The Allan variance of a sum of
    independent processes is not a weighted mean of independent estimates: the second
    differences of all the terms enter the same squares, and the cross products, of mean
    zero, add variance.  When the autocorrelations of the terms' second differences have the
    same shape (nearly so: the averaging window sets it) the relative standard errors add
    linearly.  Measured on 120 simulated 2.9 h records of white noise, flicker and random
    walk of comparable size, the standard deviation of ``ln Â`` at τ = 82 s was 0.107, the
    coherent mix gives 0.108, the Satterthwaite mix 0.072 (at τ = 164 s: 0.157, 0.162, 0.094).

    ``mix='satterthwaite'``: ``1/ν = Σ_t w_t²/ν_t``, the edf of a weighted mean of
    independent estimates, which understates the variance where terms overlap; the
    discrepancy stochastic layer keeps it for its error bars (its outputs unchanged).
    """
    if mix not in EDF_MIXES:
        raise NoiseModelError(f"mix must be one of {', '.join(EDF_MIXES)}, got {mix!r}")
    taus = allan.taus
    parts, nus = [], []
    for k, c in zip(fit.term_ids, fit.c):
        parts.append(c * noise_term(k).basis(taus, allan.fs, fit.shape if TERMS[k].shape_key else None))
        nus.append(noise_term(k).edf(allan, fit.shape))
    total = np.sum(parts, axis=0)
    if mix == "satterthwaite":
        return total**2 / np.sum([p**2 / np.maximum(nu, 1e-12) for p, nu in zip(parts, nus)], axis=0)
    rel = np.sum([p / total * np.sqrt(2.0 / np.maximum(nu, 1e-12)) for p, nu in zip(parts, nus)], axis=0)
    return 2.0 / rel**2


def fit_avar_model_error(allan: AllanVariance, avar, term_ids: Sequence[str],
                         max_iter: int = 10) -> tuple[NoiseFit, np.ndarray, float]:
    """:func:`fit_avar` of ``avar`` (one column of ``allan``) weighted by the model's own edf,
    with the model error the fit leaves.

    Returns (fit, edf of each τ used by the fit, model error σ_m).  ``ln Â_j`` has
    variance ``2/ν_j`` under the model; a model that misses a feature of the data (a
    filter, a periodic disturbance) leaves residuals larger than that, and fitted with the
    statistical weights alone the points of highest edf (the shortest τ, up to 10⁶ on a
    long record) would pull every other term away from the data.  So the variance is
    taken as ``2/ν_j + σ_m²`` with ``σ_m²`` solving ``Σ (ln Â_j/A_j)² / (2/ν_j + σ_m²) = k − p``
    (zero when the statistical variances already explain the residuals: a moment
    estimator as in random-effects meta-analysis), alternated with the fit until σ_m
    settles; the fit and the bootstrap use ``ν_eff = 1 / (1/ν + σ_m²/2)``, ``ν`` the
    model's edf (:func:`model_edf`).  The first fit is weighted by the white-FM edf.
    """
    y = np.asarray(avar, dtype=float)
    fit = fit_avar(allan.taus, y, allan.edf, term_ids, allan.fs)
    s2 = -1.0
    for _ in range(max_iter):
        nu = model_edf(allan, fit)
        lr2 = np.log(y / fit.avar(allan.taus, allan.fs)) ** 2
        dof = max(len(y) - int(np.sum(fit.c > 0)), 1)
        new = _model_error_variance(lr2, nu, dof)
        edf = 1.0 / (1.0 / nu + new / 2.0)
        fit = fit_avar(allan.taus, y, edf, term_ids, allan.fs)
        if abs(new - s2) <= 1e-3 * max(new, 1e-12):
            break
        s2 = new
    return fit, edf, math.sqrt(new)


def _model_error_variance(lr2: np.ndarray, nu: np.ndarray, dof: int) -> float:
    """σ² ≥ 0 with ``Σ lr2 / (2/ν + σ²) = dof`` (bisection on a decreasing function), 0 if none needed."""
    def q(s2):
        return float(np.sum(lr2 / (2.0 / nu + s2)))

    if q(0.0) <= dof:
        return 0.0
    lo, hi = 0.0, max(float(lr2.max()), 1e-12) * len(lr2)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if q(mid) > dof else (lo, mid)
    return 0.5 * (lo + hi)


def log_avar_covariance(allan: AllanVariance, fit: NoiseFit, model_error: float = 0.0) -> np.ndarray:
    """(k, k) covariance of ``ln Â`` at the τ grid under the fitted model, plus the model error on the diagonal.

    Correlations: each term ``t`` contributes ``ρ_t(d_ij) s_it s_jt`` with
    ``s_it = A_it √(2/ν_it) / A_i`` (its share of the Allan variance times its relative
    standard error, NIST edf) and ``d_ij`` the octaves between the two τ (``ρ_t``: the term's
    :meth:`~accelcal.noise.terms.NoiseTerm.octave_rho`), normalised to a correlation matrix.
    Variances: ``2/ν`` of the coherent mix (:func:`model_edf`), plus ``σ_m²``.
    """
    octave = np.log2(allan.m.astype(float))
    d = np.rint(np.abs(octave[:, None] - octave[None, :])).astype(int)
    total = fit.avar(allan.taus, allan.fs)
    cov = np.zeros(d.shape)
    for k, c in zip(fit.term_ids, fit.c):
        rho = noise_term(k).octave_rho(d)
        part = c * TERMS[k].basis(allan.taus, allan.fs)
        s = part / total * np.sqrt(2.0 / np.maximum(allan.edf_for(TERMS[k].alpha), 1e-12))
        cov += rho * np.outer(s, s)
    sd = np.sqrt(np.diag(cov))
    coherent = np.sqrt(2.0 / model_edf(allan, fit))
    return cov * np.outer(coherent / sd, coherent / sd) + model_error**2 * np.eye(len(d))


def bootstrap_fits(fit: NoiseFit, allan: AllanVariance, edf, model_error: float, n_boot: int, rng) -> np.ndarray:
    """(n_boot, p) coefficients of ``fit``'s terms refitted to correlated draws of its Allan variances.

    Draws: a Gaussian copula with the correlation of :func:`log_avar_covariance` and Gamma
    marginals ``A_j χ²_ν/ν`` with ``ν = 2 / var(ln Â_j)``; refitted with the fit's weights ``edf``.
    """


    taus, fs = allan.taus, allan.fs
    a = fit.avar(taus, fs)
    cov = log_avar_covariance(allan, fit, model_error)
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    chol = np.linalg.cholesky(corr + 1e-10 * np.eye(len(sd)))
    u = ndtr(rng.standard_normal((n_boot, len(sd))) @ chol.T)
    nu = 2.0 / sd**2
    draws = a * dist.gamma_ppf(np.clip(u, 1e-300, 1 - 1e-16), nu / 2.0, 2.0 / nu)
    refits = fit_avar_batch(taus, draws, edf, fit.term_ids, fs)
    return np.sqrt(np.maximum(np.array([f.c for f in refits]), 0.0))


def octave_correlations(rng, term: str, n: int = 2**16, reps: int = 1000, batch: int = 100) -> np.ndarray:
    """Measure a term's :attr:`~accelcal.noise.terms.NoiseTerm.octave_correlation`: the mean
    correlation of ``ln Â`` 1…6 octaves apart."""

    m = 2 ** np.arange(13)
    la = np.hstack([np.log(allan_variance(simulate_noise(rng, n, 1.0, {term: 1.0}, size=batch), 1.0, m=m).avar)
                    for _ in range(reps // batch)])
    c = np.corrcoef(la)
    return np.array([np.mean(np.diag(c, d)[2:12 - d]) for d in range(1, 7)])


__all__ = ["EDF_MIXES", "NoiseFit", "bootstrap_fits", "fit_avar", "fit_avar_batch", "fit_avar_model_error",
           "gamma_deviance", "log_avar_covariance", "model_edf", "octave_correlations"]
