"""The statistics of the discrepancy loop: the gap, the MDE's non-centrality, Holm.

Gap (:func:`gap`): the RMS of the weighted pose residuals, ``sqrt(χ²/n)``, with the same
fixed weights before (base model) and after (base + named effects); noise alone predicts
``sqrt((n - q)/n)``.  In-sample it can only shrink when parameters are added, so the
leave-one-pose-out gap ``sqrt(PRESS/n)`` is reported next to it.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .. import distributions as dist

def gap(weighted_residuals) -> float:
    """The gap between model and data: ``sqrt(mean((r_i/σ_i)²))`` (1 = noise level)."""
    w = np.asarray(weighted_residuals, float)
    w = w[np.isfinite(w)]
    return float(np.sqrt(np.mean(w * w))) if w.size else float("nan")


@lru_cache(maxsize=4096)
def critical_noncentrality(k: int, dof: int, level: float, power: float) -> float:
    """``λ*`` with ``P(F(k, dof; λ*) > F_{1-level}(k, dof)) = power`` (inf if ``dof < 1``)."""
    if dof < 1:
        return float("inf")
    fcrit = dist.f_isf(level, k, dof)

    def f(lam):
        return dist.ncf_sf(fcrit, k, dof, lam) - power

    hi = 1.0
    while f(hi) < 0:
        hi *= 2
        if hi > 1e8:
            return float("inf")
    from scipy.optimize import brentq  # here: scipy.optimize costs 0.2-0.6 s to import

    return float(brentq(f, 0.0, hi, xtol=1e-10, rtol=1e-12))


def holm(p_values, correction: str = "holm") -> np.ndarray:
    """Adjusted p-values (Holm step-down, Bonferroni, or none); NaN entries stay NaN."""
    p = np.asarray(p_values, float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    m = ok.size
    if m == 0:
        return out
    if correction == "none":
        out[ok] = p[ok]
    elif correction == "bonferroni":
        out[ok] = np.minimum(1.0, m * p[ok])
    else:
        order = ok[np.argsort(p[ok], kind="stable")]
        running = 0.0
        for j, i in enumerate(order):
            running = max(running, min(1.0, (m - j) * p[i]))
            out[i] = running
    return out


__all__ = ["critical_noncentrality", "gap", "holm"]
