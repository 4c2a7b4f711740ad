"""Cramér–Rao bound of the table calibration of Batista et al. (2011) for a given design.

Measurement model (eq. 2 at rest, white noise of std ``σ`` on every axis)::

    a_m,i = μ_k(p) + n_i,   μ_k(p) = F (-g_k + F2 g_k² + b'),   g_k = R_kᵀ ᵀg

for every sample ``i`` of static window ``k``, with parameters
``p = (F⁻¹ (9, row-major), b' (3), f2 (3), ᵀg (3))`` (the order of
:data:`accelcal.batista.calibration.PARAMETERS`).  The Fisher information is
``Σ_k n_k J_kᵀ J_k / σ²`` with ``J_k = ∂μ_k/∂p`` (computed by complex-step
differentiation: exact to rounding).  Gravity is constrained to the known magnitude,
``|ᵀg| = g``, so the bound is the constrained CRLB (Gorman & Hero 1990)::

    CRLB = U (Uᵀ I U)⁻¹ Uᵀ,  U an orthonormal basis of the null space of ∂|ᵀg|²/∂p.

Derived quantities (the bias ``b = F b'`` and the lower-triangular ``M`` with
``M Mᵀ = F Fᵀ``, the parametrisation of the full LLS) get the bound ``D CRLB Dᵀ`` with
``D`` their Jacobian (central differences).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DegeneratePosesError
from .calibration import PARAMETERS

#: Names of the derived quantities of :func:`derived_quantities`.
DERIVED = tuple([f"b_{a}" for a in "xyz"] + ["M_11", "M_21", "M_22", "M_31", "M_32", "M_33"])
_LOWER = ([0, 1, 1, 2, 2, 2], [0, 0, 1, 0, 1, 2])


def pack(F_inv, b_prime, f2, g_table) -> np.ndarray:
    """Parameter vector in the order of :data:`PARAMETERS`."""
    return np.concatenate([np.asarray(F_inv, float).ravel(), np.asarray(b_prime, float),
                           np.asarray(f2, float), np.asarray(g_table, float)])


def window_means(p, R_steps) -> np.ndarray:
    """Noise-free measurement of every window, ``μ_k(p)``, shape (K, 3) (complex-safe)."""
    p = np.asarray(p)
    F = np.linalg.inv(p[:9].reshape(3, 3))
    gk = np.einsum("kji,j->ki", np.asarray(R_steps, float), p[15:18])
    u = -gk + p[12:15] * gk * gk + p[9:12]
    return u @ F.T


def window_jacobian(p, R_steps) -> np.ndarray:
    """``∂μ_k/∂p`` by complex step, shape (K, 3, 18)."""
    p = np.asarray(p, float)
    h = 1e-30
    cols = []
    for j in range(len(p)):
        dp = p.astype(complex)
        dp[j] += 1j * h
        cols.append(window_means(dp, R_steps).imag / h)
    return np.stack(cols, axis=-1)


@dataclass(frozen=True)
class CalibrationBound:
    """Constrained CRLB on the 18 calibration parameters (and the derived ``b``, ``M``)."""

    parameters: tuple[str, ...]
    cov: np.ndarray  # (18, 18)
    derived: tuple[str, ...]
    derived_cov: np.ndarray  # (9, 9)
    fisher: np.ndarray  # (18, 18), unconstrained

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.cov), 0, None))

    @property
    def derived_std(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.derived_cov), 0, None))

    def as_dict(self) -> dict[str, float]:
        """Bound on the standard deviation of every parameter and derived quantity."""
        return dict(zip(self.parameters + self.derived, np.concatenate([self.std, self.derived_std])))


def derived_quantities(p) -> np.ndarray:
    """``(b = F b', lower-triangular M with M Mᵀ = F Fᵀ)`` as a 9-vector (order :data:`DERIVED`)."""
    p = np.asarray(p, float)
    F = np.linalg.inv(p[:9].reshape(3, 3))
    M = np.linalg.cholesky(F @ F.T)
    return np.concatenate([F @ p[9:12], M[_LOWER]])


def calibration_crlb(F_inv, b_prime, f2, g_table, R_steps, counts, noise_std: float,
                     estimate_f2: bool = True) -> CalibrationBound:
    """Constrained CRLB of Table I's parameters for a design of static windows.

    Parameters
    ----------
    F_inv, b_prime, f2, g_table
        True parameters (as in :func:`accelcal.batista.model.accelerometer_output`).
    R_steps : array_like, shape (K, 3, 3)
        Body-to-table rotation of each static window.
    counts : array_like, shape (K,) or scalar
        Samples per window.
    noise_std : float
        Accelerometer noise std per axis and sample [m/s²].
    estimate_f2 : bool
        False treats ``f2`` as known (the model of Table I's steps 1-2): its rows and
        columns of the bound are zero.

    Returns
    -------
    CalibrationBound

    Raises
    ------
    DegeneratePosesError
        If the design leaves a parameter undetermined (singular constrained information).
    """
    p = pack(F_inv, b_prime, f2, g_table)
    R_steps = np.asarray(R_steps, float)
    n = np.broadcast_to(np.asarray(counts, float), (len(R_steps),))
    J = window_jacobian(p, R_steps)
    info = np.einsum("k,kip,kiq->pq", n, J, J) / noise_std**2
    c = np.zeros(len(p))
    c[15:18] = p[15:18]
    U = np.linalg.svd(c[None, :])[2][1:].T  # (18, 17) orthonormal basis of c⊥
    if not estimate_f2:  # restrict to directions that leave f2 fixed
        keep = np.ones(len(p), bool)
        keep[12:15] = False
        c_red = c[keep]
        U_red = np.linalg.svd(c_red[None, :])[2][1:].T
        U = np.zeros((len(p), U_red.shape[1]))
        U[keep] = U_red
    red = U.T @ info @ U
    ev = np.linalg.eigvalsh(red)
    if ev[0] <= 1e-12 * ev[-1]:
        raise DegeneratePosesError("the table rotations do not determine the calibration (singular Fisher information)")
    cov = U @ np.linalg.inv(red) @ U.T
    D = np.zeros((len(DERIVED), len(p)))
    for j in range(len(p)):
        h = 1e-6 * max(1.0, abs(p[j]))
        e = np.zeros(len(p))
        e[j] = h
        D[:, j] = (derived_quantities(p + e) - derived_quantities(p - e)) / (2 * h)
    return CalibrationBound(parameters=PARAMETERS, cov=cov, derived=DERIVED, derived_cov=D @ cov @ D.T,
                            fisher=info)


__all__ = ["DERIVED", "CalibrationBound", "calibration_crlb", "derived_quantities", "pack",
           "window_jacobian", "window_means"]
