"""Compiled kernels of the discrepancy fits (numba, the optional ``fast`` extra).

The white and wander loops evaluate the extended model thousands of times per
recording: every Levenberg–Marquardt iteration of every candidate fit, and every
Gauss–Newton iteration of the leave-one-pose-out refits (a stack of ``n`` parameter
vectors on ``n`` poses).  Each evaluation is a few thousand floating-point operations;
in numpy it costs dozens of array calls.  :func:`evaluate_batch` is
:func:`accelcal.discrepancy.residuals.evaluate_batch` written as one compiled loop: same
algorithm (the same Newton iterations, stopped by the same batch-wide test), same
arithmetic up to the order of floating-point sums.

Effects are passed as the arrays of :attr:`accelcal.extended_model.EffectTerms.kernel_arrays`
(per effect: its covariate column, the power of ``x``, whether it is additive, whether it
is harmonic and then its basis tensors): every effect of :mod:`accelcal.effects` runs
through the same loops, in the sums and products of :mod:`accelcal.extended_model`
(a harmonic effect couples the axes: Newton on the three at once, 3 × 3 systems by their
cofactors, as :meth:`accelcal.extended_model.ModelTerms.solve`).  Imported only through :func:`accelcal.kernels.compiled`
(it imports numba).
"""

from __future__ import annotations

import numpy as np

from ..kernels import jit

#: A flag that numba types as ``bool``, not as the constant ``Literal[bool]`` (which would
#: compile a callee once more for that constant; see the end of the module).
_YES, _NO = np.True_, np.False_


def _model(p, M, dM, A):
    """``M(s, θ)``, ``∂M/∂(s, θ)`` and ``A = M⁻¹`` (identity when invalid) of one parameter
    vector, into the given arrays; returns whether the angles and scales are valid."""
    s0, s1, s2 = p[3], p[4], p[5]
    sn0, sn1, sn2 = np.sin(p[6]), np.sin(p[7]), np.sin(p[8])
    cs0, cs1, cs2 = np.cos(p[6]), np.cos(p[7]), np.cos(p[8])
    uzz2 = 1.0 - sn1 ** 2 - sn2 ** 2
    ok = uzz2 > 0 and 1.0 + s0 > 0 and 1.0 + s1 > 0 and 1.0 + s2 > 0
    uzz = np.sqrt(uzz2) if ok else 1.0
    g0, g1, g2 = 1.0 + s0, 1.0 + s1, 1.0 + s2
    M[:] = 0.0
    M[0, 0] = g0
    M[1, 0], M[1, 1] = sn0 * g1, cs0 * g1
    M[2, 0], M[2, 1], M[2, 2] = sn1 * g2, sn2 * g2, uzz * g2
    dM[:] = 0.0
    dM[0, 0, 0] = 1.0
    dM[1, 1, 0], dM[1, 1, 1] = sn0, cs0
    dM[2, 2, 0], dM[2, 2, 1], dM[2, 2, 2] = sn1, sn2, uzz
    dM[3, 1, 0], dM[3, 1, 1] = g1 * cs0, -g1 * sn0
    dM[4, 2, 0], dM[4, 2, 2] = g2 * cs1, -g2 * sn1 * cs1 / uzz
    dM[5, 2, 1], dM[5, 2, 2] = g2 * cs2, -g2 * sn2 * cs2 / uzz
    # M is lower triangular: its inverse by forward substitution
    A[:] = 0.0
    if ok:
        A[0, 0], A[1, 1], A[2, 2] = 1.0 / M[0, 0], 1.0 / M[1, 1], 1.0 / M[2, 2]
        A[1, 0] = -M[1, 0] * A[0, 0] * A[1, 1]
        A[2, 1] = -M[2, 1] * A[1, 1] * A[2, 2]
        A[2, 0] = -(M[2, 0] * A[0, 0] + M[2, 1] * A[1, 0]) * A[2, 2]
    else:
        A[0, 0] = A[1, 1] = A[2, 2] = 1.0
    return ok


def _offsets(harmonic, basis):
    """Where each effect's parameters start in the parameter vector (after the nine of the base)."""
    k = harmonic.shape[0]
    off = np.empty(k, np.int64)
    o = 9
    for e in range(k):
        off[e] = o
        o += basis.shape[1] if harmonic[e] else 3
    return off


def _evaluate_batch(P, z, cov, power, additive, harmonic, basis, g, jacobian, rtol):
    """Residuals ``r`` (B, n), Jacobian ``J`` (B, n, q) (empty if not ``jacobian``) and
    implied specific force ``x`` (B, n, 3): :func:`accelcal.discrepancy.residuals.evaluate_batch`."""
    B, q = P.shape
    n = z.shape[0]
    k = power.shape[0]
    off = _offsets(harmonic, basis)
    top = 1  # the highest power of P(x)
    poly = False  # P(x) = y needs solving (a power-1 term too)
    coupled = _NO  # a harmonic effect: the three axes at once
    for e in range(k):
        if harmonic[e]:
            coupled = True
        elif not additive[e]:
            poly = True
            top = max(top, power[e])
    K = np.zeros((B, 3, 3, 3))  # the harmonic effects' second-order tensor
    for b in range(B):
        for e in range(k):
            if harmonic[e]:
                for m in range(basis.shape[1]):  # K[b] += P[b, off[e] + m] * basis[e, m], element by element
                    c = P[b, off[e] + m]
                    for j in range(3):
                        for kk in range(3):
                            for ll in range(3):
                                K[b, j, kk, ll] += c * basis[e, m, j, kk, ll]
    Ms = np.empty((B, 3, 3))
    dMs = np.empty((B, 6, 3, 3))
    As = np.empty((B, 3, 3))
    ok = np.empty(B, np.bool_)
    y = np.empty((B, n, 3))
    C = np.zeros((B, n, 3, top + 1))  # C[b, i, j, p]: coefficient of x_j^p in P_j at pose i
    for b in range(B):
        ok[b] = _model(P[b], Ms[b], dMs[b], As[b])
        for i in range(n):
            d0, d1, d2 = z[i, 0] - P[b, 0], z[i, 1] - P[b, 1], z[i, 2] - P[b, 2]
            a0, a1, a2 = 0.0, 0.0, 0.0
            for j in range(3):
                C[b, i, j, 1] = 1.0
            for e in range(k):
                o = off[e]
                if harmonic[e]:
                    continue
                if additive[e]:
                    a0 += cov[e, i] * P[b, o]
                    a1 += cov[e, i] * P[b, o + 1]
                    a2 += cov[e, i] * P[b, o + 2]
                else:
                    for j in range(3):
                        C[b, i, j, power[e]] += cov[e, i] * P[b, o + j]
            d0, d1, d2 = d0 - a0, d1 - a1, d2 - a2
            for j in range(3):
                y[b, i, j] = d0 * As[b, j, 0] + d1 * As[b, j, 1] + d2 * As[b, j, 2]
    x = y.copy()
    dP = np.ones((B, n, 3))
    jac = np.empty((B, n, 3, 3))
    if coupled:
        _newton_coupled(x, y, C, K, jac, ok, g, rtol)
    elif poly:
        _newton(x, y, C, dP, ok, g, rtol)
    r = np.empty((B, n))
    norm = np.empty((B, n))
    for b in range(B):
        for i in range(n):
            nn = np.sqrt(x[b, i, 0] ** 2 + x[b, i, 1] ** 2 + x[b, i, 2] ** 2)
            norm[b, i] = nn
            r[b, i] = nn - g
            if not np.isfinite(r[b, i]):
                ok[b] = False
        if not ok[b]:
            r[b, :] = np.nan
    J = np.empty((B, n, q if jacobian else 0))
    if jacobian:
        _jacobian(J, x, y, norm, dP, jac, coupled, As, dMs, cov, power, additive, harmonic, basis, off)
    return r, J, x


def _ipow(x, p):
    """``x ** p`` for an integer ``p >= 0`` as numba computes it (by squaring: ``x³ = x (x x)``)."""
    r = 1.0
    while p:
        if p & 1:
            r *= x
        p >>= 1
        x *= x
    return r


def _value_and_slope(C, b, i, j, xx):
    """``P(x)`` and ``P'(x)`` of coordinate ``j`` of pose ``i`` (``C[b, i, j, p]`` the
    coefficient of ``x^p``), in the sums and products of
    :meth:`accelcal.extended_model.ModelTerms.solve` (``C₂ x²`` as ``(C₂ x) x``,
    ``p C_p x^(p-1)`` as ``(p C_p) x … x``, powers ascending).  The squares and cubes are
    written out: the same products as the loop, which costs half as much again."""
    top = C.shape[3] - 1
    c = C[b, i, j, 1]
    value = c * xx
    slope = c
    if top >= 2:
        c = C[b, i, j, 2]
        value += c * xx * xx
        slope += 2 * c * xx
    if top >= 3:
        c = C[b, i, j, 3]
        value += c * (xx * (xx * xx))
        slope += 3 * c * xx * xx
    for p in range(4, top + 1):
        c = C[b, i, j, p]
        value += c * _ipow(xx, p)
        t = p * c
        for _ in range(p - 1):
            t *= xx
        slope += t
    return value, slope


def _newton(x, y, C, dP, ok, g, rtol):
    """Solve ``P(x) = y`` axis by axis in place (Newton, one stopping test for the whole
    batch, as the numpy reference), then ``dP = P'(x)``; clears ``ok`` where it fails."""
    B, n, _ = x.shape
    scale = g
    for b in range(B):
        for i in range(n):
            for j in range(3):
                scale = max(scale, abs(y[b, i, j]))
    tol = rtol * scale
    step = np.empty_like(x)
    converged = False
    for _ in range(60):  # accelcal.extended_model.NEWTON_MAX_ITER
        big = -np.inf
        for b in range(B):
            for i in range(n):
                for j in range(3):
                    xx = x[b, i, j]
                    f, d = _value_and_slope(C, b, i, j, xx)
                    s = (f - y[b, i, j]) / d if d > 0 else np.nan
                    step[b, i, j] = s
                    x[b, i, j] = xx - s
                    if abs(s) > big:  # noqa: PLR1730 (NaN never compares greater: nanmax)
                        big = abs(s)
        if not big > tol:
            converged = True
            break
    for b in range(B):
        for i in range(n):
            for j in range(3):
                if not converged and not abs(step[b, i, j]) <= tol:
                    ok[b] = False
                dP[b, i, j] = _value_and_slope(C, b, i, j, x[b, i, j])[1]
                if not dP[b, i, j] > 0:
                    ok[b] = False


def _inverse3(a, inv):
    """Inverse of the 3 × 3 ``a`` into ``inv`` by its cofactors; returns the determinant
    (:func:`accelcal.extended_model.inverse3`)."""
    A0 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    B0 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    C0 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * A0 + a[0, 1] * B0 + a[0, 2] * C0
    inv[0, 0], inv[0, 1], inv[0, 2] = A0, a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2], a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    inv[1, 0], inv[1, 1], inv[1, 2] = B0, a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0], a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    inv[2, 0], inv[2, 1], inv[2, 2] = C0, a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1], a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    for r in range(3):
        for c in range(3):
            inv[r, c] /= det
    return det


def _coupled_at(C, K, b, i, xi, yi, jac, res):
    """``∂P/∂x`` into ``jac`` (3, 3) and ``P(x) − y`` into ``res`` (3,) at ``xi`` (pose ``i``,
    member ``b``): the per-axis slopes plus ``2 K(·, ·, x)``, the values plus ``K(x, x)``."""
    for j in range(3):
        value, slope = _value_and_slope(C, b, i, j, xi[j])
        acc = 0.0
        for kk in range(3):
            kx = 0.0
            for ll in range(3):
                kx += K[b, j, kk, ll] * xi[ll]
            jac[j, kk] = 2.0 * kx + (slope if kk == j else 0.0)
            acc += kx * xi[kk]
        res[j] = value + acc - yi[j]


def _newton_coupled(x, y, C, K, jac_out, ok, g, rtol):
    """Solve ``P(x) = y`` with a harmonic effect, the three axes at once (Newton, one stopping
    test for the whole batch, as the numpy reference), then ``jac_out = ∂P/∂x``; clears
    ``ok`` where it fails (``det ∂P/∂x <= 0`` or no convergence)."""
    B, n, _ = x.shape
    scale = g
    for b in range(B):
        for i in range(n):
            for j in range(3):
                scale = max(scale, abs(y[b, i, j]))
    tol = rtol * scale
    step = np.empty_like(x)
    jac = np.empty((3, 3))
    inv = np.empty((3, 3))
    res = np.empty(3)
    converged = False
    for _ in range(60):  # accelcal.extended_model.NEWTON_MAX_ITER
        big = -np.inf
        for b in range(B):
            for i in range(n):
                _coupled_at(C, K, b, i, x[b, i], y[b, i], jac, res)
                det = _inverse3(jac, inv)
                for j in range(3):
                    s = inv[j, 0] * res[0] + inv[j, 1] * res[1] + inv[j, 2] * res[2] if det > 0 else np.nan
                    step[b, i, j] = s
                for j in range(3):
                    x[b, i, j] -= step[b, i, j]
                    if abs(step[b, i, j]) > big:  # noqa: PLR1730 (NaN never compares greater: nanmax)
                        big = abs(step[b, i, j])
        if not big > tol:
            converged = True
            break
    for b in range(B):
        for i in range(n):
            for j in range(3):
                if not converged and not abs(step[b, i, j]) <= tol:
                    ok[b] = False
            _coupled_at(C, K, b, i, x[b, i], y[b, i], jac_out[b, i], res)
            if not _inverse3(jac_out[b, i], inv) > 0:
                ok[b] = False


def _jacobian(J, x, y, norm, dP, jac, coupled, As, dMs, cov, power, additive, harmonic, basis, off):
    """Analytic Jacobian of the residuals (module docstring of :mod:`accelcal.discrepancy.residuals`).

    ``∂r/∂p_k = -w (∂M/∂p_k) y``: each ``∂M/∂(s, θ)_k`` has one non-zero row with one to
    three non-zero entries (:func:`_model`), and only those are summed.  The effects'
    columns are :meth:`accelcal.extended_model.EffectTerms.jacobian_columns` (with a harmonic
    effect ``v = x̂ᵀ (∂P/∂x)⁻¹``)."""
    B, n, _ = x.shape
    v = np.empty(3)
    w = np.empty(3)
    inv = np.empty((3, 3))
    xh = np.empty(3)
    for b in range(B):
        A = As[b]
        dM = dMs[b]
        for i in range(n):
            y0, y1, y2 = y[b, i, 0], y[b, i, 1], y[b, i, 2]
            if coupled:
                _inverse3(jac[b, i], inv)
                for j in range(3):
                    xh[j] = x[b, i, j] / norm[b, i]
                for j in range(3):
                    v[j] = xh[0] * inv[0, j] + xh[1] * inv[1, j] + xh[2] * inv[2, j]
            else:
                for j in range(3):
                    v[j] = (x[b, i, j] / norm[b, i]) / dP[b, i, j]
            for j in range(3):
                w[j] = v[0] * A[0, j] + v[1] * A[1, j] + v[2] * A[2, j]
                J[b, i, j] = -w[j]
            J[b, i, 3] = -(w[0] * (dM[0, 0, 0] * y0))
            J[b, i, 4] = -(w[1] * (dM[1, 1, 0] * y0 + dM[1, 1, 1] * y1))
            J[b, i, 5] = -(w[2] * (dM[2, 2, 0] * y0 + dM[2, 2, 1] * y1 + dM[2, 2, 2] * y2))
            J[b, i, 6] = -(w[1] * (dM[3, 1, 0] * y0 + dM[3, 1, 1] * y1))
            J[b, i, 7] = -(w[2] * (dM[4, 2, 0] * y0 + dM[4, 2, 2] * y2))
            J[b, i, 8] = -(w[2] * (dM[5, 2, 1] * y1 + dM[5, 2, 2] * y2))
            for e in range(power.shape[0]):
                o = off[e]
                if harmonic[e]:  # -v · T_m(x, x)
                    for m in range(basis.shape[1]):
                        acc = 0.0
                        for j in range(3):
                            for kk in range(3):
                                for ll in range(3):
                                    acc += v[j] * basis[e, m, j, kk, ll] * x[b, i, kk] * x[b, i, ll]
                        J[b, i, o + m] = -acc
                    continue
                for j in range(3):
                    if additive[e]:
                        J[b, i, o + j] = -w[j] * cov[e, i]
                    else:
                        J[b, i, o + j] = -v[j] * _ipow(x[b, i, j], power[e]) * cov[e, i]


def _lopo_system(P, z, cov, power, additive, harmonic, basis, g, rtol, sig, normal):
    """One Gauss–Newton system per leave-one-pose-out refit (row ``b`` of ``P`` leaves out
    pose ``b``): residuals ``r`` (B, n), the reduced χ² ``cost`` (B,), and if ``normal``
    the column scales ``d`` (B, q) and the scaled normal equations ``H`` (B, q, q),
    ``grad`` (B, q), as :func:`accelcal.discrepancy.fit.lopo` forms them (else empty)."""
    r, J, _ = _evaluate_batch(P, z, cov, power, additive, harmonic, basis, g, normal, rtol)
    B, n = r.shape
    q = J.shape[2]
    cost = np.empty(B)
    d = np.empty((B, q))
    H = np.empty((B, q, q))
    grad = np.empty((B, q))
    if not normal:
        for b in range(B):
            c = 0.0
            for i in range(n):
                rw = r[b, i] / sig[i] * (0.0 if i == b else 1.0)
                c += rw * rw
            cost[b] = c
        return r, cost, d, H, grad
    rw = np.empty(n)
    Js = np.empty((q, n))  # transposed: the sums below run along contiguous rows
    for b in range(B):
        c = 0.0
        for i in range(n):
            keep = 0.0 if i == b else 1.0  # times zero, not skipped: a NaN residual stays NaN
            rw[i] = r[b, i] / sig[i] * keep
            c += rw[i] * rw[i]
            for j in range(q):
                Js[j, i] = J[b, i, j] / sig[i] * keep
        cost[b] = c
        for j in range(q):
            acc = 0.0
            for i in range(n):
                acc += Js[j, i] * Js[j, i]
            d[b, j] = np.sqrt(acc) if acc != 0 else 1.0
            for i in range(n):
                Js[j, i] /= d[b, j]
        Hb = np.dot(Js, Js.T)  # BLAS, as numpy's matmul of the reference
        gb = np.dot(Js, rw)
        for j in range(q):  # copied element by element: see the end of the module
            grad[b, j] = gb[j]
            for k in range(q):
                H[b, j, k] = Hb[j, k]
    return r, cost, d, H, grad


def _lu_solve(H, g, x):
    """Solve ``H x = g`` (q, q) into ``x`` by LU with partial pivoting (as LAPACK's gesv);
    False if a pivot is exactly zero (numpy's solve raises LinAlgError then).  NaN in, NaN out."""
    q = H.shape[0]
    A = H.copy()
    y = g.copy()
    for k in range(q):
        p = k
        for i in range(k + 1, q):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if A[p, k] == 0.0:
            return False
        if p != k:
            for j in range(q):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            y[k], y[p] = y[p], y[k]
        for i in range(k + 1, q):
            f = A[i, k] / A[k, k]
            for j in range(k + 1, q):
                A[i, j] -= f * A[k, j]
            y[i] -= f * y[k]
    for k in range(q - 1, -1, -1):
        acc = y[k]
        for j in range(k + 1, q):
            acc -= A[k, j] * x[j]
        x[k] = acc / A[k, k]
    return True


def _lopo_step(P, z, cov, power, additive, harmonic, basis, g, rtol, sig, normal):
    """:func:`_lopo_system` and its Gauss–Newton step: ``(r, cost, step / d, pred, d, H, grad,
    solved)`` with ``step = -H⁻¹ grad`` and ``pred = -grad · step`` per row; ``solved`` false if
    some ``H`` is singular (then the caller takes the pseudo-inverse of every row, as numpy)."""
    r, cost, d, H, grad = _lopo_system(P, z, cov, power, additive, harmonic, basis, g, rtol, sig, normal)
    B, q = d.shape
    step = np.empty((B, q))
    pred = np.empty(B)
    solved = True
    if normal:
        x = np.empty(q)
        for b in range(B):
            solved = solved and _lu_solve(H[b], grad[b], x)
            pred[b] = 0.0
            for j in range(q):
                pred[b] += grad[b, j] * x[j]  # -grad · step, step = -x
                step[b, j] = -x[j] / d[b, j]
    return r, cost, step, pred, d, H, grad, solved


def _weighted(p, z, cov, power, additive, harmonic, basis, g, rtol, sig):
    """Residuals, weighted Jacobian ``J / σ`` and ``x`` at one parameter vector; ``ok`` false
    where the model cannot be inverted (the numpy fit's ``fun`` returning None)."""
    r, J, x = _evaluate_batch(p.reshape(1, -1), z, cov, power, additive, harmonic, basis, g, _YES, rtol)
    n, q = J.shape[1], J.shape[2]
    ok = True
    for i in range(n):
        ok = ok and np.isfinite(r[0, i])
    Jw = np.empty((n, q))
    for i in range(n):
        for j in range(q):
            Jw[i, j] = J[0, i, j] / sig[i]
    return r[0], Jw, x[0], ok


def _chi2(r, sig):
    c = 0.0
    for i in range(r.shape[0]):
        c += (r[i] / sig[i]) ** 2
    return c


def _lm_step(r, Jw, sig, cost, lam):
    """Levenberg–Marquardt step with Marquardt's column scaling (least squares on the
    augmented system, as :func:`accelcal.discrepancy.fit.fit`) and the χ² decrease it predicts."""
    n, q = Jw.shape
    d = np.empty(q)
    for j in range(q):
        acc = 0.0
        for i in range(n):
            acc += Jw[i, j] * Jw[i, j]
        d[j] = np.sqrt(acc) if acc != 0 else 1.0
    A = np.zeros((n + q, q))
    rhs = np.zeros(n + q)
    for i in range(n):
        rhs[i] = -(r[i] / sig[i])
        for j in range(q):
            A[i, j] = Jw[i, j] / d[j]
    for j in range(q):
        A[n + j, j] = np.sqrt(lam)
    step = _least_squares(A, rhs)
    for j in range(q):
        step[j] /= d[j]
    pred = 0.0
    for i in range(n):
        acc = r[i] / sig[i]
        for j in range(q):
            acc += Jw[i, j] * step[j]
        pred += acc * acc
    return step, cost - pred


def _least_squares(A, b):
    """``argmin |A x - b|`` of a full-column-rank ``A`` (m, q), by Householder QR (overwrites
    ``A`` and ``b``).  The LM system has full rank (its damping rows ``sqrt(λ) I``, λ ≥ 1e-12,
    keep every singular value of the unit-norm columns far above the rank cut-off of the
    SVD that numpy's ``lstsq`` uses), so both give its one solution to rounding; QR costs a
    fraction of the SVD's LAPACK set-up for these small problems."""
    m, q = A.shape
    for k in range(q):
        norm = 0.0
        for i in range(k, m):
            norm += A[i, k] * A[i, k]
        norm = np.sqrt(norm)
        if norm == 0.0:
            continue
        alpha = -norm if A[k, k] >= 0 else norm
        A[k, k] -= alpha  # v = a_k - alpha e_k, stored in place of the column
        vv = 0.0
        for i in range(k, m):
            vv += A[i, k] * A[i, k]
        for j in range(k + 1, q):
            dot = 0.0
            for i in range(k, m):
                dot += A[i, k] * A[i, j]
            f = 2.0 * dot / vv
            for i in range(k, m):
                A[i, j] -= f * A[i, k]
        dot = 0.0
        for i in range(k, m):
            dot += A[i, k] * b[i]
        f = 2.0 * dot / vv
        for i in range(k, m):
            b[i] -= f * A[i, k]
        A[k, k] = alpha  # the diagonal of R
    x = np.empty(q)
    for k in range(q - 1, -1, -1):  # back substitution R x = (Qᵀ b)[:q]
        acc = b[k]
        for j in range(k + 1, q):
            acc -= A[k, j] * x[j]
        x[k] = acc / A[k, k]
    return x


def _lm_fit(p, z, cov, power, additive, harmonic, basis, g, rtol, sig, max_iter, chi2_tol):
    """:func:`accelcal.discrepancy.fit.fit` from the start ``p``: returns ``(p, r, J / σ, x,
    iterations, status)``, status 0 converged, 1 start not invertible, 2 not converged."""
    r, J, x, ok = _weighted(p, z, cov, power, additive, harmonic, basis, g, rtol, sig)
    if not ok:
        return p, r, J, x, 0, 1
    cost = _chi2(r, sig)
    lam = 1e-6
    for it in range(1, max_iter + 1):
        step, pred = _lm_step(r, J, sig, cost, lam)
        p_new = np.empty(p.shape[0])
        for j in range(p.shape[0]):
            p_new[j] = p[j] + step[j]
        r_new, J_new, x_new, ok = _weighted(p_new, z, cov, power, additive, harmonic, basis, g, rtol, sig)
        cost_new = _chi2(r_new, sig) if ok else np.inf
        if ok and cost_new <= cost:
            p, r, J, x = p_new, r_new, J_new, x_new
            decrease = cost - cost_new
            cost = cost_new
            lam = max(lam / 10, 1e-12)
            if pred <= chi2_tol and decrease <= chi2_tol:
                return p, r, J, x, it, 0
        else:
            if pred <= chi2_tol:  # at the optimum: no step can lower χ² measurably
                return p, r, J, x, it, 0
            lam *= 10
            if lam > 1e12:
                break
    return p, r, J, x, max_iter, 2


# Compile time (a fresh clone compiles every kernel once; tools/bench_kernel_compile.py
# measures it).  numba compiles each jitted callee as a library of its own and links its
# code into every caller's library, where LLVM optimises and emits it again: each level of
# calls between an entry point and _evaluate_batch paid for that whole tree once more.  So:
# * the small helpers and the wrappers between an entry point and _evaluate_batch are
#   inlined by numba (``inline="always"``): no library of their own.  The large _newton,
#   _newton_coupled and _jacobian keep theirs (numba's inliner deep-copies a callee's IR:
#   inlining them measured 1-2 s slower), as do the three entry points, _coupled_at, _chi2;
# * flags go to a jitted callee typed ``bool`` (_YES, _NO, or an argument): a literal
#   True compiled a second _evaluate_batch (and _jacobian) typed on the constant;
# * arrays are copied into arrays element by element, not by ``a[i] = b``: numba's
#   array-to-array assignment brings its shape-mismatch error message, whose string
#   formatting took ~5 s to compile;
# * no array expressions (``a + b`` of arrays): each compiles a loop of its own.
# The arithmetic is unchanged (the same operations in the same order: the same bits).
_model = jit(_model, inline="always")
_newton = jit(_newton)
_offsets = jit(_offsets, inline="always")
_inverse3 = jit(_inverse3, inline="always")
_coupled_at = jit(_coupled_at)
_newton_coupled = jit(_newton_coupled)
_ipow = jit(_ipow, inline="always")
_value_and_slope = jit(_value_and_slope, inline="always")
_jacobian = jit(_jacobian)
_evaluate_batch = jit(_evaluate_batch)
_lopo_system = jit(_lopo_system, inline="always")
_lu_solve = jit(_lu_solve, inline="always")
_lopo_step = jit(_lopo_step)
_weighted = jit(_weighted, inline="always")
_chi2 = jit(_chi2)
_least_squares = jit(_least_squares, inline="always")
_lm_step = jit(_lm_step, inline="always")
_lm_fit = jit(_lm_fit)


def _arrays(cov, power, additive, harmonic, basis):
    return (np.ascontiguousarray(cov, dtype=np.float64), np.ascontiguousarray(power, dtype=np.int64),
            np.ascontiguousarray(additive, dtype=np.bool_), np.ascontiguousarray(harmonic, dtype=np.bool_),
            np.ascontiguousarray(basis, dtype=np.float64))


def evaluate_batch(P, z, cov, power, additive, harmonic, basis, g: float, jacobian: bool, rtol: float):
    """Residuals, Jacobian (None if not ``jacobian``) and implied specific force of the
    parameter stack ``P`` (B, q) on the pose means ``z`` (n, 3); ``cov`` (k, n) the centred
    covariate of each effect (ones where it has none), ``power`` (k,) the power of ``x``,
    ``additive`` (k,) whether it is added to ``z``, ``harmonic`` (k,) whether it is a harmonic
    effect and ``basis`` (k, m, 3, 3, 3) its tensors (:attr:`accelcal.extended_model.EffectTerms.kernel_arrays`)."""
    r, J, x = _evaluate_batch(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
                              *_arrays(cov, power, additive, harmonic, basis), float(g), bool(jacobian), float(rtol))
    return r, (J if jacobian else None), x


def lopo_step(P, z, cov, power, additive, harmonic, basis, g: float, rtol: float, sig, normal: bool = True):
    """:func:`_lopo_step` on contiguous float arrays."""
    return _lopo_step(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
                      *_arrays(cov, power, additive, harmonic, basis), float(g), float(rtol),
                      np.ascontiguousarray(sig, dtype=np.float64), bool(normal))


def lm_fit(p, z, cov, power, additive, harmonic, basis, g: float, rtol: float, sig, max_iter: int, chi2_tol: float):
    """:func:`_lm_fit` on contiguous float arrays."""
    return _lm_fit(np.array(p, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
                   *_arrays(cov, power, additive, harmonic, basis), float(g), float(rtol),
                   np.ascontiguousarray(sig, dtype=np.float64), int(max_iter), float(chi2_tol))


__all__ = ["evaluate_batch", "lm_fit", "lopo_step"]
