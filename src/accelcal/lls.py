"""Closed-form linear least squares of Burkhard et al. (2024): full LLS and bias-only LLS.

Full LLS (Sec. 1.1): every static pose gives one homogeneous linear equation
``z^T S z - 2 r^T z + d = 0`` in ``Θ = (S11, S22, S33, S12, S13, S23, r1, r2, r3, d)``
(eq. 3), solved up to scale by the right singular vector of the smallest singular
value; then ``b = Ŝ⁻¹ r̂`` (eq. 4, free of g), ``λ = g² / (bᵀŜb - d̂)`` (eq. 5),
``S = λ Ŝ = Aᵀ A`` by the reversed Cholesky and ``M = A⁻¹`` (eq. 6).

Bias-only LLS (Sec. 1.2, eq. 7): ``[2 z_iᵀ, 1] (b; c) = z_iᵀ z_i`` with
``c = g² - bᵀb``, ordinary least squares; ``b`` does not depend on g.

Numerics: the data are divided by ``k = sqrt(mean ||z||²)`` before the SVD so that
the columns of X (z², z, 1) have comparable size whatever the unit (m/s² or raw
counts); the model is invariant (``M`` unchanged, ``b`` and ``g`` scale by ``k``).

Speed (one problem).  The paper's point is that the closed forms are cheap; a 24x10
problem is a few microseconds of arithmetic, so each numpy/LAPACK call (about a
microsecond of overhead) counts.  :func:`full_lls` and :func:`bias_lls` therefore
compute the same estimate in fewer calls, and hand the problem to the reference
implementation (``_full_lls_svd``, ``_bias_lls_lstsq``: the SVD and ``lstsq`` forms,
which are also what the tests compare against) whenever the fast route cannot
certify its answer:

* full LLS: Θ̂ is the eigenvector of the smallest eigenvalue of ``N = XᵀX``, found by
  inverse iteration (Cholesky of the 10x10 N).  Forming N squares the condition of
  the eigenvector problem, so the fast route is taken only when it *proves* (i) that
  the second-smallest eigenvalue exceeds both ``NULLSPACE_RATIO²`` times the smallest
  and ``MIN_GAP`` times trace(N) (Cholesky of the leading 9x9 block of N shifted down
  by that bound; Cauchy interlacing), so that the null space is one-dimensional
  exactly when the SVD test says so and the squared conditioning costs at most a
  factor 1/MIN_GAP on the rounding error; and (ii) that the returned Θ̂ is within
  ``EIGVEC_TOL`` (angle) of that eigenvector (Davis–Kahan bound from the residual
  ``N Θ̂ - ρ Θ̂`` and the certified gap).  Differences to the SVD are ~1e-14 in practice.
  Problems that take the SVD: poses on a hemisphere only, raw counts whose offset is
  several times the gravity radius (σ0/σ8 in the thousands), ~10-12 random poses, noise
  above ~1e-2 g, and every degenerate or doubtful pose set (the SVD then raises).
* bias-only LLS: the least-squares problem of eq. (7) with the intercept c eliminated,
  i.e. the 3x3 normal equations of the centred poses (the scatter matrix the geometry
  check inspects anyway; moments taken about the first pose, so an offset far from the
  origin costs no precision), solved by Cholesky in scalar arithmetic.
* validation reads finiteness and geometry from the moments computed anyway
  (:mod:`accelcal.validation`); residuals, standard errors and singular values are
  computed on first access; results skip the frozen-dataclass ``__init__``.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import DegeneratePosesError, NotPositiveDefiniteError
from .kernels import compiled
from .model import lower_from_gram
from .results import LLSResult
from .validation import (check_g, check_poses, geometry_is_clearly_fine, pose_array,
                         scatter_is_clearly_3d)

#: The full system has a one-dimensional null space only if σ9 clearly exceeds σ10.
#: For a well-spread pose set σ9/σ10 is of order g/noise (10³ and more); for a pose set
#: that admits a second quadric (e.g. poses on two planes) σ9 sinks to the noise floor.
NULLSPACE_RATIO = 3.0

#: Fast route of the full LLS (see the module docstring): it requires the
#: second-smallest eigenvalue of N = XᵀX to exceed MIN_GAP * trace(N) (σ0/σ8 below
#: ~30; for 24 poses spread over the sphere σ0/σ8 is about 6, for 10 random poses often
#: more than 30 and they take the SVD), and its Θ̂ to be within EIGVEC_TOL of the
#: smallest eigenvector of N; otherwise the SVD decides and computes.
MIN_GAP = 1e-3
EIGVEC_TOL = 1e-11
#: Rounding of N x is below 10 eps trace(N) (N positive semi-definite, 10 terms):
#: added to the computed residual so that the Davis–Kahan bound holds in floating point.
_MATVEC_ROUNDING = 10 * np.finfo(float).eps
_CANCELLATION = 4 * math.sqrt(np.finfo(float).eps)
#: If N is singular to rounding (noise-free poses) the Cholesky is of N + δI with
#: δ = _SHIFT trace(N): same eigenvectors; inverse iteration slows by at most
#: _SHIFT / MIN_GAP = 1e-10 per step.
_SHIFT = 1e-13
#: Inverse iteration starts at the sphere |z/k| = 1 (b = 0, M = I, d = -1), close to
#: every plausible calibration; two solves per round, up to three rounds.
_START = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0])
_ROUNDS = 3

# Columns of X (eq. 3) as products (Z1 L) * (Z1 R) with Z1 = [z, 1]: L picks the first
# factor, R the second times the coefficient (zx², zy², zz², 2zx zy, 2zx zz, 2zy zz,
# -2zx, -2zy, -2zz, 1).  One nonzero per column: X equals design_matrix bit for bit.
_LEFT = np.zeros((4, 10))
_LEFT[[0, 1, 2, 0, 0, 1, 0, 1, 2, 3], range(10)] = 1.0
_RIGHT = np.zeros((4, 10))
_RIGHT[[0, 1, 2, 1, 2, 2, 3, 3, 3, 3], range(10)] = [1.0, 1.0, 1.0, 2.0, 2.0, 2.0, -2.0, -2.0, -2.0, 1.0]
_EYE3 = np.eye(3)
#: The compiled kernels of this module (:mod:`accelcal._lls_kernels`, via :func:`accelcal.kernels.compiled`).
_KERNELS = "_lls_kernels"
#: CPU time a compiled call saves over numpy [s] (24 poses, ``tools/bench_kernel_crossover.py``:
#: full LLS 37 -> 2.2 µs, bias-only LLS 11.1 -> 2.4 µs, ALS 75.6 -> 18.7 µs of which its
#: LLS is the full LLS's): what a single-problem call adds towards the switch to the
#: kernels under ``auto`` (:func:`accelcal.kernels.compiled`).
SAVES_S = {"full_lls": 35e-6, "bias_lls": 8.7e-6, "full_als": 22e-6}
_NON_FINITE = "pose measurements contain NaN or infinite values"
for _constant in (_START, _LEFT, _RIGHT, _EYE3):
    _constant.setflags(write=False)  # shared by every call (LAPACK gets copies)


def design_matrix(z: np.ndarray) -> np.ndarray:
    """Rows ``[zx², zy², zz², 2zx zy, 2zx zz, 2zy zz, -2zx, -2zy, -2zz, 1]`` (eq. 3), batched."""
    X = np.empty(z.shape[:-1] + (10,))
    X[..., 0:3] = z * z
    X[..., 3:5] = 2 * z[..., :1] * z[..., 1:]
    X[..., 5] = 2 * z[..., 1] * z[..., 2]
    X[..., 6:9] = -2 * z
    X[..., 9] = 1.0
    return X


def _scale(z: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("...ni,...ni->...", z, z) / z.shape[-2])


def _scale_single(z: np.ndarray) -> float:
    """``k = sqrt(mean ||z||²)`` of one problem; NaN/inf if ``z`` is not finite."""
    flat = z.ravel()
    return math.sqrt(flat.dot(flat) / len(z))


def normal_matrix(z: np.ndarray, k: float) -> np.ndarray:
    """``XᵀX`` (10x10) for the design matrix X of eq. (3) of the poses ``z / k`` (n, 3)."""
    Z1 = np.empty((len(z), 4))
    np.divide(z, k, out=Z1[:, :3])
    Z1[:, 3] = 1.0
    X = Z1.dot(_LEFT) * Z1.dot(_RIGHT)  # = design_matrix(z / k), bit for bit
    return X.T.dot(X)


def bias_design(z: np.ndarray) -> np.ndarray:
    """Rows ``[2 zx, 2 zy, 2 zz, 1]`` of eq. (7) for one problem."""
    return np.column_stack([2 * z, np.ones(len(z))])


def design_singular_values(model: str, poses: np.ndarray) -> np.ndarray:
    """Singular values of the scaled design of the full LLS (eq. 3) or of the bias-only
    LLS (eq. 7): the conditioning of the problem each estimate came from."""
    zs = poses / _scale_single(poses)
    X = design_matrix(zs) if model == "full" else bias_design(zs)
    return np.linalg.svd(X, compute_uv=False)


def theta_to_model(theta: np.ndarray, g_scaled):
    """Eqs. (4)-(6): ``Θ`` (…, 10) → (b, M, λ) in the scaled units; batched.

    Returns ``bias``, ``M``, ``lam`` and a boolean ``valid`` (Ŝ positive definite
    after fixing the sign of Θ, λ > 0, positive diagonal of A).  Invalid entries are NaN.
    """
    theta = np.array(theta, dtype=float)
    # Θ is defined up to sign: choose the sign that makes trace(Ŝ) positive.
    theta *= np.where(theta[..., :3].sum(axis=-1) < 0, -1.0, 1.0)[..., None]
    S = np.empty(theta.shape[:-1] + (3, 3))
    idx = [(0, 0, 0), (1, 1, 1), (2, 2, 2), (3, 0, 1), (4, 0, 2), (5, 1, 2)]
    for k, i, j in idx:
        S[..., i, j] = S[..., j, i] = theta[..., k]
    r = theta[..., 6:9]
    d = theta[..., 9]
    eig_min = np.linalg.eigvalsh(S)[..., 0]
    valid = eig_min > 0
    Ssafe = np.where(valid[..., None, None], S, np.eye(3))
    b = np.linalg.solve(Ssafe, r[..., None])[..., 0]  # eq. (4)
    quad = np.einsum("...i,...ij,...j->...", b, Ssafe, b) - d
    valid &= quad > 0
    lam = np.where(valid, g_scaled**2 / np.where(valid, quad, 1.0), np.nan)  # eq. (5)
    Sg = np.where(valid[..., None, None], lam[..., None, None] * Ssafe, np.eye(3))
    A = lower_from_gram(Sg)  # eq. (6); Sg is positive definite wherever valid
    M = np.linalg.inv(A)
    b = np.where(valid[..., None], b, np.nan)
    M = np.where(valid[..., None, None], M, np.nan)
    return b, M, lam, valid


def _theta_to_model_single(theta: np.ndarray, g_scaled: float):
    """:func:`theta_to_model` for one problem in scalar arithmetic (3x3 numpy calls cost
    more than the arithmetic).  Θ may have any sign and scale; b and M do not depend on
    them, λ is for the Θ given (λ |Θ| for the unit-norm Θ̂).

    Returns ``(b, M, λ, valid)`` with ``b`` a list of 3 floats and ``M`` a (3, 3) array
    (NaN and ``valid=False`` if the estimate is no ellipsoid)."""
    S11, S22, S33, S12, S13, S23, r1, r2, r3, d = theta.tolist()
    if S11 + S22 + S33 < 0:  # Θ is defined up to sign: make trace(Ŝ) positive
        S11, S22, S33, S12, S13, S23, r1, r2, r3, d = (-S11, -S22, -S33, -S12, -S13, -S23, -r1, -r2, -r3, -d)
    # Ŝ positive definite <=> leading principal minors positive (Sylvester).
    m2 = S11 * S22 - S12 * S12
    det = S11 * (S22 * S33 - S23 * S23) - S12 * (S12 * S33 - S23 * S13) + S13 * (S12 * S23 - S22 * S13)
    if S11 <= 0 or m2 <= 0 or det <= 0:
        return _no_ellipsoid()
    # b = Ŝ⁻¹ r̂ via the adjugate (eq. 4)
    c11, c22, c33 = S22 * S33 - S23 * S23, S11 * S33 - S13 * S13, m2
    c12, c13, c23 = S13 * S23 - S12 * S33, S12 * S23 - S13 * S22, S12 * S13 - S11 * S23
    b1 = (c11 * r1 + c12 * r2 + c13 * r3) / det
    b2 = (c12 * r1 + c22 * r2 + c23 * r3) / det
    b3 = (c13 * r1 + c23 * r2 + c33 * r3) / det
    quad = b1 * r1 + b2 * r2 + b3 * r3 - d  # bᵀŜb - d̂, with Ŝb = r̂
    if quad <= 0:
        return _no_ellipsoid()
    lam = g_scaled * g_scaled / quad  # eq. (5)
    S11, S22, S33, S12, S13, S23 = lam * S11, lam * S22, lam * S33, lam * S12, lam * S13, lam * S23
    # reversed Cholesky (eq. 6); radicands are Schur complements of a PD matrix
    a6 = math.sqrt(S33)
    a5, a4 = S23 / a6, S13 / a6
    a3 = math.sqrt(S22 - a5 * a5)
    a2 = (S12 - a4 * a5) / a3
    a1 = math.sqrt(S11 - a2 * a2 - a4 * a4)
    # M = A⁻¹ for lower-triangular A
    m11, m22, m33 = 1 / a1, 1 / a3, 1 / a6
    m21 = -a2 * m11 / a3
    m32 = -a5 * m22 / a6
    m31 = -(a4 * m11 + a5 * m21) / a6
    M = np.array([m11, 0.0, 0.0, m21, m22, 0.0, m31, m32, m33]).reshape(3, 3)
    return [b1, b2, b3], M, lam, True


def _no_ellipsoid():
    return [math.nan] * 3, np.full((3, 3), np.nan), math.nan, False


def _null_vector(N: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Θ̂ of the full LLS from ``N = XᵀX`` (10x10, C-contiguous, overwritten) as ``(x,
    |x|)``, Θ̂ = x / |x| (the division is left to the caller: eqs. 4 and 6 do not need
    it), or None when the fast route cannot certify it (see the module docstring); the
    caller then takes the SVD.

    Inverse iteration with the inverse of the Cholesky factor of N (numpy's LAPACK:
    scipy.linalg, 0.5 s to import, is not needed for one calibration).
    After every second solve the residual bound is checked; once it holds, the gap is
    certified.
    """
    diag = N.ravel()[::11]  # a view of the diagonal
    tr = sum(diag.tolist())
    L = _cholesky(N)
    delta = 0.0
    if L is None:  # N singular to rounding (σ10 ≈ 0: noise-free poses): use N + δI
        delta = _SHIFT * tr
        diag += delta
        L = _cholesky(N)
        if L is None:
            return None
    # L⁻¹ once, then matrix-vector products (each numpy.linalg call costs microseconds);
    # an inexact solve could only delay or deny the certificate, which is computed with N
    # itself, never pass a wrong Θ̂
    Linv = np.linalg.inv(L)
    LinvT = Linv.T

    def solve(b):
        return LinvT.dot(Linv.dot(b))

    x = solve(_START)
    for _ in range(_ROUNDS):
        x = solve(x)  # two solves per round
        y = N.dot(x)  # (N + δI) x
        xx = x.dot(x)
        rho = x.dot(y) / xx  # Rayleigh quotient of N + δI
        # ||N x̂ - ρ x̂|| for unit x̂ (the shift cancels), plus what rounding can hide:
        # that of N x, and the cancellation in |N x̂|² - ρ² (a few eps ρ²)
        res = math.sqrt(max(y.dot(y) / xx - rho * rho, 0.0)) + _MATVEC_ROUNDING * tr + _CANCELLATION * abs(rho)
        rho -= delta  # Rayleigh quotient of N: at least its smallest eigenvalue
        # Required lower bound on the second-smallest eigenvalue of N: above
        # NULLSPACE_RATIO² times the smallest (at most rho) and above MIN_GAP trace(N);
        # given it, sin∠(x, eigenvector) <= res / (bound - rho) (Davis–Kahan).
        bound = max(NULLSPACE_RATIO**2 * rho, MIN_GAP * tr)
        if res <= EIGVEC_TOL * (bound - rho):
            # λmin of the leading 9x9 block <= second-smallest eigenvalue (Cauchy
            # interlacing): a Cholesky of that block minus the bound proves the gap.
            diag[:9] -= bound + delta
            return (x, math.sqrt(xx)) if _cholesky(N[:9, :9]) is not None else None
        x = solve(x / math.sqrt(xx))  # keep the iterate O(1) between rounds
    return None


def _cholesky(A: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factor of the symmetric ``A``, or None if it is not positive definite."""
    try:
        return np.linalg.cholesky(A)
    except np.linalg.LinAlgError:
        return None


def full_lls(z, g: float) -> LLSResult:
    """Full LLS: bias, scale factors and non-orthogonality in closed form.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means (any consistent unit), ``n >= 10``.
    g : float
        Gravity magnitude in the same unit (only λ, hence M, depends on it).

    Returns
    -------
    LLSResult

    Raises
    ------
    TooFewPosesError, DegeneratePosesError, NonFiniteError, InputShapeError,
    NotPositiveDefiniteError

    Notes
    -----
    Speed: with numba installed (``ACCELCAL_KERNELS=auto``, the default) the calls of a
    process run in numpy (no numba start-up for a one-off calibration) until they would
    have saved, compiled, numba's start-up (about 14 000 calls of this function on 24
    poses; :mod:`accelcal.kernels`); that call loads the compiled kernels (about 0.5 s
    once, from numba's disk cache) and every later call runs compiled, about 15
    times faster.  ``ACCELCAL_KERNELS=numba`` or ``numpy`` forces either path from the
    first call; the two agree to rounding.
    """
    K = compiled(_KERNELS, single=True, saves_s=SAVES_S["full_lls"])
    if K is not None:
        return _full_lls_compiled(K, z, g)
    return _full_lls_numpy(z, g)


def _full_lls_compiled(K, z, g) -> LLSResult:
    """:func:`full_lls` by the compiled kernel (the fast route of :func:`_full_lls_numpy`
    as one compiled loop); what it cannot certify, and every input error, goes to the SVD."""
    poses = np.ascontiguousarray(z, dtype=float)
    if poses.ndim != 2:
        return _full_lls_svd(z, g)
    bias, M = np.empty(3), np.empty((3, 3))
    lam = K.full_lls(poses, _float_or_nan(g), MIN_GAP, EIGVEC_TOL, bias, M)
    if lam == -K.REFERENCE:
        return _full_lls_svd(poses, g)
    g = check_g(g)
    if lam == -K.NO_ELLIPSOID:
        raise NotPositiveDefiniteError(_NO_ELLIPSOID)
    return LLSResult._trusted(method="full_lls", bias=bias, M=M, g=g, poses=poses, lam=lam, c=math.nan,
                              noise_var=math.nan)


def _float_or_nan(g) -> float:
    """``g`` as a float for a kernel, NaN if it is none (:func:`check_g` raises later,
    after the pose checks, as in the reference)."""
    try:
        return float(g)
    except (TypeError, ValueError):
        return math.nan


def _full_lls_numpy(z, g) -> LLSResult:
    """:func:`full_lls` in numpy: the Gram-matrix route with LAPACK, else the SVD."""
    z = pose_array(z, "full")
    n = len(z)
    k = _scale_single(z)
    if not (math.isfinite(k) and k > 0):  # NaN/inf or all-zero poses: the reference says which
        return _full_lls_svd(z, g)
    N = normal_matrix(z, k)
    # row 9 of N holds the column sums of X: Σ zs², 2 Σ zx zy, ..., -2 Σ zs, n
    xx, yy, zz, xy, xz, yz, sx, sy, sz, _ = N[9].tolist()
    if not geometry_is_clearly_fine((-0.5 * sx, -0.5 * sy, -0.5 * sz),
                                    ((xx, 0.5 * xy, 0.5 * xz), (0.0, yy, 0.5 * yz), (0.0, 0.0, zz)), n):
        return _full_lls_svd(z, g)
    g = check_g(g)
    null = _null_vector(N)
    if null is None:
        return _full_lls_svd(z, g)
    theta, norm = null
    b, M, lam, valid = _theta_to_model_single(theta, g / k)
    if not valid:
        raise NotPositiveDefiniteError(_NO_ELLIPSOID)
    # λ of eq. (5) refers to the unit-norm Θ̂ = theta / norm; b and M do not depend on the scale
    return LLSResult._trusted(method="full_lls", bias=np.array([b[0] * k, b[1] * k, b[2] * k]), M=M, g=g,
                              poses=z, lam=lam * norm, c=math.nan, noise_var=math.nan)


_NO_ELLIPSOID = "full LLS gives no ellipsoid (Ŝ not positive definite or λ <= 0): poses too noisy or not static"


def _full_lls_svd(z, g: float) -> LLSResult:
    """Reference full LLS: SVD of the scaled design matrix (eq. 3), every check."""
    z = check_poses(z, "full")
    g = check_g(g)
    k = _scale_single(z)
    X = design_matrix(z / k)
    _, sv, Vt = np.linalg.svd(X, full_matrices=False)
    if sv[8] < NULLSPACE_RATIO * sv[9] or sv[8] < 1e-10 * sv[0]:
        raise DegeneratePosesError(
            "pose set does not determine the full model (the quadric through the poses is not unique): "
            "add poses in new orientations"
        )
    b, M, lam, valid = _theta_to_model_single(Vt[-1], g / k)
    if not valid:
        raise NotPositiveDefiniteError(_NO_ELLIPSOID)
    return LLSResult._trusted(method="full_lls", bias=np.array(b) * k, M=M, g=g, poses=z, lam=lam,
                              c=math.nan, noise_var=math.nan, singular_values=sv)


def bias_lls(z, g: float) -> LLSResult:
    """Bias-only LLS (eq. 7): ``M = I``; the bias needs no knowledge of g.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means, ``n >= 4``.
    g : float
        Gravity magnitude (used only for residuals and standard errors).

    Returns
    -------
    LLSResult

    Notes
    -----
    Speed: with numba installed (``ACCELCAL_KERNELS=auto``, the default) the calls of a
    process run in numpy (no numba start-up for a one-off calibration) until they would
    have saved, compiled, numba's start-up (about 57 000 calls of this function on 24
    poses; :mod:`accelcal.kernels`); that call loads the compiled kernels (about 0.5 s
    once, from numba's disk cache) and every later call runs compiled, about 4
    times faster.  ``ACCELCAL_KERNELS=numba`` or ``numpy`` forces either path from the
    first call; the two agree to rounding.
    """
    K = compiled(_KERNELS, single=True, saves_s=SAVES_S["bias_lls"])
    if K is not None:
        return _bias_lls_compiled(K, z, g)
    return _bias_lls_numpy(z, g)


def _bias_lls_compiled(K, z, g) -> LLSResult:
    """:func:`bias_lls` by the compiled kernel (the centred normal equations of
    :func:`_bias_lls_numpy`); what it cannot certify, and every input error, goes to ``lstsq``."""
    poses = np.ascontiguousarray(z, dtype=float)
    if poses.ndim != 2:
        return _bias_lls_lstsq(z, g)
    bias = np.empty(3)
    c = K.bias_lls(poses, bias)
    if c != c:  # NaN: the reference decides
        return _bias_lls_lstsq(poses, g)
    g = check_g(g)
    return LLSResult._trusted(method="bias_lls", bias=bias, M=_EYE3.copy(), g=g, poses=poses, lam=math.nan, c=c,
                              noise_var=math.nan)


def _bias_lls_numpy(z, g) -> LLSResult:
    """:func:`bias_lls` in numpy: the centred 3x3 normal equations, else ``lstsq``."""
    z = pose_array(z, "bias")
    n = len(z)
    flat = z.ravel()
    sum_sq = flat.dot(flat)  # Σ |z|²: NaN or inf iff some z is (or overflows)
    if not math.isfinite(sum_sq):
        return _bias_lls_lstsq(z, g)  # the reference says which error
    # Eq. (7) is a least-squares problem with an intercept, so it is the same problem in
    # poses shifted by any point p: with c_i = z_i - p, |c_i|² = 2 c_iᵀ(b - p) + c'.
    # Shifting by the first pose removes the offset of the data; eliminating the
    # intercept leaves the 3x3 normal equations of the centred c_i, whose moments are
    # in WᵀW with W = [c, c², 1] (c² element-wise).
    p = z[0]
    W = np.empty((n, 7))
    shifted = W[:, :3]
    np.subtract(z, p, out=shifted)
    np.multiply(shifted, shifted, out=W[:, 3:6])
    W[:, 6] = 1.0
    rx, ry, rz = W.T[:3].dot(W).tolist()  # Σ c_j (c, c², 1) for j = x, y, z
    xx, xy, xz, sx = rx[0], rx[1], rx[2], rx[6]
    yy, yz, sy = ry[1], ry[2], ry[6]
    zz, sz = rz[2], rz[6]
    sq = xx + yy + zz  # Σ |c|²
    xq, yq, zq = rx[3] + rx[4] + rx[5], ry[3] + ry[4] + ry[5], rz[3] + rz[4] + rz[5]  # Σ c |c|²
    # scatter about the mean, Σ (c - c̄)(c - c̄)ᵀ, and mean of c
    mx, my, mz = sx / n, sy / n, sz / n
    C = ((xx - sx * mx, xy - sx * my, xz - sx * mz), (0.0, yy - sy * my, yz - sy * mz), (0.0, 0.0, zz - sz * mz))
    if not scatter_is_clearly_3d(C, sum_sq):
        return _bias_lls_lstsq(z, g)
    g = check_g(g)
    mean_cc = sq / n  # mean |c|²
    x1, x2, x3 = _solve_spd3(C, (xq - sx * mean_cc, yq - sy * mean_cc, zq - sz * mean_cc))  # = 2 (b - p)
    p1, p2, p3 = p.tolist()
    b1, b2, b3 = 0.5 * x1 + p1, 0.5 * x2 + p2, 0.5 * x3 + p3
    # intercept of eq. (7), c = mean |z|² - 2 z̄ᵀb, with z̄ = c̄ + p
    c = sum_sq / n - 2 * ((mx + p1) * b1 + (my + p2) * b2 + (mz + p3) * b3)
    return LLSResult._trusted(method="bias_lls", bias=np.array([b1, b2, b3]), M=_EYE3.copy(), g=g, poses=z,
                              lam=math.nan, c=c, noise_var=math.nan)


def _solve_spd3(C, h):
    """Solve ``C x = h`` for a symmetric positive-definite 3x3 ``C`` (nested sequences,
    upper triangle read) by Cholesky in scalar arithmetic."""
    (a, b, c), (_, d, e), (_, _, f) = C
    l11 = math.sqrt(a)
    l21, l31 = b / l11, c / l11
    l22 = math.sqrt(d - l21 * l21)
    l32 = (e - l31 * l21) / l22
    l33 = math.sqrt(f - l31 * l31 - l32 * l32)
    y1 = h[0] / l11
    y2 = (h[1] - l21 * y1) / l22
    y3 = (h[2] - l31 * y1 - l32 * y2) / l33
    x3 = y3 / l33
    x2 = (y2 - l32 * x3) / l22
    x1 = (y1 - l21 * x2 - l31 * x3) / l11
    return x1, x2, x3


def _bias_lls_lstsq(z, g: float) -> LLSResult:
    """Reference bias-only LLS: ``lstsq`` of the scaled eq. (7), every check."""
    z = check_poses(z, "bias")
    g = check_g(g)
    k = _scale_single(z)
    zs = z / k
    sol, _, rank, sv = np.linalg.lstsq(bias_design(zs), np.sum(zs**2, axis=1), rcond=None)
    if rank < 4:
        raise DegeneratePosesError("pose set does not determine the bias: turn the sensor about more axes")
    return LLSResult._trusted(method="bias_lls", bias=sol[:3] * k, M=np.eye(3), g=g, poses=z, lam=math.nan,
                              c=float(sol[3] * k**2), noise_var=math.nan, singular_values=sv)
