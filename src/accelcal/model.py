"""The accelerometer error model of Burkhard et al. (2024), eq. (1).

``z = M x + b + e`` with ``z`` the measured and ``x`` the true specific force, ``b`` the
bias and ``M`` lower triangular.  Parametrisation used throughout accelcal (the one
reconstructed in ``shared/papers/README.md``)::

    row i of M = (1 + s_i) * u_i
    u_x = (1, 0, 0)
    u_y = (sin θxy, cos θxy, 0)
    u_z = (sin θzx, sin θzy, sqrt(1 - sin²θzx - sin²θzy))

Scale factors ``s = (s_x, s_y, s_z)`` are dimensionless (1e-6 = 1 ppm); the
non-orthogonality angles are ordered ``θ = (θxy, θzx, θzy)`` and given in radians.
Each row of ``M`` is the sensing axis of one accelerometer, expressed in an orthonormal
frame whose x axis is the x accelerometer and whose y axis lies in the plane of the x
and y accelerometers; ``(1 + s_i)`` is its length.

All functions accept leading batch dimensions (``s`` of shape ``(..., 3)``).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputShapeError, NotPositiveDefiniteError

#: Parameter names in the order used by Jacobians, covariances and the CRLB.
FULL_PARAMETERS = ("bx", "by", "bz", "sx", "sy", "sz", "theta_xy", "theta_zx", "theta_zy")
BIAS_PARAMETERS = FULL_PARAMETERS[:3]


def m_from_params(scale_factors, nonorthogonality) -> np.ndarray:
    """Build ``M`` from scale factors and non-orthogonality angles.

    Parameters
    ----------
    scale_factors : array_like, shape (..., 3)
        ``(s_x, s_y, s_z)``, dimensionless.
    nonorthogonality : array_like, shape (..., 3)
        ``(θxy, θzx, θzy)`` in radians.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        Lower-triangular ``M``.
    """
    s = np.asarray(scale_factors, dtype=float)
    th = np.asarray(nonorthogonality, dtype=float)
    if s.shape[-1:] != (3,) or th.shape[-1:] != (3,):
        raise InputShapeError("scale_factors and nonorthogonality must have a last dimension of 3")
    s, th = np.broadcast_arrays(s, th)
    sxy, szx, szy = np.sin(th[..., 0]), np.sin(th[..., 1]), np.sin(th[..., 2])
    uz_z2 = 1.0 - szx**2 - szy**2
    if np.any(uz_z2 <= 0):
        raise InputShapeError("non-orthogonality angles too large: sin²θzx + sin²θzy must be < 1")
    M = np.zeros(s.shape[:-1] + (3, 3))
    M[..., 0, 0] = 1.0
    M[..., 1, 0] = sxy
    M[..., 1, 1] = np.cos(th[..., 0])
    M[..., 2, 0] = szx
    M[..., 2, 1] = szy
    M[..., 2, 2] = np.sqrt(uz_z2)
    return M * (1.0 + s)[..., :, None]


def m_from_params_single(scale_factors, nonorthogonality) -> np.ndarray:
    """:func:`m_from_params` for one parameter set (two sequences of 3 floats) in scalar
    arithmetic: the same matrix for a tenth of the time, for the per-problem estimators."""
    sx, sy, sz = (float(v) for v in scale_factors)
    txy, tzx, tzy = (float(v) for v in nonorthogonality)
    sxy, szx, szy = math.sin(txy), math.sin(tzx), math.sin(tzy)
    uz_z2 = 1.0 - szx * szx - szy * szy
    if not uz_z2 > 0:
        raise InputShapeError("non-orthogonality angles too large: sin²θzx + sin²θzy must be < 1")
    ax, ay, az = 1.0 + sx, 1.0 + sy, 1.0 + sz
    return np.array([ax, 0.0, 0.0, ay * sxy, ay * math.cos(txy), 0.0,
                     az * szx, az * szy, az * math.sqrt(uz_z2)]).reshape(3, 3)


def params_from_m(M) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`m_from_params`.

    Parameters
    ----------
    M : array_like, shape (..., 3, 3)
        Lower-triangular matrix with a positive diagonal.

    Returns
    -------
    scale_factors, nonorthogonality : numpy.ndarray, shape (..., 3)
        As in :func:`m_from_params` (angles in radians).

    Raises
    ------
    NotPositiveDefiniteError
        If a diagonal element of ``M`` is not positive.
    InputShapeError
        If ``M`` is not 3x3 or not lower triangular.
    """
    M = np.asarray(M, dtype=float)
    if M.shape[-2:] != (3, 3):
        raise InputShapeError(f"M must be 3x3, got shape {M.shape}")
    upper = np.abs(M[..., [0, 0, 1], [1, 2, 2]])
    if np.any(upper > 1e-12 * np.abs(M).max(axis=(-2, -1), keepdims=False)[..., None]):
        raise InputShapeError("M must be lower triangular (the model of Burkhard et al. 2024)")
    if np.any(np.diagonal(M, axis1=-2, axis2=-1) <= 0):
        raise NotPositiveDefiniteError("M has a non-positive diagonal element")
    norms = np.linalg.norm(M, axis=-1)
    u = M / norms[..., :, None]
    th = np.stack([np.arcsin(u[..., 1, 0]), np.arcsin(u[..., 2, 0]), np.arcsin(u[..., 2, 1])], axis=-1)
    return norms - 1.0, th


def dM_dparams(scale_factors, nonorthogonality) -> np.ndarray:
    """Derivatives of ``M`` with respect to ``(s_x, s_y, s_z, θxy, θzx, θzy)``.

    Returns
    -------
    numpy.ndarray, shape (6, 3, 3)
        ``out[k] = ∂M/∂p_k`` for a single (unbatched) parameter set.
    """
    s = np.asarray(scale_factors, dtype=float)
    th = np.asarray(nonorthogonality, dtype=float)
    U = m_from_params(np.zeros(3), th)  # unit rows u_i
    out = np.zeros((6, 3, 3))
    for i in range(3):
        out[i, i] = U[i]
    cxy, czx, czy = np.cos(th)
    sxy, szx, szy = np.sin(th)
    uzz = U[2, 2]
    out[3, 1] = (1 + s[1]) * np.array([cxy, -sxy, 0.0])
    out[4, 2] = (1 + s[2]) * np.array([czx, 0.0, -szx * czx / uzz])
    out[5, 2] = (1 + s[2]) * np.array([0.0, czy, -szy * czy / uzz])
    return out


def lower_from_gram(S) -> np.ndarray:
    """Lower-triangular ``A`` with positive diagonal such that ``S = Aᵀ A``.

    This is the "reversed Cholesky" of Burkhard et al. (2024), Sec. 1.1: with
    ``A = [[a1, 0, 0], [a2, a3, 0], [a4, a5, a6]]``::

        a6 = sqrt(S33), a5 = S23/a6, a4 = S13/a6, a3 = sqrt(S22 - a5²),
        a2 = (S12 - a4 a5)/a3, a1 = sqrt(S11 - a2² - a4²)

    Works on stacks ``(..., 3, 3)``; an element whose radicand is not positive
    raises :class:`NotPositiveDefiniteError` (a batch caller masks those first).
    """
    S = np.asarray(S, dtype=float)
    r6 = S[..., 2, 2]
    if np.any(r6 <= 0):
        raise NotPositiveDefiniteError("estimated S is not positive definite (S33 <= 0)")
    a6 = np.sqrt(r6)
    a5 = S[..., 1, 2] / a6
    a4 = S[..., 0, 2] / a6
    r3 = S[..., 1, 1] - a5**2
    if np.any(r3 <= 0):
        raise NotPositiveDefiniteError("estimated S is not positive definite (S22 - a5² <= 0)")
    a3 = np.sqrt(r3)
    a2 = (S[..., 0, 1] - a4 * a5) / a3
    r1 = S[..., 0, 0] - a2**2 - a4**2
    if np.any(r1 <= 0):
        raise NotPositiveDefiniteError("estimated S is not positive definite (S11 - a2² - a4² <= 0)")
    A = np.zeros(S.shape)
    A[..., 0, 0] = np.sqrt(r1)
    A[..., 1, 0] = a2
    A[..., 1, 1] = a3
    A[..., 2, 0] = a4
    A[..., 2, 1] = a5
    A[..., 2, 2] = a6
    return A


def apply_model(x, M, bias) -> np.ndarray:
    """Noise-free measurement ``z = M x + b`` for true specific forces ``x`` (..., n, 3)."""
    x = np.asarray(x, dtype=float)
    M = np.asarray(M, dtype=float)
    return np.einsum("...ij,...nj->...ni", M, x) + np.asarray(bias, dtype=float)[..., None, :]


def correct(z, M, bias) -> np.ndarray:
    """Calibrated specific force ``x = M⁻¹ (z - b)`` for measurements ``z`` (n, 3)."""
    z = np.asarray(z, dtype=float)
    return np.linalg.solve(np.asarray(M, dtype=float), (z - np.asarray(bias, dtype=float)).T).T
