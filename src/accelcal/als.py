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

import math

import numpy as np

from .errors import AccelcalError, NonFiniteError, NotPositiveDefiniteError
from .kernels import compiled
from .lls import (_KERNELS, EIGVEC_TOL, MIN_GAP, SAVES_S, _float_or_nan, _scale_single, _theta_to_model_single,
                  full_lls, normal_matrix)
from .results import BatchResult, LLSResult
from .validation import check_finite, check_g, pose_array

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
for _constant in (_T1, _T2):
    _constant.setflags(write=False)


def corrected_matrix_terms(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Ψ1, Ψ2)`` with ``Ψ(σ²) = N + σ² Ψ1 + σ⁴ Ψ2`` from ``N = XᵀX`` of the same poses:
    the ALS matrix at any σ² from the LLS normal matrix, without touching the poses."""
    return _T1.dot(N[9]), N[9, 9] * _T2


def _noise_var_from(N: np.ndarray) -> float:
    from scipy.optimize import brentq  # here: scipy.optimize costs 0.6 s to import

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
            raise NotPositiveDefiniteError(_NO_NOISE_LEVEL)
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

    Notes
    -----
    Speed: with numba installed (``ACCELCAL_KERNELS=auto``, the default) the calls of a
    process run in numpy (no numba start-up for a one-off calibration) until they would
    have saved, compiled, numba's start-up (about 9 000 calls of this function on 24
    poses; :mod:`accelcal.kernels`); that call loads the compiled kernels (about 0.5 s
    once, from numba's disk cache) and every later call runs compiled, about 4
    times faster.  ``ACCELCAL_KERNELS=numba`` or ``numpy`` forces either path from the
    first call; the two agree to rounding.
    """
    # the LLS it corrects validates z and g and raises the same errors (degenerate poses,
    # no ellipsoid) as the LLS would
    lls = full_lls(z, g)
    K = compiled(_KERNELS, single=True, saves_s=SAVES_S["full_als"])
    if K is not None:
        return _full_als_compiled(K, lls.poses, lls.g, noise_std)
    return _full_als_numpy(lls.poses, lls.g, noise_std)


def _full_als_numpy(z, g, noise_std) -> LLSResult:
    """:func:`full_als` in numpy (``eigvalsh`` + ``brentq`` for σ², ``eigh`` for Θ̂)."""
    k = _scale_single(z)
    N = normal_matrix(z, k)  # Ψ(0): the moment matrix of the LLS, of z / k
    var = _noise_var_from(N) if noise_std is None else (float(noise_std) / k) ** 2
    P1, P2 = corrected_matrix_terms(N)
    w, V = np.linalg.eigh(N + var * P1 + (var * var) * P2)
    b, M, lam, valid = _theta_to_model_single(V[:, 0], g / k)
    if not valid:
        raise NotPositiveDefiniteError(_NO_ELLIPSOID)
    return LLSResult._trusted(method="full_als", bias=np.array(b) * k, M=M, g=g, poses=z, lam=lam,
                              c=float("nan"), noise_var=var * k * k, singular_values=np.sqrt(np.abs(w)))


def _full_als_compiled(K, z, g, noise_std) -> LLSResult:
    """:func:`full_als` by the compiled kernel (Jacobi eigenvalues, the same Brent search)."""
    if not z.flags.c_contiguous:
        z = np.ascontiguousarray(z)
    out, ev = np.empty(14), np.empty(10)
    status = K.full_als(z, g, math.nan if noise_std is None else float(noise_std), _T1, _T2, out, ev)
    if status == K.REFERENCE:
        return _full_als_numpy(z, g, noise_std)
    if status == K.NO_NOISE_LEVEL:
        raise NotPositiveDefiniteError(_NO_NOISE_LEVEL)
    if status == K.NO_ELLIPSOID:
        raise NotPositiveDefiniteError(_NO_ELLIPSOID)
    return LLSResult._trusted(method="full_als", bias=out[:3], M=out[3:12].reshape(3, 3), g=g, poses=z,
                              lam=float(out[12]), c=math.nan, noise_var=float(out[13]),
                              singular_values=np.sqrt(np.abs(ev)))


_NO_ELLIPSOID = "ALS gives no ellipsoid (Ŝ not positive definite or λ <= 0)"
_NO_NOISE_LEVEL = "ALS finds no noise level that makes the moments singular"


def full_als_batch(z, g: float, noise_std: float | None = None) -> BatchResult:
    """:func:`full_als` over trials ``z`` (T, n, 3); a trial whose ALS (or the LLS it
    corrects) fails is marked ``valid=False``, NaN, with the name of the error it raised
    in ``status`` (``'ok'`` otherwise).

    The compiled kernel runs every trial in one loop; trials it cannot decide (the LLS
    needs the SVD, Brent's method did not converge) and the numpy backend run
    :func:`full_als` one by one.
    """
    z = pose_array(z, "full", batched=True)
    K = compiled(_KERNELS)
    T = len(z)
    bias, M = np.full((T, 3), np.nan), np.full((T, 3, 3), np.nan)
    status = np.full(T, "ok", dtype=object)
    if K is None:
        check_finite(z)
        check_g(g)
        single = range(T)
    else:
        z = np.ascontiguousarray(z)
        code = np.empty(T, np.int8)
        K.full_als_batch(z, _float_or_nan(g), math.nan if noise_std is None else float(noise_std), _T1, _T2,
                         MIN_GAP, EIGVEC_TOL, bias, M, code)
        if (code == K.NON_FINITE).any():
            raise NonFiniteError("pose measurements contain NaN or infinite values")
        check_g(g)
        status[(code == K.NO_ELLIPSOID) | (code == K.ALS_NO_ELLIPSOID) | (code == K.NO_NOISE_LEVEL)] = \
            NotPositiveDefiniteError.__name__
        single = np.flatnonzero(code == K.REFERENCE)
    for t in single:
        try:
            r = full_als(z[t], g, noise_std)
        except AccelcalError as e:
            status[t] = type(e).__name__
            continue
        bias[t], M[t] = r.bias, r.M
    valid = status == "ok"
    return BatchResult(method="full_als", bias=bias, M=M, valid=valid.astype(bool), status=status.astype(str))


def moment_singular_values(poses: np.ndarray, noise_var: float) -> np.ndarray:
    """``sqrt(|eigenvalues|)`` of the ALS matrix Ψ(σ²) of the scaled poses (ascending),
    the ``singular_values`` of an ALS result (``noise_var`` in input units squared)."""
    k = _scale_single(poses)
    return np.sqrt(np.abs(np.linalg.eigvalsh(corrected_moments(poses / k, noise_var / (k * k)))))
