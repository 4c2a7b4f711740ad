"""Compiled step loops of the Batista et al. (2011) Kalman filter (:mod:`accelcal.batista.filter`).

The same discretisation and update as the numpy reference (closed-form ``Φ``, ``G0``,
``G1`` and ``Q`` per step from the midpoint rate, Joseph-form update), as scalar loops
compiled by numba (:mod:`accelcal.kernels`): no 9x9 temporary arrays, the block
structure of ``Φ`` and of ``I - K C`` used instead of dense products.

Imported only through :func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import jit

_SERIES_BELOW = 0.02  # as accelcal.batista.filter


@jit
def _coefficients(th, c):
    """Rodrigues-type coefficients (a, b, c, d, e) of θ into ``c`` (series for small θ)."""
    if th < _SERIES_BELOW:
        t2 = th * th
        c[0] = 1.0 + t2 * (-1 / 6 + t2 * (1 / 120 + t2 * (-1 / 5040)))
        c[1] = 0.5 + t2 * (-1 / 24 + t2 * (1 / 720 + t2 * (-1 / 40320)))
        c[2] = 1 / 6 + t2 * (-1 / 120 + t2 * (1 / 5040 + t2 * (-1 / 362880)))
        c[3] = 1 / 3 + t2 * (-1 / 30 + t2 * (1 / 840 + t2 * (-1 / 45360)))
        c[4] = 0.125 + t2 * (-1 / 144 + t2 * (1 / 5760 + t2 * (-1 / 403200)))
    else:
        s, co = math.sin(th), math.cos(th)
        c[0] = s / th
        c[1] = (1 - co) / th**2
        c[2] = (th - s) / th**3
        c[3] = (s - th * co) / th**3
        c[4] = (0.5 - (co + th * s - 1) / th**2) / th**2


@jit
def rotation_blocks(wx, wy, wz, dt, E, J0, J1, coef):
    """``E``, ``J0``, ``J1`` of :func:`accelcal.batista.filter.rotation_blocks` for one ω."""
    a0, a1, a2 = wx * dt, wy * dt, wz * dt
    th2 = a0 * a0 + a1 * a1 + a2 * a2
    _coefficients(math.sqrt(th2), coef)
    a, b, c, d, e = coef[0], coef[1], coef[2], coef[3], coef[4]
    # K = S(w dt), K2 = w wᵀ - |w|² I
    K = ((0.0, -a2, a1), (a2, 0.0, -a0), (-a1, a0, 0.0))
    w = (a0, a1, a2)
    for i in range(3):
        for j in range(3):
            k2 = w[i] * w[j] - (th2 if i == j else 0.0)
            eye = 1.0 if i == j else 0.0
            E[i, j] = eye - a * K[i][j] + b * k2
            J0[i, j] = dt * (eye - b * K[i][j] + c * k2)
            J1[i, j] = dt * dt * (0.5 * eye - d * K[i][j] + e * k2)


@jit
def _step_model(wx, wy, wz, dt, qv, qg, qb, E, J0, J1, Q, coef):
    """``E``, ``J0``, ``J1`` and the process noise ``Q`` (9x9, :func:`process_noise`) of one step."""
    rotation_blocks(wx, wy, wz, dt, E, J0, J1, coef)
    for i in range(9):
        for j in range(9):
            Q[i, j] = 0.0
    # S² = w wᵀ - |w|² I for S = S(ω)
    w = (wx, wy, wz)
    n2 = wx * wx + wy * wy + wz * wz
    dvv = qv * dt + (qg + qb) * dt**3 / 3
    c5 = qb * dt**5 / 60
    for i in range(3):
        for j in range(3):
            s2 = w[i] * w[j] - (n2 if i == j else 0.0)
            Q[i, j] = (dvv if i == j else 0.0) + c5 * s2
            vb = -qb * (dt * J0[i, j] - J1[i, j])
            Q[i, 6 + j] = vb
            Q[6 + j, i] = vb
        Q[i, 3 + i] = qg * dt**2 / 2
        Q[3 + i, i] = qg * dt**2 / 2
        Q[3 + i, 3 + i] = qg * dt
        Q[6 + i, 6 + i] = qb * dt


@jit
def _propagate_covariance(P, E, J0, Q, dt, T):
    """``P <- Φ P Φᵀ + Q`` with ``Φ = [[E, dt E, -J0], [0, E, 0], [0, 0, I]]``."""
    # T = Φ P (rows: block rows of Φ)
    for j in range(9):
        for i in range(3):
            s = 0.0
            for m in range(3):
                s += E[i, m] * P[m, j] + dt * E[i, m] * P[3 + m, j] - J0[i, m] * P[6 + m, j]
            T[i, j] = s
            s = 0.0
            for m in range(3):
                s += E[i, m] * P[3 + m, j]
            T[3 + i, j] = s
            T[6 + i, j] = P[6 + i, j]
    # P = T Φᵀ + Q
    for i in range(9):
        for k in range(3):
            s = 0.0
            for m in range(3):
                s += T[i, m] * E[k, m] + T[i, 3 + m] * dt * E[k, m] - T[i, 6 + m] * J0[k, m]
            P[i, k] = s + Q[i, k]
            s = 0.0
            for m in range(3):
                s += T[i, 3 + m] * E[k, m]
            P[i, 3 + k] = s + Q[i, 3 + k]
            P[i, 6 + k] = T[i, 6 + k] + Q[i, 6 + k]


@jit
def _update(P, Rd, K, T):
    """Gain ``K = P Cᵀ (C P Cᵀ + Rd)⁻¹`` (9x3) and the Joseph update of ``P``."""
    # S = P[:3, :3] + Rd; K[i] = S⁻¹ P[:3, i] (S symmetric): inverse by the adjugate
    s00, s01, s02 = P[0, 0] + Rd[0, 0], P[0, 1] + Rd[0, 1], P[0, 2] + Rd[0, 2]
    s10, s11, s12 = P[1, 0] + Rd[1, 0], P[1, 1] + Rd[1, 1], P[1, 2] + Rd[1, 2]
    s20, s21, s22 = P[2, 0] + Rd[2, 0], P[2, 1] + Rd[2, 1], P[2, 2] + Rd[2, 2]
    c00, c01, c02 = s11 * s22 - s12 * s21, s02 * s21 - s01 * s22, s01 * s12 - s02 * s11
    c10, c11, c12 = s12 * s20 - s10 * s22, s00 * s22 - s02 * s20, s02 * s10 - s00 * s12
    c20, c21, c22 = s10 * s21 - s11 * s20, s01 * s20 - s00 * s21, s00 * s11 - s01 * s10
    det = s00 * c00 + s01 * c10 + s02 * c20
    for i in range(9):
        p0, p1, p2 = P[0, i], P[1, i], P[2, i]
        K[i, 0] = (c00 * p0 + c01 * p1 + c02 * p2) / det
        K[i, 1] = (c10 * p0 + c11 * p1 + c12 * p2) / det
        K[i, 2] = (c20 * p0 + c21 * p1 + c22 * p2) / det
    # T = (I - K C) P: row i minus K[i] times the first three rows
    for i in range(9):
        for j in range(9):
            T[i, j] = P[i, j] - K[i, 0] * P[0, j] - K[i, 1] * P[1, j] - K[i, 2] * P[2, j]
    # P = T (I - K C)ᵀ + K Rd Kᵀ
    for i in range(9):
        kr0 = K[i, 0] * Rd[0, 0] + K[i, 1] * Rd[1, 0] + K[i, 2] * Rd[2, 0]
        kr1 = K[i, 0] * Rd[0, 1] + K[i, 1] * Rd[1, 1] + K[i, 2] * Rd[2, 1]
        kr2 = K[i, 0] * Rd[0, 2] + K[i, 1] * Rd[1, 2] + K[i, 2] * Rd[2, 2]
        for k in range(9):
            P[i, k] = (T[i, k] - T[i, 0] * K[k, 0] - T[i, 1] * K[k, 1] - T[i, 2] * K[k, 2]
                       + kr0 * K[k, 0] + kr1 * K[k, 1] + kr2 * K[k, 2])


@jit
def kalman_filter(dt, a, w, y, x, P, Rd, qv, qg, qb, keep, xs, ss):
    """The filter of :func:`accelcal.batista.filter.kalman_filter` over samples ``a``,
    ``w``, ``y`` (n, 3), from ``x`` (9,) and ``P`` (9, 9) (both updated in place);
    ``keep`` (n,) bool: the samples whose estimate and ``sqrt(diag P)`` go to the next
    rows of ``xs`` and ``ss`` (row 0 is the initial state, written by the caller)."""
    E, J0, J1 = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    Q, T, K = np.empty((9, 9)), np.empty((9, 9)), np.empty((9, 3))
    coef = np.empty(5)
    xn = np.empty(9)
    row = 1
    for k in range(a.shape[0] - 1):
        _step_model(0.5 * (w[k + 1, 0] + w[k, 0]), 0.5 * (w[k + 1, 1] + w[k, 1]), 0.5 * (w[k + 1, 2] + w[k, 2]),
                    dt, qv, qg, qb, E, J0, J1, Q, coef)
        # x <- Φ x + G0 a_k + G1 a_{k+1}, G0 = J1/dt, G1 = J0 - J1/dt (velocity rows)
        for i in range(3):
            s = 0.0
            for m in range(3):
                s += (E[i, m] * x[m] + dt * E[i, m] * x[3 + m] - J0[i, m] * x[6 + m]
                      + J1[i, m] / dt * a[k, m] + (J0[i, m] - J1[i, m] / dt) * a[k + 1, m])
            xn[i] = s
            s = 0.0
            for m in range(3):
                s += E[i, m] * x[3 + m]
            xn[3 + i] = s
            xn[6 + i] = x[6 + i]
        _propagate_covariance(P, E, J0, Q, dt, T)
        _update(P, Rd, K, T)
        r0, r1, r2 = y[k + 1, 0] - xn[0], y[k + 1, 1] - xn[1], y[k + 1, 2] - xn[2]
        for i in range(9):
            x[i] = xn[i] + K[i, 0] * r0 + K[i, 1] * r1 + K[i, 2] * r2
        if keep[k + 1]:
            for i in range(9):
                xs[row, i] = x[i]
                ss[row, i] = math.sqrt(P[i, i])
            row += 1


@jit
def covariance_sequence(dt, w, P, Rd, qv, qg, qb, Ks, Ps):
    """Gains ``Ks`` (n, 9, 3) and posterior covariances ``Ps`` (n, 9, 9) of
    :func:`accelcal.batista.filter.covariance_sequence` along rates ``w`` (n, 3) from
    ``P`` (updated in place); ``Ks[0]`` and ``Ps[0]`` are set by the caller."""
    E, J0, J1 = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    Q, T, K = np.empty((9, 9)), np.empty((9, 9)), np.empty((9, 3))
    coef = np.empty(5)
    for k in range(w.shape[0] - 1):
        _step_model(0.5 * (w[k + 1, 0] + w[k, 0]), 0.5 * (w[k + 1, 1] + w[k, 1]), 0.5 * (w[k + 1, 2] + w[k, 2]),
                    dt, qv, qg, qb, E, J0, J1, Q, coef)
        _propagate_covariance(P, E, J0, Q, dt, T)
        _update(P, Rd, K, T)
        for i in range(9):
            for j in range(3):
                Ks[k + 1, i, j] = K[i, j]
            for j in range(9):
                Ps[k + 1, i, j] = P[i, j]
