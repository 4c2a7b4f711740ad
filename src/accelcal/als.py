"""Adjusted least squares (ALS): a consistent version of the full LLS.

The full LLS of Burkhard et al. (2024) is the algebraic ellipsoid fit: it minimises
``||X Θ||`` where the rows of X hold products of the *noisy* measurements.  Because
``E[z_j²] = x_j² + σ²`` (and likewise for the cubic and quartic products in ``XᵀX``),
``XᵀX / n`` converges to the noise-free moment matrix plus a term in σ², and the
estimate is biased by O(σ²) however many poses are taken.  Kukush, Markovsky and Van
Huffel (2004, "Consistent least squares fitting of ellipsoids", Numer. Math. 98)
replace every monomial of ``XᵀX`` by an unbiased estimate of its noise-free value:
with independent noise of variance σ² on each axis, ``E[h_k(z)] = x^k`` for

    h0 = 1, h1 = z, h2 = z² - σ², h3 = z³ - 3σ²z, h4 = z⁴ - 6σ²z² + 3σ⁴,

and a monomial ``zx^a zy^b zz^c`` is replaced by ``h_a(zx) h_b(zy) h_c(zz)``.  The
estimate is the eigenvector of the smallest eigenvalue of the corrected matrix
``Ψ(σ²)``.  When σ² is unknown it is estimated as the root of ``λ_min(Ψ(σ²)) = 0``
(the noise-free moment matrix is singular), as in Kukush et al.  The rest (b, λ, M)
follows eqs. (4)-(6) exactly as for the full LLS.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .errors import NotPositiveDefiniteError
from .lls import _scale_single, _theta_to_model_single, full_lls
from .results import LLSResult
from .validation import check_g, check_poses

# Feature j of a row of X is COEF[j] * zx^E[j,0] zy^E[j,1] zz^E[j,2] (eq. 3 ordering).
_EXP = np.array([[2, 0, 0], [0, 2, 0], [0, 0, 2], [1, 1, 0], [1, 0, 1], [0, 1, 1],
                 [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]])
_COEF = np.array([1, 1, 1, 2, 2, 2, -2, -2, -2, 1], dtype=float)
_PAIR_EXP = _EXP[:, None, :] + _EXP[None, :, :]  # (10, 10, 3), degrees up to 4 per axis
_PAIR_COEF = _COEF[:, None] * _COEF[None, :]


def _hermite_powers(z: np.ndarray, var: float) -> np.ndarray:
    """``H[k, i, a] = h_k(z[i, a])`` for k = 0..4 (unbiased estimates of x^k)."""
    z2 = z * z
    return np.stack([np.ones_like(z), z, z2 - var, z2 * z - 3 * var * z,
                     z2 * z2 - 6 * var * z2 + 3 * var * var])


def corrected_moments(z: np.ndarray, var: float) -> np.ndarray:
    """``Ψ(σ²) = Σ_i E-corrected (x_i x_iᵀ)``: the 10x10 ALS matrix for poses ``z`` (n, 3)."""
    H = _hermite_powers(z, var)  # (5, n, 3)
    e = _PAIR_EXP
    prod = H[e[..., 0], :, 0] * H[e[..., 1], :, 1] * H[e[..., 2], :, 2]  # (10, 10, n)
    return _PAIR_COEF * prod.sum(axis=-1)


def estimate_noise_var(z: np.ndarray) -> float:
    """σ² at which ``Ψ(σ²)`` becomes singular (Kukush et al. 2004), for scaled data."""
    def lam_min(v):
        return np.linalg.eigvalsh(corrected_moments(z, v))[0]

    f0 = lam_min(0.0)
    if f0 <= 0:
        return 0.0
    hi = 1e-6
    while lam_min(hi) > 0:
        hi *= 4
        if hi > 1.0:  # scaled data have |z| ~ 1: a noise std of 1 g is no calibration
            raise NotPositiveDefiniteError("ALS finds no noise level that makes the moments singular")
    return brentq(lam_min, 0.0, hi, xtol=1e-16, rtol=1e-12)


def full_als(z, g: float, noise_std: float | None = None) -> LLSResult:
    """Full model by adjusted least squares: the full LLS with its O(σ²) bias removed.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means, ``n >= 10``.
    g : float
        Gravity magnitude in the unit of ``z``.
    noise_std : float, optional
        Per-axis noise std of the pose means (same unit as ``z``).  If omitted it is
        estimated from the data (consistent as the number of poses grows; with few
        poses the estimate is itself noisy, so pass a known value when you have one,
        e.g. from :func:`accelcal.static.detect_static`).

    Returns
    -------
    LLSResult
        ``noise_var`` holds the σ² corrected for, in the unit of ``z`` squared.
    """
    z = check_poses(z, "full")
    g = check_g(g)
    full_lls(z, g)  # same degeneracy checks and errors as the LLS it corrects
    k = _scale_single(z)
    zs = z / k
    var = estimate_noise_var(zs) if noise_std is None else (float(noise_std) / k) ** 2
    w, V = np.linalg.eigh(corrected_moments(zs, var))
    b, M, lam, valid = _theta_to_model_single(V[:, 0], g / k)
    if not valid:
        raise NotPositiveDefiniteError("ALS gives no ellipsoid (Ŝ not positive definite or λ <= 0)")
    return LLSResult._trusted(method="full_als", bias=np.array(b) * k, M=M, g=g, poses=z, lam=lam,
                              c=float("nan"), noise_var=var * k * k, singular_values=np.sqrt(np.abs(w)))


def moment_singular_values(poses: np.ndarray, noise_var: float) -> np.ndarray:
    """``sqrt(|eigenvalues|)`` of the ALS matrix Ψ(σ²) of the scaled poses (ascending),
    the ``singular_values`` of an ALS result (``noise_var`` in input units squared)."""
    k = _scale_single(poses)
    return np.sqrt(np.abs(np.linalg.eigvalsh(corrected_moments(poses / k, noise_var / (k * k)))))
