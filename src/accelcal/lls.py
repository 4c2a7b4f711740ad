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
"""

from __future__ import annotations

import math

import numpy as np

from .errors import DegeneratePosesError, NotPositiveDefiniteError
from .model import lower_from_gram
from .results import BatchResult, LLSResult
from .validation import check_g, check_poses

#: The full system has a one-dimensional null space only if σ9 clearly exceeds σ10.
#: For a well-spread pose set σ9/σ10 is of order g/noise (10³ and more); for a pose set
#: that admits a second quadric (e.g. poses on two planes) σ9 sinks to the noise floor.
NULLSPACE_RATIO = 3.0


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
    more than the arithmetic; this keeps a single closed-form solve in the tens of µs)."""
    t = theta if theta[0] + theta[1] + theta[2] > 0 else -theta
    S11, S22, S33, S12, S13, S23, r1, r2, r3, d = t.tolist()
    nan = (np.full(3, np.nan), np.full((3, 3), np.nan), float("nan"), False)
    # Ŝ positive definite <=> leading principal minors positive (Sylvester).
    m2 = S11 * S22 - S12 * S12
    det = S11 * (S22 * S33 - S23 * S23) - S12 * (S12 * S33 - S23 * S13) + S13 * (S12 * S23 - S22 * S13)
    if S11 <= 0 or m2 <= 0 or det <= 0:
        return nan
    # b = Ŝ⁻¹ r̂ via the adjugate (eq. 4)
    c11, c22, c33 = S22 * S33 - S23 * S23, S11 * S33 - S13 * S13, m2
    c12, c13, c23 = S13 * S23 - S12 * S33, S12 * S23 - S13 * S22, S12 * S13 - S11 * S23
    b1 = (c11 * r1 + c12 * r2 + c13 * r3) / det
    b2 = (c12 * r1 + c22 * r2 + c23 * r3) / det
    b3 = (c13 * r1 + c23 * r2 + c33 * r3) / det
    quad = b1 * r1 + b2 * r2 + b3 * r3 - d  # bᵀŜb - d̂, with Ŝb = r̂
    if quad <= 0:
        return nan
    lam = g_scaled * g_scaled / quad  # eq. (5)
    S11, S22, S33, S12, S13, S23 = (lam * v for v in (S11, S22, S33, S12, S13, S23))
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
    M = np.array([[m11, 0.0, 0.0], [m21, m22, 0.0], [m31, m32, m33]])
    return np.array([b1, b2, b3]), M, lam, True


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
    """
    z = check_poses(z, "full")
    g = check_g(g)
    k = _scale(z)
    X = design_matrix(z / k)
    _, sv, Vt = np.linalg.svd(X, full_matrices=False)
    if sv[8] < NULLSPACE_RATIO * sv[9] or sv[8] < 1e-10 * sv[0]:
        raise DegeneratePosesError(
            "pose set does not determine the full model (the quadric through the poses is not unique): "
            "add poses in new orientations"
        )
    b, M, lam, valid = _theta_to_model_single(Vt[-1], g / k)
    if not valid:
        raise NotPositiveDefiniteError(
            "full LLS gives no ellipsoid (Ŝ not positive definite or λ <= 0): poses too noisy or not static"
        )
    return _full_result("full_lls", z, g, b * k, M, singular_values=sv, lam=float(lam))


def _full_result(method, z, g, b, M, **extra) -> LLSResult:
    return LLSResult(method=method, bias=b, M=M, g=g, poses=z, **extra)


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
    """
    z = check_poses(z, "bias")
    g = check_g(g)
    k = _scale(z)
    zs = z / k
    H = np.column_stack([2 * zs, np.ones(len(zs))])
    sol, _, rank, sv = np.linalg.lstsq(H, np.sum(zs**2, axis=1), rcond=None)
    if rank < 4:
        raise DegeneratePosesError("pose set does not determine the bias: turn the sensor about more axes")
    b = sol[:3] * k
    M = np.eye(3)
    return LLSResult(method="bias_lls", bias=b, M=M, g=g, poses=z, singular_values=sv, c=float(sol[3] * k**2))


def full_lls_batch(z, g: float) -> BatchResult:
    """Full LLS over many trials at once: ``z`` of shape ``(trials, poses, 3)``.

    Trials whose estimate is not an ellipsoid are marked ``valid=False`` and hold NaN.
    """
    z = check_poses(z, "full", batched=True)
    g = check_g(g)
    k = _scale(z)
    X = design_matrix(z / k[:, None, None])
    _, _, Vt = np.linalg.svd(X, full_matrices=False)
    b, M, _, valid = theta_to_model(Vt[:, -1, :], g / k)
    return BatchResult(method="full_lls", bias=b * k[:, None], M=M, valid=valid)


def bias_lls_batch(z, g: float) -> BatchResult:
    """Bias-only LLS over many trials at once: ``z`` of shape ``(trials, poses, 3)``."""
    z = check_poses(z, "bias", batched=True)
    check_g(g)
    k = _scale(z)
    zs = z / k[:, None, None]
    H = np.concatenate([2 * zs, np.ones(zs.shape[:-1] + (1,))], axis=-1)
    y = np.sum(zs**2, axis=-1)
    # Normal equations of a 4-column system scaled to O(1): condition² stays small.
    HtH = np.einsum("tni,tnj->tij", H, H)
    Hty = np.einsum("tni,tn->ti", H, y)
    sol = np.linalg.solve(HtH, Hty[..., None])[..., 0]
    T = len(z)
    return BatchResult(method="bias_lls", bias=sol[:, :3] * k[:, None],
                       M=np.broadcast_to(np.eye(3), (T, 3, 3)).copy(), valid=np.ones(T, bool))
