"""Compiled kernels of the stochastic layer's bootstrap (numba, the optional ``fast`` extra).

The stochastic layer refits thousands of small Allan-variance models per test step (one
per bootstrap replicate and, for the sinusoid, per frequency of its grid) and computes
the Allan variance of every replicate.  In numpy each small problem pays the overhead of
dozens of array calls; these kernels run the same algorithms in one compiled loop:

* :func:`irls_gamma` — :func:`accelcal.noise.allan_fit._irls` (Fisher scoring of
  the Gamma likelihood, non-negative least squares by Lawson and Hanson's active set, step
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

import numpy as np

from ..kernels import jit


def _gram(A, b, gram, rhs):
    """``gram = AᵀA + 1e-12 I`` and ``rhs = Aᵀb`` (the ridge keeps a column of zeros solvable)."""
    k, p = A.shape
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
        gram[a, a] += 1e-12


def _solve_passive(gram, rhs, passive, L, z, out):
    """``out`` = the least-squares solution on the passive columns (Cholesky of their Gram
    sub-matrix), 0 elsewhere; False if that sub-matrix is not positive definite."""
    p = rhs.shape[0]
    idx = np.empty(p, np.int64)
    s = 0
    for a in range(p):
        out[a] = 0.0
        if passive[a]:
            idx[s] = a
            s += 1
    for a in range(s):
        for c in range(a + 1):
            acc = gram[idx[a], idx[c]]
            for e in range(c):
                acc -= L[a, e] * L[c, e]
            if a == c:
                if not acc > 0:
                    return False
                L[a, a] = np.sqrt(acc)
            else:
                L[a, c] = acc / L[c, c]
    for a in range(s):
        acc = rhs[idx[a]]
        for e in range(a):
            acc -= L[a, e] * z[e]
        z[a] = acc / L[a, a]
    for a in range(s - 1, -1, -1):
        acc = z[a]
        for e in range(a + 1, s):
            acc -= L[e, a] * out[idx[e]]
        out[idx[a]] = acc / L[a, a]
    return True


def _nnls_small(A, b):
    """Non-negative least squares ``min |A x − b|, x ≥ 0`` of one small problem, ``A`` (k, p), by
    Lawson and Hanson's active-set method (Solving Least Squares Problems, 1974, ch. 23; as
    ``scipy.optimize.nnls``) on the Gram matrix: columns enter the passive set while the
    gradient ``Aᵀ(b − A x)`` is positive on them, and a step that would make a passive
    coefficient negative stops at the boundary and frees it.  A few solves instead of the
    2^p − 1 of enumerating every support (the same optimum: the problem is strictly convex)."""
    p = A.shape[1]
    gram = np.empty((p, p))
    rhs = np.empty(p)
    _gram(A, b, gram, rhs)
    x = np.zeros(p)
    s = np.zeros(p)
    L = np.empty((p, p))
    z = np.empty(p)
    passive = np.zeros(p, np.bool_)
    for _ in range(4 * p):
        best, j = _NNLS_TOL, -1
        for a in range(p):  # the most promising column outside the passive set
            if not passive[a]:
                w = rhs[a]
                for c in range(p):
                    w -= gram[a, c] * x[c]
                if w > best:
                    best, j = w, a
        if j < 0:
            break
        passive[j] = True
        for _inner in range(p + 1):
            if not _solve_passive(gram, rhs, passive, L, z, s):
                passive[j] = False
                return x
            alpha, block = 2.0, -1
            for a in range(p):
                if passive[a] and s[a] <= 0.0:
                    step = x[a] / (x[a] - s[a])
                    if step < alpha:
                        alpha, block = step, a
            if block < 0:  # every passive coefficient positive: take the solution
                for a in range(p):
                    x[a] = s[a]
                break
            for a in range(p):  # stop at the boundary, free what reached it
                x[a] += alpha * (s[a] - x[a])
                if passive[a] and (a == block or x[a] <= 0.0):
                    passive[a] = False
                    x[a] = 0.0
    return x


#: Gradient below which a column does not enter the passive set (the columns have unit norm).
_NNLS_TOL = 1e-13


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


def _irls_one(H, y, edf, max_iter, tol):
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
        c_new = _nnls_small(A, bw)
        for a in range(p):
            c_new[a] /= scale[a]
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
            for a in range(p):  # element by element: see the end of the module
                c[a] = c_new[a]
            for i in range(k):
                model[i] = m_new[i]
            dev = d_new
        else:
            d_new = d_old
        if abs(d_old - d_new) <= tol * (1.0 + abs(d_new)):
            break
    return c, dev


def _irls_batch(H, y, edf, max_iter, tol):
    G, k, p = H.shape
    c = np.zeros((G, p))
    dev = np.empty(G)
    for g in range(G):
        cg, dg = _irls_one(H[g], y[g], edf, max_iter, tol)
        for a in range(p):  # element by element: see the end of the module
            c[g, a] = cg[a]
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
# Compile time (a fresh clone compiles every kernel once; tools/bench_kernel_compile.py):
# _nnls_small and _irls_one have one caller each and are inlined by numba (a jitted callee
# is a library of its own whose code every caller's library links, optimises and emits
# again); arrays are copied element by element (numba's array-to-array assignment brings
# its shape-mismatch message, whose string formatting is seconds to compile) and divided
# in loops (an array expression compiles a loop of its own); inputs arrive read-only
# (:func:`_read_only`).  The same operations in the same order: the same bits.
_jit = jit(error_model="python")
_gram = _jit(_gram)
_solve_passive = _jit(_solve_passive)
_nnls_small = jit(_nnls_small, error_model="python", inline="always")
_deviance = _jit(_deviance)
_floored_model = _jit(_floored_model)
_irls_one = jit(_irls_one, error_model="python", inline="always")
_irls_batch = _jit(_irls_batch)
_sums4 = _jit(_sums4)
_allan_sums = _jit(_allan_sums)
_ar1 = _jit(_ar1)


def _read_only(a, dtype=np.float64) -> np.ndarray:
    """``a`` as a C-contiguous array of ``dtype``, seen read-only (a view: no copy).

    numba compiles a kernel once per argument type, and a read-only array is a type of its
    own: callers pass both (a frozen recording, a broadcast design), which compiled every
    kernel on the path twice.  The kernels only read their inputs, so they take them read-only."""
    a = np.ascontiguousarray(a, dtype=dtype)
    if a.flags.writeable:
        a = a.view()
        a.flags.writeable = False
    return a


def irls_gamma(H: np.ndarray, y: np.ndarray, edf: np.ndarray, max_iter: int = 200, tol: float = 1e-10):
    """Compiled :func:`accelcal.noise.allan_fit._irls`: ``H`` (G, k, p), ``y`` (G, k)."""
    return _irls_batch(_read_only(H), _read_only(y), _read_only(edf), int(max_iter), float(tol))


def allan_sums(s: np.ndarray, mean: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Compiled sums of squared second differences of the running sums of ``s − mean`` (:func:`_allan_sums`)."""
    return _allan_sums(_read_only(s), _read_only(mean), _read_only(m, np.int64))


def ar1(e: np.ndarray, rho: float) -> np.ndarray:
    """Compiled ``scipy.signal.lfilter([1], [1, -rho], e, axis=0)`` of a 2-D ``e``: the same
    operations in the same order (``y = 1·e + (0·e' + rho·y')``, which is ``e + rho·y'``
    exactly), so the same bits; scipy.signal costs ~1 s of CPU to import."""
    return _ar1(_read_only(e), float(rho))


__all__ = ["allan_sums", "ar1", "irls_gamma"]
