"""The outlier family of a round: the largest studentised residual among the poses, and its null.

A pose is an outlier when its residual is shifted: the mean-shift model adds a free shift
to that pose alone.  At the round's fitted noise ``s (I + q K_τ)`` (the REML wander of the
current model) the GLS residuals of the poses are ``P r`` (``P`` the residual projector,
:func:`~.gls.gls_projector`), and the evidence for a shift of pose ``i`` is its studentised
residual ``t_i = (P r)_i / sqrt(P_ii ŝ)``.  The family's statistic is ``T = max_i |t_i|``:
the multiplicity (``n`` poses) and the correlation between the poses that the wander
implies are in its null distribution, not in a correction.

The null, exactly.  In the ``r = m − p`` contrasts the current model leaves free, rotated
to diagonalise the wander (:class:`~.gls.Basis`) and scaled by ``1/sqrt(1 + q μ_j)``, the
residuals are ``z ~ N(0, s I_r)`` and ``(P r)_i = b_iᵀ z`` for known vectors ``b_i``.  With
the white scale estimated from the same residuals (``ŝ = |z|²/r``, internal
studentisation) ``t_i = sqrt(r) b̂_iᵀ z/|z|`` (``b̂_i = b_i/|b_i|``): ``T`` depends on
the direction of ``z`` only, uniform on the sphere whatever ``s``.  Its null distribution
is therefore a function of the ``b̂_i`` alone, and :func:`max_null_pvalue` draws it by
Monte Carlo with as many draws as the decision needs (thousands, not the bootstrap's
hundreds: a p-value at the floor of 199 replicates, 0.005, is below Holm's first level
over six tests but says nothing about how far below).  With a known white variance (the
benchmark's oracle) ``t_i = b̂_iᵀ z/sqrt(s)`` and the same routine draws ``z`` without
normalising it.

The wander is held at its estimate under the current model (a plug-in, as in the
bootstrap).  The mean-shift likelihood ratio with the wander re-estimated
(:meth:`~.gls.Surface.shift_ml_min`) is still computed for the chosen pose: it ranks the
outlier against the candidate effects by ΔBIC.
"""

from __future__ import annotations

import numpy as np

from ... import distributions as dist
from .gls import Basis
from .problem import Problem

#: Monte Carlo draws of the null: a first batch (enough to stop a clearly insignificant
#: test: 500 draws put a p-value of 0.1 at 0.07-0.14, 99.9 %), then batches of
#: :data:`DRAW_BATCH`, at most :data:`MAX_DRAWS` in all.
FIRST_BATCH = 500
DRAW_BATCH = 2000
MAX_DRAWS = 40000
#: The draws stop once the 99.9 % Clopper–Pearson interval of the p-value lies wholly above
#: α (the test cannot pass) or wholly below α over the round's family (it passes at any
#: Holm level).
DECISION_LEVEL = 0.999


def directions(prob: Problem, bas: Basis, t: int, q: float) -> tuple[np.ndarray, np.ndarray]:
    """``(b̂, w)``: the unit vectors ``b̂_i`` (n, r) of the module docstring at the wander
    ``(t, q)`` and the scaling ``w = 1/sqrt(1 + q μ)`` (r,) that takes the rotated free
    contrasts ``Uᵀ Kᵀ y`` to ``z``; rows of poses the model fixes (``P_ii ≈ 0``) are zero."""
    w = 1.0 / np.sqrt(1.0 + q * bas.mu[t])
    B = (prob.L @ bas.K @ bas.U[t]) * w[None, :]
    norm = np.linalg.norm(B, axis=1, keepdims=True)
    ok = norm > 1e-9 * max(float(norm.max()), 1e-300)
    return np.where(ok, B / np.where(ok, norm, 1.0), 0.0), w


def studentised_max(prob: Problem, bas: Basis, t: int, q: float, y=None) -> tuple[np.ndarray, float]:
    """Internally studentised residuals ``t_i`` (n,) of data ``y`` (default the data) and ``max |t_i|``."""
    bhat, w = directions(prob, bas, t, q)
    y = prob.y if y is None else np.asarray(y, float)
    z = (y @ bas.K @ bas.U[t]) * w
    r = z.shape[-1]
    tt = np.sqrt(r) * (bhat @ z) / max(float(np.linalg.norm(z)), 1e-300)
    return tt, float(np.max(np.abs(tt)))


def max_null_pvalue(bhat: np.ndarray, statistic: float, rng: np.random.Generator, *, alpha: float, family: int,
                    studentised: bool = True, max_draws: int = MAX_DRAWS, stop_early: bool = True) -> tuple[float, int]:
    """Monte Carlo p-value of ``max_i |t_i| >= statistic`` under the null (module docstring).

    ``studentised``: ``t_i = sqrt(r) b̂_iᵀ u`` with ``u`` uniform on the unit sphere of
    ``R^r``; otherwise ``t_i = b̂_iᵀ z``, ``z ~ N(0, I_r)``.  Draws in batches
    (:data:`FIRST_BATCH`, then :data:`DRAW_BATCH`) until the decision at level ``α`` over a
    Holm family of ``family`` tests is resolved (:data:`DECISION_LEVEL`; ``stop_early=False``:
    never) or ``max_draws`` are used.

    Returns
    -------
    p : float
        ``(1 + #{T* ≥ T})/(N + 1)`` (a valid p-value for any ``N``).
    draws : int
        ``N``.
    """
    r = bhat.shape[1]
    count, n = 0, 0
    tol = 1e-9 * max(1.0, abs(statistic))
    edge = (1.0 - DECISION_LEVEL) / 2
    while n < max_draws:
        z = rng.standard_normal((min(DRAW_BATCH if n else FIRST_BATCH, max_draws - n), r))
        if studentised:
            z *= np.sqrt(r) / np.linalg.norm(z, axis=1, keepdims=True)
        stats = z @ bhat.T
        np.abs(stats, out=stats)  # in place: no second (draws, n) array per batch
        count += int(np.count_nonzero(stats.max(axis=1) >= statistic - tol))
        n += z.shape[0]
        lo = dist.beta_ppf(edge, count, n - count + 1) if count else 0.0
        hi = dist.beta_ppf(1 - edge, count + 1, n - count) if count < n else 1.0
        if stop_early and (lo > alpha or hi < alpha / max(family, 1)):
            break
    return (1 + count) / (n + 1), n


__all__ = ["DECISION_LEVEL", "DRAW_BATCH", "FIRST_BATCH", "MAX_DRAWS", "directions", "max_null_pvalue", "studentised_max"]
