"""The accelerometer model of Batista et al. (2011), eq. (2), and the rotations it needs.

``a_m = F [a + F2 a²] + b + n`` with ``F`` invertible (scale factors and cross
coupling), ``F2`` diagonal (the even quadratic term), ``a²`` element-wise and ``n``
white noise.  With ``b' = F⁻¹ b`` this is ``a_m = F (a + F2 a² + b') + n``.  At rest
the sensor measures ``a = -g`` with ``g`` gravity in body coordinates (eq. 3).

Frames and conventions used throughout :mod:`accelcal.batista`:

* ``R`` is the rotation from body to table (or inertial) coordinates, ``^T_B R`` in
  the paper; body vectors are ``x_B = Rᵀ x_T``.
* Euler angles are roll ``φ``, pitch ``θ``, yaw ``ψ`` in the ZYX order,
  ``R = Rz(ψ) Ry(θ) Rx(φ)``.
* The reference frame is north-east-down: gravity in it is ``(0, 0, +|g|)``, so the
  paper's normalisation "sign of the z component" is positive.
* ``ω`` is the angular velocity of the body in body coordinates, ``Ṙ = R S(ω)``,
  ``S(ω) x = ω × x``.

All functions accept leading batch dimensions.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputShapeError, NonFiniteError

#: Simulation truth of Batista et al. (2011), Sec. V-A.
PAPER_F_INV = np.array([[0.990, 0.001, -0.002], [0.020, 1.005, 0.003], [-0.010, -0.004, 1.010]])
PAPER_B_PRIME = np.array([0.05, -0.01, 0.04])  # m/s²
PAPER_F2 = 1e-4 * np.array([2.5, 1.5, -0.75])  # diag(F2), 1/(m/s²)
PAPER_NOISE = 0.0013  # accelerometer noise std, m/s²
#: Bias of the online filter simulation, Sec. V-B (m/s²).
PAPER_FILTER_BIAS = np.array([0.1, -0.05, 0.025])


def skew(w) -> np.ndarray:
    """``S(w)`` with ``S(w) x = w × x``; ``w`` of shape (..., 3) -> (..., 3, 3)."""
    w = np.asarray(w, dtype=float)
    z = np.zeros(w.shape[:-1])
    return np.stack([np.stack([z, -w[..., 2], w[..., 1]], -1),
                     np.stack([w[..., 2], z, -w[..., 0]], -1),
                     np.stack([-w[..., 1], w[..., 0], z], -1)], -2)


def euler_to_rotation(euler) -> np.ndarray:
    """Body-to-reference rotation ``R = Rz(ψ) Ry(θ) Rx(φ)`` from ``(φ, θ, ψ)`` [rad], (..., 3)."""
    e = np.asarray(euler, dtype=float)
    if e.shape[-1:] != (3,):
        raise InputShapeError(f"Euler angles must have a last dimension of 3, got shape {e.shape}")
    cf, sf = np.cos(e[..., 0]), np.sin(e[..., 0])
    ct, st = np.cos(e[..., 1]), np.sin(e[..., 1])
    cp, sp = np.cos(e[..., 2]), np.sin(e[..., 2])
    return np.stack([
        np.stack([cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf], -1),
        np.stack([sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf], -1),
        np.stack([-st, ct * sf, ct * cf], -1),
    ], -2)


def euler_rate_matrix(euler) -> np.ndarray:
    """``E`` with ``ω = E (φ̇, θ̇, ψ̇)`` for ZYX Euler angles, (..., 3) -> (..., 3, 3)."""
    e = np.asarray(euler, dtype=float)
    cf, sf = np.cos(e[..., 0]), np.sin(e[..., 0])
    ct, st = np.cos(e[..., 1]), np.sin(e[..., 1])
    one, zero = np.ones_like(cf), np.zeros_like(cf)
    return np.stack([np.stack([one, zero, -st], -1),
                     np.stack([zero, cf, ct * sf], -1),
                     np.stack([zero, -sf, ct * cf], -1)], -2)


def euler_rate_matrix_dot(euler, euler_dot) -> np.ndarray:
    """Time derivative of :func:`euler_rate_matrix` along ``(φ̇, θ̇, ψ̇)``."""
    e = np.asarray(euler, dtype=float)
    d = np.asarray(euler_dot, dtype=float)
    cf, sf = np.cos(e[..., 0]), np.sin(e[..., 0])
    ct, st = np.cos(e[..., 1]), np.sin(e[..., 1])
    fd, td = d[..., 0], d[..., 1]
    zero = np.zeros_like(cf)
    return np.stack([np.stack([zero, zero, -ct * td], -1),
                     np.stack([zero, -sf * fd, -st * sf * td + ct * cf * fd], -1),
                     np.stack([zero, -cf * fd, -st * cf * td - ct * sf * fd], -1)], -2)


def axis_angle_rotation(axis, angle) -> np.ndarray:
    """``exp(S(n) α)`` for unit ``axis`` (3,) and angles ``angle`` (...,) (Rodrigues)."""
    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    a = np.asarray(angle, dtype=float)[..., None, None]
    K = skew(n)
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * (K @ K)


def gravity_in_table(offset_euler, g: float) -> np.ndarray:
    """Gravity in table coordinates ``^T g = (^I_T R)ᵀ (0, 0, g)`` for a mounting offset.

    ``offset_euler`` (φ, θ, ψ) [rad] is the unknown installation rotation from table to
    level (NED) coordinates; a perfectly level table gives ``(0, 0, g)``.
    """
    return euler_to_rotation(offset_euler).T @ np.array([0.0, 0.0, float(g)])


def specific_force_at_rest(R, g_table) -> np.ndarray:
    """``a = -g_B = -Rᵀ ^T g`` for body-to-table rotations ``R`` (..., 3, 3)."""
    return -np.einsum("...ji,j->...i", np.asarray(R, float), np.asarray(g_table, float))


def accelerometer_output(a, F_inv, b_prime, f2) -> np.ndarray:
    """Noise-free eq. (2): ``a_m = F (a + F2 a² + b')`` for specific forces ``a`` (..., 3).

    Parameters
    ----------
    a : array_like, shape (..., 3)
        True specific force in body coordinates [m/s²].
    F_inv : array_like, shape (3, 3)
        ``F⁻¹``.
    b_prime : array_like, shape (3,)
        ``b' = F⁻¹ b`` [m/s²].
    f2 : array_like, shape (3,)
        Diagonal of ``F2`` [1/(m/s²)].

    Returns
    -------
    numpy.ndarray, shape (..., 3)
    """
    a = np.asarray(a, dtype=float)
    u = a + np.asarray(f2, float) * a * a + np.asarray(b_prime, float)
    return u @ np.linalg.inv(np.asarray(F_inv, float)).T


def correct_measurement(a_m, F_inv, b_prime, f2) -> np.ndarray:
    """Invert eq. (2) in closed form: the specific force ``a`` from ``a_m``.

    ``u = F⁻¹ a_m - b' = a + f2 a²`` per axis, so ``a = 2u / (1 + sqrt(1 + 4 f2 u))``
    (the root that tends to ``u`` as ``f2 → 0``; written without cancellation).

    Raises
    ------
    NonFiniteError
        If ``1 + 4 f2 u < 0`` for some sample (outside the range of the model).
    """
    u = np.asarray(a_m, float) @ np.asarray(F_inv, float).T - np.asarray(b_prime, float)
    disc = 1.0 + 4.0 * np.asarray(f2, float) * u
    if np.any(disc < 0):
        raise NonFiniteError("measurement outside the range of the quadratic model (1 + 4 f2 u < 0)")
    return 2.0 * u / (1.0 + np.sqrt(disc))
