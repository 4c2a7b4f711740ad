"""Compiled kernels of the stochastic layer's bootstrap (numba, the optional ``fast`` extra).

The stochastic layer refits thousands of small Allan-variance models per test step (one
per bootstrap replicate and, for the sinusoid, per frequency of its grid) and computes
the Allan variance of every replicate.  In numpy each small problem pays the overhead of
dozens of array calls; these kernels run the same algorithms in one compiled loop:

* :func:`irls_gamma` — :func:`accelcal.noise.allan_fit._irls` (Fisher scoring of
  the Gamma likelihood, non-negative least squares by enumerating the supports, step
  halving), problem by problem;
* :func:`allan_sums` — the sums of squared second differences of the running sums that
  :func:`accelcal.noise.allan.allan_variance` accumulates (the running sums formed here
  too, one column at a time);
* :func:`ar1` — the Gauss–Markov recursion of the noise simulator (``lfilter``, bit for bit).

Same algorithms, same arithmetic up to the order of floating-point sums (results agree
to ~1e-12 relative; the tests compare them).  Imported only through
:func:`accelcal.kernels.compiled` (it imports numba), so ``ACCELCAL_KERNELS`` selects it
as it does every other kernel; without numba the callers use their numpy versions.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ..kernels import jit


def _nnls_small(A, b, subsets, sizes):
    """Best non-negative least-squares solution over the given supports (rows of ``subsets``,
    the first ``sizes[j]`` entries used): ``A`` (k, p), ``b`` (k,).

    The Gram matrix and ``Aᵀb`` are formed once; each support solves its sub-system by
    Cholesky and scores ``|b − A x|² = bᵀb − 2 xᵀAᵀb + xᵀ(AᵀA)x``."""
    k, p = A.shape
    gram = np.empty((p, p))
    rhs = np.empty(p)
    bb = 0.0
    for i in range(k):
        bb += b[i] * b[i]
    for a in range(p):
        acc = 0.0
        for i in range(k):
            acc += A[i, a] * b[i]
        rhs[a] = acc
        for c in range(a, p):
            acc = 0.0
            for i in range(k):
                acc += A[i, a] * A[i, c]
            gram[a, c] = acc
            gram[c, a] = acc
    best_x = np.zeros(p)
    best = bb
    L = np.empty((p, p))
    z = np.empty(p)
    xs = np.empty(p)
    for j in range(subsets.shape[0]):
        s = sizes[j]
        idx = subsets[j]
        ok = True
        for a in range(s):  # Cholesky of gram[idx, idx] + 1e-12 I
            for c in range(a + 1):
                acc = gram[idx[a], idx[c]] + (1e-12 if a == c else 0.0)
                for e in range(c):
                    acc -= L[a, e] * L[c, e]
                if a == c:
                    if not acc > 0:
                        ok = False
                        break
                    L[a, a] = np.sqrt(acc)
                else:
                    L[a, c] = acc / L[c, c]
            if not ok:
                break
        if not ok:
            continue
        for a in range(s):
            acc = rhs[idx[a]]
            for e in range(a):
                acc -= L[a, e] * z[e]
            z[a] = acc / L[a, a]
        for a in range(s - 1, -1, -1):
            acc = z[a]
            for e in range(a + 1, s):
                acc -= L[e, a] * xs[e]
            xs[a] = acc / L[a, a]
            if not xs[a] >= 0:
                ok = False
        if not ok:
            continue
        obj = bb
        for a in range(s):
            obj -= 2.0 * xs[a] * rhs[idx[a]]
            for c in range(s):
                obj += xs[a] * gram[idx[a], idx[c]] * xs[c]
        if obj < best:
            best = obj
            for a in range(p):
                best_x[a] = 0.0
            for a in range(s):
                best_x[idx[a]] = xs[a]
    return best_x


def _deviance(y, m, edf):
    d = 0.0
    for i in range(y.shape[0]):
        r = y[i] / m[i]
        d += edf[i] * (r - 1.0 - np.log(r))
    return d


def _floored_model(H, c, floor, out):
    """``out = max(H c, floor)`` row by row: the model Allan variances of coefficients ``c``."""
    k, p = H.shape
    for i in range(k):
        acc = 0.0
        for a in range(p):
            acc += H[i, a] * c[a]
        out[i] = max(acc, floor)


def _irls_one(H, y, edf, subsets, sizes, max_iter, tol):
    k, p = H.shape
    ymax = y[0]
    for i in range(k):
        if y[i] > ymax:
            ymax = y[i]
    floor = 1e-12 * ymax
    c = np.zeros(p)
    model = y.copy()
    dev = np.inf
    A = np.empty((k, p))
    bw = np.empty(k)
    m_new = np.empty(k)
    for _ in range(max_iter):
        for i in range(k):
            w = np.sqrt(edf[i]) / model[i]
            bw[i] = y[i] * w
            for a in range(p):
                A[i, a] = H[i, a] * w
        scale = np.empty(p)
        for a in range(p):
            acc = 0.0
            for i in range(k):
                acc += A[i, a] * A[i, a]
            scale[a] = np.sqrt(acc) if acc > 0 else 1.0
            for i in range(k):
                A[i, a] /= scale[a]
        c_new = _nnls_small(A, bw, subsets, sizes) / scale
        _floored_model(H, c_new, floor, m_new)
        d_new = _deviance(y, m_new, edf)
        d_old = dev
        for _h in range(30):  # step halving towards the previous (feasible) c
            if not d_new > d_old:
                break
            for a in range(p):
                c_new[a] = 0.5 * (c_new[a] + c[a])
            _floored_model(H, c_new, floor, m_new)
            d_new = _deviance(y, m_new, edf)
        if d_new <= d_old:
            c[:] = c_new
            model[:] = m_new
            dev = d_new
        else:
            d_new = d_old
        if abs(d_old - d_new) <= tol * (1.0 + abs(d_new)):
            break
    return c, dev


def _irls_batch(H, y, edf, subsets, sizes, max_iter, tol):
    G, k, p = H.shape
    c = np.zeros((G, p))
    dev = np.empty(G)
    for g in range(G):
        cg, dg = _irls_one(H[g], y[g], edf, subsets, sizes, max_iter, tol)
        c[g] = cg
        dev[g] = dg
    return c, dev


def _allan_sums(s, mean, m):
    """``Σ_i (c[i+2m] − 2 c[i+m] + c[i])²`` per averaging factor and column, ``c`` the running
    sums of the centred data (``c[0] = 0``, ``c[i+1] = c[i] + (s[i] − mean)``): ``s`` (n, d).

    Per column, the running sums are formed in one contiguous buffer (what numpy's
    ``cumsum(s - mean)`` gives, bit for bit, without its temporaries), then the factors are
    taken four at a time in one pass over it, each sum in its own accumulator, so that the
    additions of four factors overlap instead of waiting for each other (and, for octaves,
    ``c[i+2m]`` of one factor is ``c[i+m]`` of the next).  Every sum still adds its terms in
    the order of ``i``: the same bits as one loop per factor.
    """
    n, d = s.shape
    M = m.shape[0]
    out = np.zeros((M, d))
    x = np.empty(n + 1)
    for col in range(d):
        acc = 0.0
        x[0] = 0.0
        mu = mean[col]
        for i in range(n):
            acc += s[i, col] - mu
            x[i + 1] = acc
        for j in range(0, M, 4):
            k = min(4, M - j)
            four = _sums4(x, m[j], m[j + 1] if k > 1 else 0, m[j + 2] if k > 2 else 0, m[j + 3] if k > 3 else 0, k)
            for a in range(k):
                out[j + a, col] = four[a]
    return out


def _sums4(x, m0, m1, m2, m3, k):
    """The sums of :func:`_allan_sums` for up to four factors (``k`` of them) of one column."""
    n1 = x.shape[0]
    ms = (m0, m1, m2, m3)
    lim = np.zeros(4, dtype=np.int64)  # last i (exclusive) with a term, per factor; 0 for unused slots
    for a in range(k):
        lim[a] = max(n1 - 2 * ms[a], 0)
    s0 = s1 = s2 = s3 = 0.0
    common = lim[0]
    for a in range(1, k):
        common = min(common, lim[a])
    if k == 4:
        for i in range(common):  # every factor has a term at i
            v0 = x[i + 2 * m0] - 2.0 * x[i + m0] + x[i]
            v1 = x[i + 2 * m1] - 2.0 * x[i + m1] + x[i]
            v2 = x[i + 2 * m2] - 2.0 * x[i + m2] + x[i]
            v3 = x[i + 2 * m3] - 2.0 * x[i + m3] + x[i]
            s0 += v0 * v0
            s1 += v1 * v1
            s2 += v2 * v2
            s3 += v3 * v3
    else:  # the last group of fewer: each factor alone
        common = 0
    for i in range(common, lim[0]):  # the tails, factor by factor, still in the order of i
        v0 = x[i + 2 * m0] - 2.0 * x[i + m0] + x[i]
        s0 += v0 * v0
    for i in range(common, lim[1]):
        v1 = x[i + 2 * m1] - 2.0 * x[i + m1] + x[i]
        s1 += v1 * v1
    for i in range(common, lim[2]):
        v2 = x[i + 2 * m2] - 2.0 * x[i + m2] + x[i]
        s2 += v2 * v2
    for i in range(common, lim[3]):
        v3 = x[i + 2 * m3] - 2.0 * x[i + m3] + x[i]
        s3 += v3 * v3
    return s0, s1, s2, s3


def _ar1(e, rho):
    """``y[t] = e[t] + rho·y[t−1]`` down each column of ``e`` (n, d), from ``y[−1] = 0``."""
    n, d = e.shape
    y = np.empty((n, d))
    prev = np.zeros(d)
    for t in range(n):
        for col in range(d):
            prev[col] = e[t, col] + rho * prev[col]
            y[t, col] = prev[col]
    return y


# The Python error model: these kernels never divide by zero on valid input, and the
# numpy versions raise where they would.
_jit = jit(error_model="python")
_nnls_small = _jit(_nnls_small)
_deviance = _jit(_deviance)
_floored_model = _jit(_floored_model)
_irls_one = _jit(_irls_one)
_irls_batch = _jit(_irls_batch)
_sums4 = _jit(_sums4)
_allan_sums = _jit(_allan_sums)
_ar1 = _jit(_ar1)


def supports(p: int) -> tuple[np.ndarray, np.ndarray]:
    """Every non-empty support of ``p`` columns, in the order the numpy solver tries them
    (by size, then lexicographic): rows padded with -1, and their sizes."""

    rows = [idx for s in range(1, p + 1) for idx in combinations(range(p), s)]
    out = np.full((len(rows), p), -1, dtype=np.int64)
    for j, idx in enumerate(rows):
        out[j, : len(idx)] = idx
    return out, np.array([len(r) for r in rows], dtype=np.int64)


def irls_gamma(H: np.ndarray, y: np.ndarray, edf: np.ndarray, max_iter: int = 200, tol: float = 1e-10):
    """Compiled :func:`accelcal.noise.allan_fit._irls`: ``H`` (G, k, p), ``y`` (G, k)."""
    subsets, sizes = supports(H.shape[2])
    return _irls_batch(np.ascontiguousarray(H, dtype=np.float64), np.ascontiguousarray(y, dtype=np.float64),
                       np.ascontiguousarray(edf, dtype=np.float64), subsets, sizes, int(max_iter), float(tol))


def allan_sums(s: np.ndarray, mean: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Compiled sums of squared second differences of the running sums of ``s − mean`` (:func:`_allan_sums`)."""
    return _allan_sums(np.ascontiguousarray(s, dtype=np.float64), np.ascontiguousarray(mean, dtype=np.float64),
                       np.ascontiguousarray(m, dtype=np.int64))


def ar1(e: np.ndarray, rho: float) -> np.ndarray:
    """Compiled ``scipy.signal.lfilter([1], [1, -rho], e, axis=0)`` of a 2-D ``e``: the same
    operations in the same order (``y = 1·e + (0·e' + rho·y')``, which is ``e + rho·y'``
    exactly), so the same bits; scipy.signal costs ~1 s of CPU to import."""
    return _ar1(np.ascontiguousarray(e, dtype=np.float64), float(rho))


__all__ = ["allan_sums", "ar1", "irls_gamma", "supports"]
