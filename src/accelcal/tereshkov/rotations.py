"""Small rotation helpers on batched arrays (``(..., 3)`` vectors, ``(..., 3, 3)`` matrices).

Conventions: ``skew(a) @ b = a × b`` (the paper's "arc" ã); Euler angles are
aerospace ZYX (yaw ψ, pitch θ, roll φ) with ``C_nb = R_z(ψ) R_y(θ) R_x(φ)`` mapping
body-frame vectors to the navigation (North-East-Down) frame.
"""

from __future__ import annotations

import numpy as np


def skew(a: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrices ``ã`` with ``ã b = a × b``, shape ``(..., 3, 3)``."""
    a = np.asarray(a, dtype=float)
    z = np.zeros(a.shape[:-1])
    x, y, w = a[..., 0], a[..., 1], a[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def expm_so3(a: np.ndarray) -> np.ndarray:
    """Rotation matrix ``exp(ã)`` of rotation vectors ``a`` (Rodrigues), shape ``(..., 3, 3)``.

    Written out element by element (and with the Taylor series of the Rodrigues
    coefficients below 1e-4 rad), because it runs once or twice per estimator step.
    """
    a = np.asarray(a, dtype=float)
    x, y, z = a[..., 0], a[..., 1], a[..., 2]
    th2 = x * x + y * y + z * z
    small = th2 < 1e-8
    th = np.sqrt(th2)
    safe = np.where(small, 1.0, th)
    s = np.where(small, 1.0 - th2 / 6.0, np.sin(safe) / safe)
    c = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / np.where(small, 1.0, th2))
    xx, yy, zz = c * x * x, c * y * y, c * z * z
    xy, xz, yz = c * x * y, c * x * z, c * y * z
    sx, sy, sz = s * x, s * y, s * z
    out = np.empty(a.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1.0 - yy - zz
    out[..., 0, 1] = xy - sz
    out[..., 0, 2] = xz + sy
    out[..., 1, 0] = xy + sz
    out[..., 1, 1] = 1.0 - xx - zz
    out[..., 1, 2] = yz - sx
    out[..., 2, 0] = xz - sy
    out[..., 2, 1] = yz + sx
    out[..., 2, 2] = 1.0 - xx - yy
    return out


def euler_to_dcm(roll, pitch, yaw) -> np.ndarray:
    """``C_nb = R_z(yaw) R_y(pitch) R_x(roll)`` (body to NED), broadcast, shape ``(..., 3, 3)``."""
    roll, pitch, yaw = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (roll, pitch, yaw)))
    cf, sf = np.cos(roll), np.sin(roll)
    ct, st = np.cos(pitch), np.sin(pitch)
    cp, sp = np.cos(yaw), np.sin(yaw)
    out = np.empty(roll.shape + (3, 3))
    out[..., 0, 0] = ct * cp
    out[..., 0, 1] = sf * st * cp - cf * sp
    out[..., 0, 2] = cf * st * cp + sf * sp
    out[..., 1, 0] = ct * sp
    out[..., 1, 1] = sf * st * sp + cf * cp
    out[..., 1, 2] = cf * st * sp - sf * cp
    out[..., 2, 0] = -st
    out[..., 2, 1] = sf * ct
    out[..., 2, 2] = cf * ct
    return out


def rotation_angle(C: np.ndarray) -> np.ndarray:
    """Angle of rotation matrices ``C`` [rad] (0 for the identity)."""
    tr = np.trace(C, axis1=-2, axis2=-1)
    return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))
