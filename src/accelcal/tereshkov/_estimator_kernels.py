"""Compiled step loop of Tereshkov's virtual-platform estimator (:func:`accelcal.tereshkov.run_estimator`).

The same step as the numpy reference (levelling torque, heading torque, gating, eqs.
(12) and (14) or (13) through the low-pass filters, fourth-order body rotation and
first-order platform rotation of ``C``, re-orthonormalisation every
``RENORMALISE_EVERY`` steps), one run after the other in scalar arithmetic, compiled
by numba (:mod:`accelcal.kernels`).  The nearest rotation is computed by Newton's
iteration for the polar factor (``X <- (X + X⁻ᵀ)/2``, quadratic: two or three steps
from a matrix 1e-6 away from orthogonal) instead of the SVD; both give it to rounding.

Imported only through :func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import jit

STRAIGHT, TURN, OTHER = 0, 1, 2  # as accelcal.tereshkov.estimator


@jit
def _inverse_transpose(X, Y):
    """``Y = X⁻ᵀ`` (3x3) by cofactors; returns det(X)."""
    c00 = X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1]
    c01 = X[1, 2] * X[2, 0] - X[1, 0] * X[2, 2]
    c02 = X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0]
    c10 = X[0, 2] * X[2, 1] - X[0, 1] * X[2, 2]
    c11 = X[0, 0] * X[2, 2] - X[0, 2] * X[2, 0]
    c12 = X[0, 1] * X[2, 0] - X[0, 0] * X[2, 1]
    c20 = X[0, 1] * X[1, 2] - X[0, 2] * X[1, 1]
    c21 = X[0, 2] * X[1, 0] - X[0, 0] * X[1, 2]
    c22 = X[0, 0] * X[1, 1] - X[0, 1] * X[1, 0]
    det = X[0, 0] * c00 + X[0, 1] * c01 + X[0, 2] * c02
    Y[0, 0], Y[0, 1], Y[0, 2] = c00 / det, c01 / det, c02 / det
    Y[1, 0], Y[1, 1], Y[1, 2] = c10 / det, c11 / det, c12 / det
    Y[2, 0], Y[2, 1], Y[2, 2] = c20 / det, c21 / det, c22 / det
    return det


@jit
def _orthonormalise(C, Y):
    """``C`` <- its nearest rotation (polar factor), by Newton's iteration."""
    for _ in range(20):
        _inverse_transpose(C, Y)
        change = 0.0
        for i in range(3):
            for j in range(3):
                new = 0.5 * (C[i, j] + Y[i, j])
                change = max(change, abs(new - C[i, j]))
                C[i, j] = new
        if change < 1e-15:
            return


@jit
def _accel_eq13(w0, w1, w2, C, u0, u1, u2, k, g):
    """Least-squares ``(b_ax, b_ay)`` from eq. (13) (``accelcal.tereshkov.estimator._accel_eq13``)."""
    kg = k * g
    # inverse of S(w) + kg I
    Sm = np.empty((3, 3))
    Sm[0, 0], Sm[0, 1], Sm[0, 2] = kg, -w2, w1
    Sm[1, 0], Sm[1, 1], Sm[1, 2] = w2, kg, -w0
    Sm[2, 0], Sm[2, 1], Sm[2, 2] = -w1, w0, kg
    Inv = np.empty((3, 3))
    _inverse_transpose(Sm, Inv)  # Inv = (S + kgI)⁻ᵀ: use its transpose below
    S = ((0.0, -w2, w1), (w2, 0.0, -w0), (-w1, w0, 0.0))
    W = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            W[i, j] = S[i][0] * Inv[j, 0] + S[i][1] * Inv[j, 1] + S[i][2] * Inv[j, 2]
    kb0, kb1, kb2 = -k * C[2, 0], -k * C[2, 1], -k * C[2, 2]
    Kb = ((0.0, -kb2, kb1), (kb2, 0.0, -kb0), (-kb1, kb0, 0.0))
    A = np.empty((3, 2))
    for i in range(3):
        for j in range(2):
            A[i, j] = W[i, 0] * Kb[0][j] + W[i, 1] * Kb[1][j] + W[i, 2] * Kb[2][j]
    a00 = A[0, 0] * A[0, 0] + A[1, 0] * A[1, 0] + A[2, 0] * A[2, 0]
    a01 = A[0, 0] * A[0, 1] + A[1, 0] * A[1, 1] + A[2, 0] * A[2, 1]
    a11 = A[0, 1] * A[0, 1] + A[1, 1] * A[1, 1] + A[2, 1] * A[2, 1]
    b0 = A[0, 0] * u0 + A[1, 0] * u1 + A[2, 0] * u2
    b1 = A[0, 1] * u0 + A[1, 1] * u1 + A[2, 1] * u2
    det = a00 * a11 - a01 * a01
    if not abs(det) > 1e-30:
        det = 1e-30
    return (a11 * b0 - a01 * b1) / det, (a00 * b1 - a01 * b0) / det


@jit
def run(gyro, accel, f_ext, course, moving, dt, k, g, tau, kh, cg, ca, aw, thr_s, thr_t, settle_s, settle_t, ng,
        feedback, eq13, update_gyro, update_accel, k0, renormalise_every,
        C, bg, ba, wzf, mode, mtime, gtime, atime,
        record, out_bg, out_ba, out_u, out_mode, out_C, out_mt, out_gt, out_at):
    """Every run ``r`` of ``gyro``, ``accel``, ``f_ext`` (R, n, 3), ``course``,
    ``moving`` (R, n) through the estimator from its state (``C`` (R, 3, 3), ``bg``,
    ``ba`` (R, 3), ``wzf``, ``mode``, ``mtime``, ``gtime``, ``atime`` (R,), updated in
    place); at the local sample indices ``record`` (m,) the state before the step goes
    to ``out_*`` (R, m, ...).  ``k0``: global index of the first sample."""
    Y = np.empty((3, 3))
    CA = np.empty((3, 3))
    Cr = np.empty((3, 3))
    twopi = 2.0 * math.pi
    for r in range(gyro.shape[0]):
        for i in range(3):
            for j in range(3):
                Cr[i, j] = C[r, i, j]
        bg0, bg1, bg2 = bg[r, 0], bg[r, 1], bg[r, 2]
        ba0, ba1 = ba[r, 0], ba[r, 1]
        ba2 = ba[r, 2]
        wz, md, mt, gt, at = wzf[r], mode[r], mtime[r], gtime[r], atime[r]
        j_rec = 0
        for i in range(gyro.shape[1]):
            w0, w1, w2 = gyro[r, i, 0] - bg0, gyro[r, i, 1] - bg1, gyro[r, i, 2] - bg2
            if feedback:
                f0, f1, f2 = accel[r, i, 0] - ba0, accel[r, i, 1] - ba1, accel[r, i, 2] - ba2
            else:
                f0, f1, f2 = accel[r, i, 0], accel[r, i, 1], accel[r, i, 2]
            fp0 = Cr[0, 0] * f0 + Cr[0, 1] * f1 + Cr[0, 2] * f2
            fp1 = Cr[1, 0] * f0 + Cr[1, 1] * f1 + Cr[1, 2] * f2
            d0, d1 = f_ext[r, i, 0] - fp0, f_ext[r, i, 1] - fp1
            herr = math.atan2(Cr[1, 0], Cr[0, 0]) - course[r, i]
            herr = (herr + math.pi) % twopi - math.pi
            mov = moving[r, i]
            p0, p1 = -k * d1, k * d0
            p2 = kh * herr if mov else 0.0
            u0 = Cr[0, 0] * p0 + Cr[1, 0] * p1 + Cr[2, 0] * p2
            u1 = Cr[0, 1] * p0 + Cr[1, 1] * p1 + Cr[2, 1] * p2
            u2 = Cr[0, 2] * p0 + Cr[1, 2] * p1 + Cr[2, 2] * p2
            if j_rec < record.shape[0] and record[j_rec] == i:
                out_bg[r, j_rec, 0], out_bg[r, j_rec, 1], out_bg[r, j_rec, 2] = bg0, bg1, bg2
                out_ba[r, j_rec, 0], out_ba[r, j_rec, 1], out_ba[r, j_rec, 2] = ba0, ba1, ba2
                out_u[r, j_rec, 0], out_u[r, j_rec, 1], out_u[r, j_rec, 2] = u0, u1, u2
                out_mode[r, j_rec] = md
                out_mt[r, j_rec], out_gt[r, j_rec], out_at[r, j_rec] = mt, gt, at
                for a in range(3):
                    for b in range(3):
                        out_C[r, j_rec, a, b] = Cr[a, b]
                j_rec += 1
            # gating on the low-passed compensated body z rate
            wz += aw * (w2 - wz)
            awz = abs(wz)
            straight = mov and awz < thr_s
            turn = mov and awz > thr_t
            new_mode = STRAIGHT if straight else (TURN if turn else OTHER)
            mt = mt + dt if new_mode == md else 0.0
            md = new_mode
            if straight and mt >= settle_s and update_gyro:  # (12) through the low-pass filter
                bg0 += cg * u0
                bg1 += cg * u1
                if ng == 3:
                    bg2 += cg * u2
                gt += dt
            if turn and mt >= settle_t and update_accel:
                if eq13:
                    e0, e1 = _accel_eq13(w0, w1, w2, Cr, u0, u1, u2, k, g)
                else:  # (14)
                    inv = 1.0 / wz
                    e0, e1 = g * (u0 * inv - tau * u1), g * (tau * u0 + u1 * inv)
                if not feedback:
                    e0, e1 = e0 - ba0, e1 - ba1
                ba0 += ca * e0
                ba1 += ca * e1
                at += dt
            # (1): C <- C + s CA + c CA A (body, 4th order), then C <- C + P C (platform)
            a0, a1, a2 = w0 * dt, w1 * dt, w2 * dt
            th2 = a0 * a0 + a1 * a1 + a2 * a2
            s = 1 - th2 * (1 / 6 - th2 / 120)
            c = 0.5 - th2 * (1 / 24 - th2 / 720)
            for a in range(3):
                CA[a, 0] = Cr[a, 1] * a2 + Cr[a, 2] * (-a1)
                CA[a, 1] = Cr[a, 0] * (-a2) + Cr[a, 2] * a0
                CA[a, 2] = Cr[a, 0] * a1 + Cr[a, 1] * (-a0)
            for a in range(3):
                x0 = CA[a, 1] * a2 + CA[a, 2] * (-a1)
                x1 = CA[a, 0] * (-a2) + CA[a, 2] * a0
                x2 = CA[a, 0] * a1 + CA[a, 1] * (-a0)
                Cr[a, 0] = Cr[a, 0] + s * CA[a, 0] + c * x0
                Cr[a, 1] = Cr[a, 1] + s * CA[a, 1] + c * x1
                Cr[a, 2] = Cr[a, 2] + s * CA[a, 2] + c * x2
            q0, q1, q2 = -p0 * dt, -p1 * dt, -p2 * dt
            for b in range(3):
                c0, c1, c2 = Cr[0, b], Cr[1, b], Cr[2, b]
                Cr[0, b] = c0 + (-q2 * c1 + q1 * c2)
                Cr[1, b] = c1 + (q2 * c0 - q0 * c2)
                Cr[2, b] = c2 + (-q1 * c0 + q0 * c1)
            if (k0 + i + 1) % renormalise_every == 0:
                _orthonormalise(Cr, Y)
        for i in range(3):
            for j in range(3):
                C[r, i, j] = Cr[i, j]
        bg[r, 0], bg[r, 1], bg[r, 2] = bg0, bg1, bg2
        ba[r, 0], ba[r, 1] = ba0, ba1
        wzf[r], mode[r], mtime[r], gtime[r], atime[r] = wz, md, mt, gt, at
