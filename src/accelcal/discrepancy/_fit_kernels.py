"""Compiled kernels of the discrepancy fits (numba, the optional ``fast`` extra).

The white and colored loops evaluate the extended model thousands of times per
recording: every Levenberg–Marquardt iteration of every candidate fit, and every
Gauss–Newton iteration of the leave-one-pose-out refits (a stack of ``n`` parameter
vectors on ``n`` poses).  Each evaluation is a few thousand floating-point operations;
in numpy it costs dozens of array calls.  :func:`evaluate_batch` is
:func:`accelcal.discrepancy.fit.evaluate_batch` written as one compiled loop: same
algorithm (the same Newton iterations, stopped by the same batch-wide test), same
arithmetic up to the order of floating-point sums.

Effects are passed as codes (:data:`ADDITIVE`, :data:`SCALE`, or the power 2, 3 of a
polynomial term) with their centred covariate per pose.  Imported only through
:func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import numpy as np

from ..kernels import jit

#: Effect codes: an additive term ``φ c_i``, a scale term ``P(x) = (1 + φ c_i) x``; 2 and 3
#: are the polynomial terms ``φ x²`` and ``φ x³``.
ADDITIVE = 0
SCALE = 1


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


def _evaluate_batch(P, z, cov, code, g, jacobian, rtol):
    """Residuals ``r`` (B, n), Jacobian ``J`` (B, n, q) (empty if not ``jacobian``) and
    implied specific force ``x`` (B, n, 3): :func:`accelcal.discrepancy.fit.evaluate_batch`."""
    B, q = P.shape
    n = z.shape[0]
    k = code.shape[0]
    Ms = np.empty((B, 3, 3))
    dMs = np.empty((B, 6, 3, 3))
    As = np.empty((B, 3, 3))
    ok = np.empty(B, np.bool_)
    y = np.empty((B, n, 3))
    c1 = np.ones((B, n, 3))
    c2 = np.zeros((B, 3))
    c3 = np.zeros((B, 3))
    poly = False
    for e in range(k):
        poly = poly or code[e] != ADDITIVE  # P(x) = y needs solving (the scale term too)
    for b in range(B):
        ok[b] = _model(P[b], Ms[b], dMs[b], As[b])
        for i in range(n):
            d0, d1, d2 = z[i, 0] - P[b, 0], z[i, 1] - P[b, 1], z[i, 2] - P[b, 2]
            a0, a1, a2 = 0.0, 0.0, 0.0
            for e in range(k):
                o = 9 + 3 * e
                if code[e] == ADDITIVE:
                    a0 += cov[e, i] * P[b, o]
                    a1 += cov[e, i] * P[b, o + 1]
                    a2 += cov[e, i] * P[b, o + 2]
                elif code[e] == SCALE:
                    for j in range(3):
                        c1[b, i, j] += cov[e, i] * P[b, o + j]
            d0, d1, d2 = d0 - a0, d1 - a1, d2 - a2
            for j in range(3):
                y[b, i, j] = d0 * As[b, j, 0] + d1 * As[b, j, 1] + d2 * As[b, j, 2]
        for e in range(k):
            o = 9 + 3 * e
            for j in range(3):
                if code[e] == 2:
                    c2[b, j] += P[b, o + j]
                elif code[e] == 3:
                    c3[b, j] += P[b, o + j]
    x = y.copy()
    dP = c1.copy()
    if poly:
        _newton(x, y, c1, c2, c3, dP, ok, g, rtol)
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
        _jacobian(J, x, y, norm, dP, As, dMs, cov, code)
    return r, J, x


def _newton(x, y, c1, c2, c3, dP, ok, g, rtol):
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
    for _ in range(60):
        big = -np.inf
        for b in range(B):
            for i in range(n):
                for j in range(3):
                    xx = x[b, i, j]
                    d = c1[b, i, j] + 2 * c2[b, j] * xx + 3 * c3[b, j] * xx * xx
                    f = c1[b, i, j] * xx + c2[b, j] * xx * xx + c3[b, j] * xx ** 3 - y[b, i, j]
                    s = f / d if d > 0 else np.nan
                    step[b, i, j] = s
                    x[b, i, j] = xx - s
                    if abs(s) > big:  # NaN never compares greater: nanmax
                        big = abs(s)
        if not big > tol:
            converged = True
            break
    for b in range(B):
        for i in range(n):
            for j in range(3):
                if not converged and not abs(step[b, i, j]) <= tol:
                    ok[b] = False
                xx = x[b, i, j]
                dP[b, i, j] = c1[b, i, j] + 2 * c2[b, j] * xx + 3 * c3[b, j] * xx * xx
                if not dP[b, i, j] > 0:
                    ok[b] = False


def _jacobian(J, x, y, norm, dP, As, dMs, cov, code):
    """Analytic Jacobian of the residuals (module docstring of :mod:`accelcal.discrepancy.fit`)."""
    B, n, _ = x.shape
    v = np.empty(3)
    w = np.empty(3)
    for b in range(B):
        A = As[b]
        dM = dMs[b]
        for i in range(n):
            for j in range(3):
                v[j] = (x[b, i, j] / norm[b, i]) / dP[b, i, j]
            for j in range(3):
                w[j] = v[0] * A[0, j] + v[1] * A[1, j] + v[2] * A[2, j]
                J[b, i, j] = -w[j]
            for m in range(6):
                acc = 0.0
                for row in range(3):
                    acc += w[row] * (dM[m, row, 0] * y[b, i, 0] + dM[m, row, 1] * y[b, i, 1]
                                     + dM[m, row, 2] * y[b, i, 2])
                J[b, i, 3 + m] = -acc
            for e in range(code.shape[0]):
                o = 9 + 3 * e
                for j in range(3):
                    if code[e] == ADDITIVE:
                        J[b, i, o + j] = -w[j] * cov[e, i]
                    elif code[e] == SCALE:
                        J[b, i, o + j] = -v[j] * x[b, i, j] * cov[e, i]
                    else:
                        J[b, i, o + j] = -v[j] * x[b, i, j] ** code[e]


_model = jit(_model)
_newton = jit(_newton)
_jacobian = jit(_jacobian)
_evaluate_batch = jit(_evaluate_batch)


def evaluate_batch(P, z, cov, code, g: float, jacobian: bool, rtol: float):
    """Residuals, Jacobian (None if not ``jacobian``) and implied specific force of the
    parameter stack ``P`` (B, q) on the pose means ``z`` (n, 3); ``cov`` (k, n) the centred
    covariate of each effect (zeros for the polynomial ones), ``code`` (k,) its kind."""
    r, J, x = _evaluate_batch(np.ascontiguousarray(P, dtype=np.float64), np.ascontiguousarray(z, dtype=np.float64),
                              np.ascontiguousarray(cov, dtype=np.float64), np.asarray(code, dtype=np.int64),
                              float(g), bool(jacobian), float(rtol))
    return r, (J if jacobian else None), x


__all__ = ["ADDITIVE", "SCALE", "evaluate_batch"]
