"""The peers' magnetometer methods, each as its authors run it, returning a map raw -> field.

* Magneto 1.2 (Li & Griffiths 2004): :func:`accelcal.mag.fit.li_griffiths`, the same closed
  form; ``h = A (m - b)``, no alignment.
* Dorveaux et al. (2009) as tomisuarez2/MagnetometerCalibration runs it
  (``MagnetometerCalibrationModules/magnetometer_calibration.py``, commit eb93f82,
  ``calibrate_mag_from_data`` l. 113-186 and ``design_matrix_and_target`` l. 73-111): the
  samples after the initial rest, centred on their mean, then repeated linear least squares
  ``A_k y + B_k ≈ y / |y|`` on the partially calibrated data until the cost falls by less than
  ``tol`` (their test: tol 1e-4, 5000 iterations), composed into ``h = A m + B``.
* CK-Explorer (``Calibration MATLAB script/calibration_mag.m``, commit 6f2f3d2): Petrov's
  algebraic ellipsoid fit (``ellipsoid_fit_new``), a triangular ``n_o`` from it, then the
  rotation ``R`` and ``k`` minimising ``aᵀ R n_o (m - c) - |a| |n_o (m - c)| k`` over every
  sample (raw accelerometer), Levenberg-Marquardt from the identity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from accelcal.mag.fit import li_griffiths
from accelcal.mag.model import rotvec_to_matrix


@dataclass(frozen=True)
class PeerMap:
    """``h = L (m - c)`` (a peer's whole correction), and how many iterations it took."""

    L: np.ndarray
    c: np.ndarray
    iterations: int = 0

    def apply(self, m) -> np.ndarray:
        return (np.asarray(m, float) - self.c) @ self.L.T


def magneto(m) -> PeerMap:
    A, b = li_griffiths(m)
    return PeerMap(A, b)


def dorveaux(m, *, start: int = 0, tol: float = 1e-4, max_iter: int = 5000) -> PeerMap:
    """The author's loop (module docstring), on ``m[start:]``."""
    y = np.asarray(m, float)[start:]
    c = y.mean(axis=0)
    cal = y - c
    thetas, costs = [], []
    for k in range(max_iter):
        u = cal / np.linalg.norm(cal, axis=1, keepdims=True)
        # the author's (3n x 12) system is block diagonal: each axis's row is [y, 1] -> u_axis,
        # three 4-unknown least squares with one design (the same solution, ~50x faster)
        X = np.column_stack([cal, np.ones(len(cal))])
        sol, *_ = np.linalg.lstsq(X, u, rcond=None)
        theta = np.concatenate([sol[:3].T.ravel(), sol[3]])
        cost = float(np.sum((X @ sol - u) ** 2))
        if k > 0 and (costs[-1] - cost) / max(costs[-1], 1e-16) < tol:
            break
        thetas.append(theta)
        costs.append(cost)
        cal = cal @ theta[:9].reshape(3, 3).T + theta[9:]
    A = thetas[0][:9].reshape(3, 3)
    B = thetas[0][9:]
    for th in thetas[1:]:
        Ak = th[:9].reshape(3, 3)
        A, B = Ak @ A, Ak @ B + th[9:]
    B = A @ (-c) + B
    # h = A m + B = A (m - c') with c' = -A⁻¹ B
    return PeerMap(A, -np.linalg.solve(A, B), len(thetas))


def published_dorveaux(params) -> PeerMap:
    """The author's published 12 numbers (``paramters_mag.csv``): ``h = A m + B``."""
    p = np.asarray(params, float).ravel()
    A, B = p[:9].reshape(3, 3), p[9:]
    return PeerMap(A, -np.linalg.solve(A, B))


def petrov_ellipsoid(m) -> tuple[np.ndarray, np.ndarray]:
    """Yury Petrov's ``ellipsoid_fit_new`` (no constraints): centre and the 10 coefficients
    ``v`` of ``v1 x² + v2 y² + v3 z² + 2 v4 xy + 2 v5 xz + 2 v6 yz + 2 v7 x + 2 v8 y + 2 v9 z + v10 = 0``."""
    x, y, z = np.asarray(m, float).T
    D = np.column_stack([x * x + y * y - 2 * z * z, x * x + z * z - 2 * y * y, 2 * x * y, 2 * x * z, 2 * y * z,
                         2 * x, 2 * y, 2 * z, np.ones_like(x)])
    d2 = x * x + y * y + z * z
    u = np.linalg.solve(D.T @ D, D.T @ d2)
    v = np.empty(10)
    v[0] = u[0] + u[1] - 1
    v[1] = u[0] - 2 * u[1] - 1
    v[2] = u[1] - 2 * u[0] - 1
    v[3:] = u[2:]
    K = np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])
    centre = np.linalg.solve(-K, v[6:9])
    return centre, v


def ck_explorer(m, acc) -> PeerMap:
    """CK-Explorer's method (module docstring)."""
    c, v = petrov_ellipsoid(m)
    K = np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])
    v = v / (c @ K @ c - v[9])
    n = np.zeros((3, 3))
    n[2, 2] = np.sqrt(v[2])
    n[2, 1] = v[5] / n[2, 2]
    n[2, 0] = v[4] / n[2, 2]
    n[1, 1] = np.sqrt(v[1] - n[2, 1] ** 2)
    n[1, 0] = (v[3] - n[2, 1] * n[2, 0]) / n[1, 1]
    n[0, 0] = np.sqrt(v[0] - n[1, 0] ** 2 - n[2, 0] ** 2)
    mt = (np.asarray(m, float) - c) @ n.T
    a = np.asarray(acc, float)
    mag = np.linalg.norm(a, axis=1) * np.linalg.norm(mt, axis=1)

    def res(p):
        return np.einsum("ij,jk,ik->i", a, rotvec_to_matrix(p[:3]), mt) - mag * p[3]

    s = least_squares(res, np.zeros(4), method="lm")
    return PeerMap(rotvec_to_matrix(s.x[:3]) @ n, c, int(s.nfev))


__all__ = ["PeerMap", "ck_explorer", "dorveaux", "magneto", "petrov_ellipsoid", "published_dorveaux"]
