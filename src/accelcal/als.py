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
``Ψ(σ²)``, a quadratic polynomial in σ² whose constant term is the LLS normal matrix
``XᵀX`` (:func:`corrected_matrix_terms`; :func:`corrected_moments` is the definition).
When σ² is unknown it is estimated as the root of ``λ_min(Ψ(σ²)) = 0`` (the
noise-free moment matrix is singular), as in Kukush et al.  The rest (b, λ, M)
follows eqs. (4)-(6) exactly as for the full LLS.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .errors import NotPositiveDefiniteError
from .lls import _scale_single, _theta_to_model_single, full_lls, normal_matrix
from .results import LLSResult

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


def _correction_terms() -> tuple[np.ndarray, np.ndarray]:
    """Constant tensors with ``Ψ(σ²) = N + σ² (T1 · m) + σ⁴ n T2``, ``N = XᵀX`` and ``m =
    N[9]`` (the column sums of X: every monomial of degree <= 2, times its coefficient).

    Expanding ``h_k(t) = t^k - C(k,2) σ² t^(k-2) + 3 C(k,4) σ⁴ t^(k-4)`` in the product
    ``h_a(x) h_b(y) h_c(z)`` (a + b + c <= 4): the σ² terms are monomials of degree <= 2,
    the σ⁴ terms constants.
    """
    def c2(k):
        return k * (k - 1) // 2

    mono = {tuple(e): j for j, e in enumerate(_EXP.tolist())}  # exponents -> column of X
    T1 = np.zeros((10, 10, 10))
    T2 = np.zeros((10, 10))
    for j in range(10):
        for l in range(10):
            e = _PAIR_EXP[j, l]
            K = _PAIR_COEF[j, l]
            for axis in range(3):  # σ² terms: one axis lowered by 2
                if e[axis] >= 2:
                    low = e.copy()
                    low[axis] -= 2
                    jj = mono[tuple(low)]
                    T1[j, l, jj] -= K * c2(e[axis]) / _COEF[jj]
            # σ⁴ terms: 3 C(k, 4) on one axis, or C(a, 2) C(b, 2) on two axes (degree 0 left)
            quartic = sum(3 * (e[a] == 4) for a in range(3))
            pairs = sum(c2(e[a]) * c2(e[b]) for a, b in ((0, 1), (0, 2), (1, 2)))
            T2[j, l] = K * (quartic + pairs)
    return T1, T2


_T1, _T2 = _correction_terms()


def corrected_matrix_terms(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Ψ1, Ψ2)`` with ``Ψ(σ²) = N + σ² Ψ1 + σ⁴ Ψ2`` from ``N = XᵀX`` of the same poses:
    the ALS matrix at any σ² from the LLS normal matrix, without touching the poses."""
    return _T1.dot(N[9]), N[9, 9] * _T2


def estimate_noise_var(z: np.ndarray) -> float:
    """σ² at which ``Ψ(σ²)`` becomes singular (Kukush et al. 2004), for scaled data."""
    return _noise_var_from(normal_matrix(z, 1.0))


def _noise_var_from(N: np.ndarray) -> float:
    P1, P2 = corrected_matrix_terms(N)

    def lam_min(v):
        return np.linalg.eigvalsh(N + v * P1 + (v * v) * P2)[0]

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
    # the LLS it corrects validates z and g and raises the same errors (degenerate poses,
    # no ellipsoid) as the LLS would
    lls = full_lls(z, g)
    z, g = lls.poses, lls.g
    k = _scale_single(z)
    N = normal_matrix(z, k)  # Ψ(0): the moment matrix of the LLS, of z / k
    var = _noise_var_from(N) if noise_std is None else (float(noise_std) / k) ** 2
    P1, P2 = corrected_matrix_terms(N)
    w, V = np.linalg.eigh(N + var * P1 + (var * var) * P2)
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
