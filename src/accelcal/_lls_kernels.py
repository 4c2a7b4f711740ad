"""Compiled kernels of the closed forms (full LLS, bias-only LLS, ALS), single and batched.

The same algorithms as the numpy routes of :mod:`accelcal.lls` and :mod:`accelcal.als`
(see their docstrings for the mathematics and the certification of the fast route),
as scalar loops compiled by numba (:mod:`accelcal.kernels`).  Every kernel returns a
status per problem and leaves the decisions it cannot certify to the reference
implementation, so that errors and doubtful cases take exactly the reference's path:

* ``OK`` (0): the estimate is in the output arrays;
* ``REFERENCE`` (1): hand the problem to the reference (non-finite or all-zero poses,
  geometry not clearly three-dimensional, Gram-matrix route not certified);
* ``NO_ELLIPSOID`` (2): the estimate is no ellipsoid (Ŝ not positive definite, λ <= 0);
* ``NON_FINITE`` (3): NaN or infinite poses (batched kernels);
* ``UNSCREENED`` (5, full LLS, inside the module only): as ``REFERENCE``, and the pose
  geometry was not shown clearly three-dimensional: the batches report which trials
  their moment screen passed (``clear``), so that only the others get the reference
  geometry check (:func:`accelcal.validation.degenerate_trials`).

Imported only through :func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import math

import numpy as np

from .kernels import jit

OK, REFERENCE, NO_ELLIPSOID, NON_FINITE = 0, 1, 2, 3
UNSCREENED = 5

# Constants of the fast route, as in accelcal.lls (the tolerances a caller may change,
# MIN_GAP and EIGVEC_TOL, are arguments).
_NULLSPACE_RATIO2 = 9.0
_EPS = np.finfo(np.float64).eps
_MATVEC_ROUNDING = 10 * _EPS
_CANCELLATION = 4 * math.sqrt(_EPS)
_SHIFT = 1e-13
_ROUNDS = 3
_COPLANAR_TOL = 1e-3
_MOMENT_SHIFT = 2.0 * _COPLANAR_TOL  # _MOMENT_MARGIN * COPLANAR_TOL of accelcal.validation
_MIN_SPREAD = 1e-8


# ----------------------------------------------------------------------------- helpers
@jit
def _ldl(A, L, dinv, D, W, m):
    """``A = L D Lᵀ`` of the leading ``m x m`` block of ``A`` (unit lower ``L``, strictly
    lower part written; ``dinv`` = 1/D); False if that block is not positive definite
    (a pivot <= 0 or NaN), which is exactly when its Cholesky factorisation fails.
    No square roots and one division per column: this runs for every Monte Carlo trial.
    ``D``, ``W``: workspace (10,)."""
    for j in range(m):
        d = A[j, j]
        for p in range(j):
            w = L[j, p] * D[p]
            W[p] = w
            d -= L[j, p] * w
        if not d > 0.0:
            return False
        D[j] = d
        inv = 1.0 / d
        dinv[j] = inv
        for i in range(j + 1, m):
            t = A[i, j]
            for p in range(j):
                t -= L[i, p] * W[p]
            L[i, j] = t * inv
    return True


@jit
def _ldl_solve(L, dinv, x, m):
    """``x <- (L D Lᵀ)⁻¹ x`` in place."""
    for i in range(m):
        s = x[i]
        for p in range(i):
            s -= L[i, p] * x[p]
        x[i] = s
    for i in range(m):
        x[i] *= dinv[i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for p in range(i + 1, m):
            s -= L[p, i] * x[p]
        x[i] = s


@jit
def _normal_matrix(z, k, N):
    """``N = XᵀX`` (10x10, upper and lower) of the design of eq. (3) of the poses ``z / k``.

    Every entry of N is a coefficient (a power of two) times a moment ``Σ x^a y^b w^c``
    of degree <= 4 of the scaled poses: the 34 moments are summed (34 products per pose
    instead of the 55 of ``XᵀX``) and N is assembled from them."""
    r = 1.0 / k
    s_x = s_y = s_w = 0.0
    s_xx = s_xy = s_xw = s_yy = s_yw = s_ww = 0.0
    s_xxx = s_xxy = s_xxw = s_xyy = s_xyw = s_xww = s_yyy = s_yyw = s_yww = s_www = 0.0
    s_xxxx = s_xxxy = s_xxxw = s_xxyy = s_xxyw = s_xxww = s_xyyy = s_xyyw = s_xyww = s_xwww = 0.0
    s_yyyy = s_yyyw = s_yyww = s_ywww = s_wwww = 0.0
    for p in range(z.shape[0]):
        x, y, w = z[p, 0] * r, z[p, 1] * r, z[p, 2] * r
        xx, xy, xw, yy, yw, ww = x * x, x * y, x * w, y * y, y * w, w * w
        s_x += x
        s_y += y
        s_w += w
        s_xx += xx
        s_xy += xy
        s_xw += xw
        s_yy += yy
        s_yw += yw
        s_ww += ww
        s_xxx += xx * x
        s_xxy += xx * y
        s_xxw += xx * w
        s_xyy += xy * y
        s_xyw += xy * w
        s_xww += xw * w
        s_yyy += yy * y
        s_yyw += yy * w
        s_yww += yw * w
        s_www += ww * w
        s_xxxx += xx * xx
        s_xxxy += xx * xy
        s_xxxw += xx * xw
        s_xxyy += xx * yy
        s_xxyw += xx * yw
        s_xxww += xx * ww
        s_xyyy += xy * yy
        s_xyyw += xy * yw
        s_xyww += xy * ww
        s_xwww += xw * ww
        s_yyyy += yy * yy
        s_yyyw += yy * yw
        s_yyww += yy * ww
        s_ywww += yw * ww
        s_wwww += ww * ww
    n = float(z.shape[0])
    N[0, 0] = s_xxxx
    N[0, 1] = s_xxyy
    N[0, 2] = s_xxww
    N[0, 3] = 2.0 * s_xxxy
    N[0, 4] = 2.0 * s_xxxw
    N[0, 5] = 2.0 * s_xxyw
    N[0, 6] = -2.0 * s_xxx
    N[0, 7] = -2.0 * s_xxy
    N[0, 8] = -2.0 * s_xxw
    N[0, 9] = s_xx
    N[1, 1] = s_yyyy
    N[1, 2] = s_yyww
    N[1, 3] = 2.0 * s_xyyy
    N[1, 4] = 2.0 * s_xyyw
    N[1, 5] = 2.0 * s_yyyw
    N[1, 6] = -2.0 * s_xyy
    N[1, 7] = -2.0 * s_yyy
    N[1, 8] = -2.0 * s_yyw
    N[1, 9] = s_yy
    N[2, 2] = s_wwww
    N[2, 3] = 2.0 * s_xyww
    N[2, 4] = 2.0 * s_xwww
    N[2, 5] = 2.0 * s_ywww
    N[2, 6] = -2.0 * s_xww
    N[2, 7] = -2.0 * s_yww
    N[2, 8] = -2.0 * s_www
    N[2, 9] = s_ww
    N[3, 3] = 4.0 * s_xxyy
    N[3, 4] = 4.0 * s_xxyw
    N[3, 5] = 4.0 * s_xyyw
    N[3, 6] = -4.0 * s_xxy
    N[3, 7] = -4.0 * s_xyy
    N[3, 8] = -4.0 * s_xyw
    N[3, 9] = 2.0 * s_xy
    N[4, 4] = 4.0 * s_xxww
    N[4, 5] = 4.0 * s_xyww
    N[4, 6] = -4.0 * s_xxw
    N[4, 7] = -4.0 * s_xyw
    N[4, 8] = -4.0 * s_xww
    N[4, 9] = 2.0 * s_xw
    N[5, 5] = 4.0 * s_yyww
    N[5, 6] = -4.0 * s_xyw
    N[5, 7] = -4.0 * s_yyw
    N[5, 8] = -4.0 * s_yww
    N[5, 9] = 2.0 * s_yw
    N[6, 6] = 4.0 * s_xx
    N[6, 7] = 4.0 * s_xy
    N[6, 8] = 4.0 * s_xw
    N[6, 9] = -2.0 * s_x
    N[7, 7] = 4.0 * s_yy
    N[7, 8] = 4.0 * s_yw
    N[7, 9] = -2.0 * s_y
    N[8, 8] = 4.0 * s_ww
    N[8, 9] = -2.0 * s_w
    N[9, 9] = n
    for i in range(10):
        for j in range(i):
            N[i, j] = N[j, i]


@jit
def _scatter_is_clearly_3d(a, b, c, d, e, f, sum_sq):
    """:func:`accelcal.validation.scatter_is_clearly_3d` for the scatter
    ``[[a, b, c], [b, d, e], [c, e, f]]``."""
    tr = a + d + f
    if not tr > _MIN_SPREAD * sum_sq:
        return False
    r = 1.0 / tr
    a, b, c, d, e, f = a * r - _MOMENT_SHIFT, b * r, c * r, d * r - _MOMENT_SHIFT, e * r, f * r - _MOMENT_SHIFT
    if not a > 0:
        return False
    ia = 1.0 / a
    d2 = d - b * b * ia
    if not d2 > 0:
        return False
    e2 = e - b * c * ia
    return f - c * c * ia - e2 * e2 / d2 > 0


@jit
def _geometry_from_normal_matrix(N, n):
    """:func:`accelcal.validation.geometry_is_clearly_fine` from row 9 of ``N`` (the
    column sums of X: Σ zs², 2 Σ zx zy, ..., -2 Σ zs, n), as in :func:`accelcal.lls.full_lls`."""
    xx, yy, zz = N[9, 0], N[9, 1], N[9, 2]
    xy, xz, yz = 0.5 * N[9, 3], 0.5 * N[9, 4], 0.5 * N[9, 5]
    sx, sy, sz = -0.5 * N[9, 6], -0.5 * N[9, 7], -0.5 * N[9, 8]
    mx, my, mz = sx / n, sy / n, sz / n
    return _scatter_is_clearly_3d(xx - n * mx * mx, xy - n * mx * my, xz - n * mx * mz, yy - n * my * my,
                                  yz - n * my * mz, zz - n * mz * mz, xx + yy + zz)


@jit
def _null_vector(N, x, L, wk, min_gap, eigvec_tol):
    """Θ̂ (unnormalised, in ``x``) of the full LLS from ``N`` (overwritten) by inverse
    iteration, certified as in :func:`accelcal.lls._null_vector` (there with LAPACK's
    Cholesky, here with LDLᵀ: the same test of positive definiteness).  Returns ``|x|``,
    or -1 when the route cannot certify it.  ``wk``: workspace (30,)."""
    dinv, D, W = wk[:10], wk[10:20], wk[20:30]
    tr = 0.0
    for i in range(10):
        tr += N[i, i]
    delta = 0.0
    if not _ldl(N, L, dinv, D, W, 10):  # N singular to rounding (noise-free poses): N + δI
        delta = _SHIFT * tr
        for i in range(10):
            N[i, i] += delta
        if not _ldl(N, L, dinv, D, W, 10):
            return -1.0
    for i in range(10):
        x[i] = 0.0
    x[0] = x[1] = x[2] = 1.0
    x[9] = -1.0
    _ldl_solve(L, dinv, x, 10)
    for _ in range(_ROUNDS):
        _ldl_solve(L, dinv, x, 10)
        xx = 0.0
        xy = 0.0
        yy = 0.0
        for i in range(10):
            s = 0.0
            for j in range(10):
                s += N[i, j] * x[j]
            xx += x[i] * x[i]
            xy += x[i] * s
            yy += s * s
        rho = xy / xx
        res = math.sqrt(max(yy / xx - rho * rho, 0.0)) + _MATVEC_ROUNDING * tr + _CANCELLATION * abs(rho)
        rho -= delta
        bound = max(_NULLSPACE_RATIO2 * rho, min_gap * tr)
        if res <= eigvec_tol * (bound - rho):
            for i in range(9):
                N[i, i] -= bound + delta
            return math.sqrt(xx) if _ldl(N, L, dinv, D, W, 9) else -1.0
        scale = 1.0 / math.sqrt(xx)
        for i in range(10):
            x[i] *= scale
        _ldl_solve(L, dinv, x, 10)
    return -1.0


@jit
def _theta_to_model(theta, g_scaled, out):
    """Eqs. (4)-(6) as :func:`accelcal.lls._theta_to_model_single`: ``out`` = (b (3),
    M row-major (9), λ) for the Θ given; False if the estimate is no ellipsoid."""
    S11, S22, S33, S12, S13, S23 = theta[0], theta[1], theta[2], theta[3], theta[4], theta[5]
    r1, r2, r3, d = theta[6], theta[7], theta[8], theta[9]
    if S11 + S22 + S33 < 0:
        S11, S22, S33, S12, S13, S23 = -S11, -S22, -S33, -S12, -S13, -S23
        r1, r2, r3, d = -r1, -r2, -r3, -d
    m2 = S11 * S22 - S12 * S12
    det = S11 * (S22 * S33 - S23 * S23) - S12 * (S12 * S33 - S23 * S13) + S13 * (S12 * S23 - S22 * S13)
    if S11 <= 0 or m2 <= 0 or det <= 0:
        return False
    c11, c22, c33 = S22 * S33 - S23 * S23, S11 * S33 - S13 * S13, m2
    c12, c13, c23 = S13 * S23 - S12 * S33, S12 * S23 - S13 * S22, S12 * S13 - S11 * S23
    b1 = (c11 * r1 + c12 * r2 + c13 * r3) / det
    b2 = (c12 * r1 + c22 * r2 + c23 * r3) / det
    b3 = (c13 * r1 + c23 * r2 + c33 * r3) / det
    quad = b1 * r1 + b2 * r2 + b3 * r3 - d
    if not quad > 0:
        return False
    lam = g_scaled * g_scaled / quad
    S11, S22, S33, S12, S13, S23 = lam * S11, lam * S22, lam * S33, lam * S12, lam * S13, lam * S23
    a6 = math.sqrt(S33)
    a5, a4 = S23 / a6, S13 / a6
    a3 = math.sqrt(S22 - a5 * a5)
    a2 = (S12 - a4 * a5) / a3
    a1 = math.sqrt(S11 - a2 * a2 - a4 * a4)
    m11, m22, m33 = 1 / a1, 1 / a3, 1 / a6
    m21 = -a2 * m11 / a3
    m32 = -a5 * m22 / a6
    m31 = -(a4 * m11 + a5 * m21) / a6
    out[0], out[1], out[2] = b1, b2, b3
    out[3], out[4], out[5] = m11, 0.0, 0.0
    out[6], out[7], out[8] = m21, m22, 0.0
    out[9], out[10], out[11] = m31, m32, m33
    out[12] = lam
    return True


@jit
def _sum_squares(z):
    s = 0.0
    for p in range(z.shape[0]):
        s += z[p, 0] * z[p, 0] + z[p, 1] * z[p, 1] + z[p, 2] * z[p, 2]
    return s


@jit
def _all_finite(z):
    for p in range(z.shape[0]):
        for a in range(3):
            if not math.isfinite(z[p, a]):
                return False
    return True


# ----------------------------------------------------------------------------- full LLS
@jit
def _full_lls(z, g, min_gap, eigvec_tol, out, N, L, x, wk):
    """Full LLS of one problem into ``out`` = (b (3), M (9), λ of the unit Θ̂); status
    (UNSCREENED up to the geometry screen, REFERENCE after it)."""
    n = z.shape[0]
    if z.shape[1] != 3 or n < 10:  # the reference raises the error
        return UNSCREENED
    k = math.sqrt(_sum_squares(z) / n)
    if not (math.isfinite(k) and k > 0):
        return UNSCREENED
    _normal_matrix(z, k, N)
    if not _geometry_from_normal_matrix(N, n):
        return UNSCREENED
    norm = _null_vector(N, x, L, wk, min_gap, eigvec_tol)
    if norm < 0:
        return REFERENCE
    if not _theta_to_model(x, g / k, out):
        return NO_ELLIPSOID
    out[0] *= k
    out[1] *= k
    out[2] *= k
    out[12] *= norm
    return OK


@jit
def full_lls(z, g, min_gap, eigvec_tol, bias, M):
    """Full LLS of poses ``z`` (n, 3) into ``bias`` (3,) and ``M`` (3, 3).

    Returns λ (of the unit Θ̂; NaN if g is), or ``-REFERENCE`` / ``-NO_ELLIPSOID`` (one
    float crosses the Python boundary faster than a tuple)."""
    out = np.empty(13)
    s = _full_lls(z, g, min_gap, eigvec_tol, out, np.empty((10, 10)), np.empty((10, 10)), np.empty(10),
                  np.empty(30))
    if s != OK:
        return -float(REFERENCE if s == UNSCREENED else s)
    for i in range(3):
        bias[i] = out[i]
        for j in range(3):
            M[i, j] = out[3 + 3 * i + j]
    return out[12]


@jit
def _full_lls_svd(z, g, out, X, V, theta):
    """Full LLS of one problem from the singular vectors of the scaled design matrix X
    (eq. 3), by one-sided (Hestenes) Jacobi, which computes them to the accuracy of the
    SVD (no XᵀX formed): the batch's fallback where the Gram route cannot certify its
    answer.  Returns REFERENCE where the null space is not clearly one-dimensional (the
    SVD's rank test of :func:`accelcal.lls._full_lls_svd`: any vector of it would be
    an answer, and the reference's choice is LAPACK's), else OK or NO_ELLIPSOID."""
    n = z.shape[0]
    if z.shape[1] != 3 or n < 10:
        return REFERENCE
    k = math.sqrt(_sum_squares(z) / n)
    if not (math.isfinite(k) and k > 0):
        return REFERENCE
    for p in range(n):
        x, y, w = z[p, 0] / k, z[p, 1] / k, z[p, 2] / k
        X[p, 0], X[p, 1], X[p, 2] = x * x, y * y, w * w
        X[p, 3], X[p, 4], X[p, 5] = 2 * x * y, 2 * x * w, 2 * y * w
        X[p, 6], X[p, 7], X[p, 8], X[p, 9] = -2 * x, -2 * y, -2 * w, 1.0
    for i in range(10):
        for j in range(10):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(60):
        rotated = False
        for a in range(9):
            for b in range(a + 1, 10):
                alpha = beta = gamma = 0.0
                for p in range(n):
                    alpha += X[p, a] * X[p, a]
                    beta += X[p, b] * X[p, b]
                    gamma += X[p, a] * X[p, b]
                if abs(gamma) <= _EPS * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = (1.0 if zeta >= 0 else -1.0) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                sn = c * t
                for p in range(n):
                    xa, xb = X[p, a], X[p, b]
                    X[p, a] = c * xa - sn * xb
                    X[p, b] = sn * xa + c * xb
                for p in range(10):
                    va, vb = V[p, a], V[p, b]
                    V[p, a] = c * va - sn * vb
                    V[p, b] = sn * va + c * vb
        if not rotated:
            break
    # singular values: the column norms; the smallest, the next and the largest
    s1 = 0.0
    i10 = 0
    s10 = math.inf
    for j in range(10):
        sj = 0.0
        for p in range(n):
            sj += X[p, j] * X[p, j]
        sj = math.sqrt(sj)
        theta[j] = sj  # scratch
        s1 = max(s1, sj)
        if sj < s10:
            s10, i10 = sj, j
    s9 = math.inf
    for j in range(10):
        if j != i10:
            s9 = min(s9, theta[j])
    if s9 < 3.0 * s10 or s9 < 1e-10 * s1:  # NULLSPACE_RATIO of accelcal.lls
        return REFERENCE
    for j in range(10):
        theta[j] = V[j, i10]
    if not _theta_to_model(theta, g / k, out):
        return NO_ELLIPSOID
    out[0] *= k
    out[1] *= k
    out[2] *= k
    return OK


@jit
def full_lls_batch(z, g, min_gap, eigvec_tol, bias, M, status, clear):
    """Full LLS of every trial of ``z`` (T, n, 3): ``bias`` (T, 3), ``M`` (T, 3, 3) (NaN
    unless OK), ``status`` (T,); ``clear`` (T,) True where the moment screen showed the
    poses clearly three-dimensional (then the reference geometry check passes too).
    Trials the Gram route cannot certify are solved by :func:`_full_lls_svd`; those whose
    null space is not clearly one-dimensional, or whose poses are not finite, are left to
    the caller (REFERENCE, NON_FINITE)."""
    N = np.empty((10, 10))
    L = np.empty((10, 10))
    x = np.empty(10)
    wk = np.empty(30)
    out = np.empty(13)
    X = np.empty((z.shape[1], 10))
    V = np.empty((10, 10))
    for t in range(z.shape[0]):
        zt = z[t]
        s = _full_lls(zt, g, min_gap, eigvec_tol, out, N, L, x, wk)
        clear[t] = s != UNSCREENED
        if s == REFERENCE or s == UNSCREENED:
            s = NON_FINITE if not _all_finite(zt) else _full_lls_svd(zt, g, out, X, V, x)
        status[t] = s
        if s == OK:
            for i in range(3):
                bias[t, i] = out[i]
                for j in range(3):
                    M[t, i, j] = out[3 + 3 * i + j]
        else:
            for i in range(3):
                bias[t, i] = math.nan
                for j in range(3):
                    M[t, i, j] = math.nan


# ----------------------------------------------------------------------------- bias-only LLS
@jit
def _bias_lls(z, out):
    """Bias-only LLS of one problem (the centred 3x3 normal equations of
    :func:`accelcal.lls.bias_lls`): ``out`` = (b (3), c); status."""
    n = z.shape[0]
    if z.shape[1] != 3 or n < 4:  # the reference raises the error
        return REFERENCE
    sum_sq = _sum_squares(z)
    if not math.isfinite(sum_sq):
        return REFERENCE
    p1, p2, p3 = z[0, 0], z[0, 1], z[0, 2]
    sx = sy = sz = 0.0
    xx = xy = xz = yy = yz = zz = 0.0
    xq = yq = zq = 0.0
    for i in range(n):
        cx, cy, cz = z[i, 0] - p1, z[i, 1] - p2, z[i, 2] - p3
        x2, y2, z2 = cx * cx, cy * cy, cz * cz
        q = x2 + y2 + z2
        sx += cx
        sy += cy
        sz += cz
        xx += x2
        yy += y2
        zz += z2
        xy += cx * cy
        xz += cx * cz
        yz += cy * cz
        xq += cx * q
        yq += cy * q
        zq += cz * q
    mx, my, mz = sx / n, sy / n, sz / n
    a, b, c = xx - sx * mx, xy - sx * my, xz - sx * mz
    d, e, f = yy - sy * my, yz - sy * mz, zz - sz * mz
    if not _scatter_is_clearly_3d(a, b, c, d, e, f, sum_sq):
        return REFERENCE
    mean_cc = (xx + yy + zz) / n
    h1, h2, h3 = xq - sx * mean_cc, yq - sy * mean_cc, zq - sz * mean_cc
    # Cholesky of the scatter, as accelcal.lls._solve_spd3 (reciprocal pivots: three
    # divisions instead of nine, this runs for every trial of a batch)
    l11 = math.sqrt(a)
    i11 = 1.0 / l11
    l21, l31 = b * i11, c * i11
    l22 = math.sqrt(d - l21 * l21)
    i22 = 1.0 / l22
    l32 = (e - l31 * l21) * i22
    i33 = 1.0 / math.sqrt(f - l31 * l31 - l32 * l32)
    y1 = h1 * i11
    y2 = (h2 - l21 * y1) * i22
    y3 = (h3 - l31 * y1 - l32 * y2) * i33
    x3 = y3 * i33
    x2 = (y2 - l32 * x3) * i22
    x1 = (y1 - l21 * x2 - l31 * x3) * i11
    b1, b2, b3 = 0.5 * x1 + p1, 0.5 * x2 + p2, 0.5 * x3 + p3
    out[0], out[1], out[2] = b1, b2, b3
    out[3] = sum_sq / n - 2 * ((mx + p1) * b1 + (my + p2) * b2 + (mz + p3) * b3)
    return OK


@jit
def bias_lls(z, bias):
    """Bias-only LLS of poses ``z`` (n, 3) into ``bias`` (3,); returns c of eq. (7), or NaN
    where the reference must decide (c is finite whenever the kernel succeeds)."""
    out = np.empty(4)
    if _bias_lls(z, out) != OK:
        return math.nan
    bias[0], bias[1], bias[2] = out[0], out[1], out[2]
    return out[3]


@jit
def bias_lls_batch(z, bias, M, status, clear):
    """Bias-only LLS of every trial of ``z`` (T, n, 3) into ``bias`` (T, 3), ``M`` (T, 3, 3)
    the identity of the model; status (T,); ``clear`` as in :func:`full_lls_batch` (the
    kernel hands to the reference exactly the trials its screen does not pass)."""
    out = np.empty(4)
    for t in range(z.shape[0]):
        zt = z[t]
        s = _bias_lls(zt, out)
        clear[t] = s == OK
        if s == REFERENCE and not _all_finite(zt):
            s = NON_FINITE
        status[t] = s
        if s == OK:
            bias[t, 0], bias[t, 1], bias[t, 2] = out[0], out[1], out[2]
        else:
            bias[t, 0] = bias[t, 1] = bias[t, 2] = math.nan
        for i in range(3):
            for j in range(3):
                M[t, i, j] = 1.0 if i == j else 0.0


# ----------------------------------------------------------------------------- ALS
#: ALS statuses: no noise level below σ = 1 (scaled) makes Ψ singular; (batch) the
#: LLS was fine but the ALS estimate is no ellipsoid.
NO_NOISE_LEVEL = 4
ALS_NO_ELLIPSOID = 8


@jit
def _jacobi_eigh(A, w, V, vectors):
    """Eigenvalues ``w`` (unsorted) and, if ``vectors``, eigenvectors (columns of ``V``)
    of the symmetric 10x10 ``A`` (upper triangle read and destroyed), by the cyclic
    Jacobi method with thresholds (Rutishauser; Numerical Recipes ``jacobi``): accurate
    to rounding also for the eigenvalues near zero that ALS looks for."""
    n = 10
    b = np.empty(n)
    zacc = np.zeros(n)
    for i in range(n):
        b[i] = w[i] = A[i, i]
        if vectors:
            for j in range(n):
                V[i, j] = 0.0
            V[i, i] = 1.0
    for sweep in range(50):
        sm = 0.0
        for p in range(n - 1):
            for q in range(p + 1, n):
                sm += abs(A[p, q])
        if sm == 0.0:
            return
        tresh = 0.2 * sm / (n * n) if sweep < 3 else 0.0
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = A[p, q]
                gg = 100.0 * abs(apq)
                if sweep > 3 and abs(w[p]) + gg == abs(w[p]) and abs(w[q]) + gg == abs(w[q]):
                    A[p, q] = 0.0
                elif abs(apq) > tresh:
                    h = w[q] - w[p]
                    if abs(h) + gg == abs(h):
                        t = apq / h
                    else:
                        theta = 0.5 * h / apq
                        t = 1.0 / (abs(theta) + math.sqrt(1.0 + theta * theta))
                        if theta < 0.0:
                            t = -t
                    c = 1.0 / math.sqrt(1.0 + t * t)
                    s = t * c
                    tau = s / (1.0 + c)
                    h = t * apq
                    zacc[p] -= h
                    zacc[q] += h
                    w[p] -= h
                    w[q] += h
                    A[p, q] = 0.0
                    for j in range(p):
                        g1, h1 = A[j, p], A[j, q]
                        A[j, p] = g1 - s * (h1 + g1 * tau)
                        A[j, q] = h1 + s * (g1 - h1 * tau)
                    for j in range(p + 1, q):
                        g1, h1 = A[p, j], A[j, q]
                        A[p, j] = g1 - s * (h1 + g1 * tau)
                        A[j, q] = h1 + s * (g1 - h1 * tau)
                    for j in range(q + 1, n):
                        g1, h1 = A[p, j], A[q, j]
                        A[p, j] = g1 - s * (h1 + g1 * tau)
                        A[q, j] = h1 + s * (g1 - h1 * tau)
                    if vectors:
                        for j in range(n):
                            g1, h1 = V[j, p], V[j, q]
                            V[j, p] = g1 - s * (h1 + g1 * tau)
                            V[j, q] = h1 + s * (g1 - h1 * tau)
        for i in range(n):
            b[i] += zacc[i]
            w[i] = b[i]
            zacc[i] = 0.0


@jit
def _correction_terms(N, T1, T2, P1, P2):
    """``Ψ1 = T1 · N[9]``, ``Ψ2 = N[9, 9] T2`` (:func:`accelcal.als.corrected_matrix_terms`)."""
    for i in range(10):
        for j in range(10):
            s = 0.0
            for l in range(10):
                s += T1[i, j, l] * N[9, l]
            P1[i, j] = s
            P2[i, j] = N[9, 9] * T2[i, j]


@jit
def _psi(N, P1, P2, v, A):
    for i in range(10):
        for j in range(10):
            A[i, j] = N[i, j] + v * P1[i, j] + (v * v) * P2[i, j]


@jit
def _lam_min(N, P1, P2, v, A, w, V):
    _psi(N, P1, P2, v, A)
    _jacobi_eigh(A, w, V, False)
    m = w[0]
    for i in range(1, 10):
        m = min(m, w[i])
    return m


@jit
def _noise_var(N, P1, P2, A, w, V):
    """σ² (scaled) at which Ψ(σ²) becomes singular, as :func:`accelcal.als._noise_var_from`:
    the same bracket and scipy's ``brentq`` (xtol 1e-16, rtol 1e-12, 100 iterations).
    Returns -1 if there is no root below 1 (NO_NOISE_LEVEL), -2 if Brent's method did not
    converge (the reference decides)."""
    if _lam_min(N, P1, P2, 0.0, A, w, V) <= 0:
        return 0.0
    hi = 1e-6
    while _lam_min(N, P1, P2, hi, A, w, V) > 0:
        hi *= 4
        if hi > 1.0:
            return -1.0
    xtol, rtol = 1e-16, 1e-12
    xpre, xcur = 0.0, hi
    xblk = fblk = spre = scur = 0.0
    fpre = _lam_min(N, P1, P2, xpre, A, w, V)
    fcur = _lam_min(N, P1, P2, xcur, A, w, V)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    for _ in range(100):
        if fpre != 0 and fcur != 0 and (fpre < 0) != (fcur < 0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _lam_min(N, P1, P2, xcur, A, w, V)
    return -2.0


@jit
def _full_als(z, g, noise_std, T1, T2, out, ev, N, P1, P2, A, V, theta):
    """ALS of one problem whose full LLS succeeded: ``out`` = (b, M, λ of the unit Θ̂,
    σ² in input units), ``ev`` the eigenvalues of Ψ ascending; status."""
    n = z.shape[0]
    k = math.sqrt(_sum_squares(z) / n)
    _normal_matrix(z, k, N)
    _correction_terms(N, T1, T2, P1, P2)
    if math.isnan(noise_std):
        var = _noise_var(N, P1, P2, A, ev, V)
        if var == -1.0:
            return NO_NOISE_LEVEL
        if var < 0:
            return REFERENCE
    else:
        var = (noise_std / k) ** 2
    _psi(N, P1, P2, var, A)
    _jacobi_eigh(A, ev, V, True)
    imin = 0
    for i in range(1, 10):
        if ev[i] < ev[imin]:
            imin = i
    for i in range(10):
        theta[i] = V[i, imin]
    ev.sort()
    if not _theta_to_model(theta, g / k, out):
        return NO_ELLIPSOID
    out[0] *= k
    out[1] *= k
    out[2] *= k
    out[13] = var * k * k
    return OK


@jit
def full_als(z, g, noise_std, T1, T2, out, ev):
    """ALS of poses ``z`` (n, 3) whose full LLS succeeded (``noise_std`` NaN: estimated):
    ``out`` (14,) = b, M, λ, σ²; ``ev`` (10,) the eigenvalues of Ψ ascending; status."""
    return _full_als(z, g, noise_std, T1, T2, out, ev, np.empty((10, 10)), np.empty((10, 10)),
                     np.empty((10, 10)), np.empty((10, 10)), np.empty((10, 10)), np.empty(10))


@jit
def full_als_batch(z, g, noise_std, T1, T2, min_gap, eigvec_tol, bias, M, status):
    """ALS of every trial of ``z`` (T, n, 3): the full LLS kernel first (its status if it
    fails: REFERENCE, NO_ELLIPSOID, NON_FINITE), then ALS (NO_ELLIPSOID + 8 if ALS gives
    no ellipsoid, NO_NOISE_LEVEL, REFERENCE)."""
    N, P1, P2, A, V, L = (np.empty((10, 10)), np.empty((10, 10)), np.empty((10, 10)), np.empty((10, 10)),
                          np.empty((10, 10)), np.empty((10, 10)))
    x, ev, theta, wk = np.empty(10), np.empty(10), np.empty(10), np.empty(30)
    out = np.empty(14)
    for t in range(z.shape[0]):
        zt = z[t]
        s = _full_lls(zt, g, min_gap, eigvec_tol, out, N, L, x, wk)
        if s == UNSCREENED:
            s = REFERENCE
        if s == REFERENCE and not _all_finite(zt):
            s = NON_FINITE
        if s == OK:
            s = _full_als(zt, g, noise_std, T1, T2, out, ev, N, P1, P2, A, V, theta)
            if s == NO_ELLIPSOID:
                s = ALS_NO_ELLIPSOID
        status[t] = s
        for i in range(3):
            bias[t, i] = out[i] if s == OK else math.nan
            for j in range(3):
                M[t, i, j] = out[3 + 3 * i + j] if s == OK else math.nan

