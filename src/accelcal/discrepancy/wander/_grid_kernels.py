"""Compiled kernel of the wander null's likelihood grid (numba, the optional ``fast`` extra).

Every likelihood-ratio test of the wander loop minimises ``−2ℓ`` over the grid of
``(τ, q)`` for each data set: the observed one and every bootstrap replicate, under the
current model and each candidate (:func:`accelcal.discrepancy.wander.gls.grid_ml_min`).
In numpy that builds the quadratic forms of every grid point as arrays (models × τ ×
replicates × q) and then reduces them; here one loop forms each quadratic form and keeps
the running minima, without the arrays.  Same algorithm and arithmetic as the numpy
path (:func:`accelcal.discrepancy.wander.gls._neg2ll_min`), up to the order of the sum
over the free contrasts (reassociated, so that it runs in SIMD lanes: the numpy path's
matrix product has an order of its own too): the exponentials and logarithms are taken
in numpy, outside.
Imported only through :func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import numpy as np

from ...kernels import jit


def _grid_minima(Yt, w, ex, ld, lo_nu, hi_nu, lo, hi):
    """Per (model, data set): the smallest ``quad · ex`` over the grid points where the white
    scale ``quad/ν`` is inside ``[lo, hi]`` (``lo_nu``, ``hi_nu``: the bounds times ``ν``),
    and the smallest ``quad/lo + ld`` and ``quad/hi + ld`` where it is below / above.

    ``Yt`` (G, T, B, r): rotated free contrasts; ``w`` (G, T, Q, r): the
    weights ``1/(1 + q μ)``; ``ex`` (T, Q): ``exp((ld − min ld)/ν)``; ``ld`` (T, Q): the
    log-determinant of each grid point.  Returns three (G, B) arrays (``inf`` where no grid
    point qualifies)."""
    G, T, B, r = Yt.shape
    Q = w.shape[2]
    prod = np.full((G, B), np.inf)
    low = np.full((G, B), np.inf)
    high = np.full((G, B), np.inf)
    for g in range(G):
        for t in range(T):
            for b in range(B):
                y = Yt[g, t, b]
                pm, lm, hm = prod[g, b], low[g, b], high[g, b]
                for k in range(Q):
                    wk = w[g, t, k]
                    quad = 0.0
                    for j in range(r):
                        quad += y[j] * y[j] * wk[j]
                    if quad < 1e-300:
                        quad = 1e-300
                    if quad < lo_nu:
                        v = quad / lo + ld[t, k]
                        if v < lm:
                            lm = v
                    elif quad > hi_nu:
                        v = quad / hi + ld[t, k]
                        if v < hm:
                            hm = v
                    else:
                        v = quad * ex[t, k]
                        if v < pm:
                            pm = v
                prod[g, b], low[g, b], high[g, b] = pm, lm, hm
    return prod, low, high


_grid_minima = jit(_grid_minima, fastmath={"reassoc", "contract"})


def grid_minima(Yt, w, ex, ld, nu: float, lo: float, hi: float):
    """:func:`_grid_minima` on contiguous float arrays (``nu``: the degrees of freedom ``ν``)."""
    c = np.ascontiguousarray
    return _grid_minima(c(Yt, dtype=np.float64), c(w, dtype=np.float64), c(ex, dtype=np.float64),
                        c(ld, dtype=np.float64), float(lo * nu), float(hi * nu), float(lo), float(hi))


__all__ = ["grid_minima"]
