"""The magnetometer's model: ``m_cal = R A (m_raw - b)``.

``b`` is the hard iron (an offset in the raw unit), ``A`` the soft iron with the scale
factors and non-orthogonality (symmetric: an ellipsoid fit determines only its symmetric
part), ``R`` the rotation from the magnetometer's axes to the accelerometer's (identity
when no accelerometer aligned it).  ``m_cal`` is in units of the fitted field strength
(|m_cal| = 1) unless a field strength was given (``strength``: µT from a geomagnetic model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class MagModel:
    """``m_cal = strength * R @ A @ (m_raw - b)``.

    Attributes
    ----------
    A : ndarray (3, 3)
        Soft iron, symmetric positive definite [1 / raw unit].
    b : ndarray (3,)
        Hard iron [raw unit].
    R : ndarray (3, 3)
        Rotation from the magnetometer's axes to the accelerometer's (identity: not aligned).
    strength : float
        The field strength the unit sphere stands for (1.0: normalised to the fitted strength).
    strength_unit : str
        ``'normalised'`` or the unit of ``strength`` (``'uT'``).
    raw_unit : str
        Unit of the raw samples (``'gauss'``, ``'uT'``, ``'T'``, ``'counts'``).
    """

    A: np.ndarray
    b: np.ndarray
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    strength: float = 1.0
    strength_unit: str = "normalised"
    raw_unit: str = "unknown"

    def __post_init__(self):
        for name, shape in (("A", (3, 3)), ("b", (3,)), ("R", (3, 3))):
            a = np.array(getattr(self, name), dtype=float)
            if a.shape != shape:
                raise ValueError(f"MagModel.{name} has shape {a.shape}, expected {shape}")
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def matrix(self) -> np.ndarray:
        """The whole linear part ``strength * R A`` (raw unit -> output unit)."""
        return self.strength * self.R @ self.A

    def correct(self, m_raw) -> np.ndarray:
        """Calibrated field (n, 3) in the accelerometer's frame (when aligned)."""
        m = np.asarray(m_raw, dtype=float)
        return (m - self.b) @ self.matrix.T

    def to_dict(self) -> dict:
        return {"A": self.A.tolist(), "b": self.b.tolist(), "R": self.R.tolist(), "strength": self.strength,
                "strength_unit": self.strength_unit, "raw_unit": self.raw_unit}

    @classmethod
    def from_dict(cls, d: dict) -> "MagModel":
        return cls(A=np.array(d["A"]), b=np.array(d["b"]), R=np.array(d.get("R", np.eye(3))),
                   strength=float(d.get("strength", 1.0)), strength_unit=d.get("strength_unit", "normalised"),
                   raw_unit=d.get("raw_unit", "unknown"))


def sym_from_vec(s) -> np.ndarray:
    """Symmetric 3x3 from its upper triangle ``[a11, a12, a13, a22, a23, a33]``."""
    a11, a12, a13, a22, a23, a33 = s
    return np.array([[a11, a12, a13], [a12, a22, a23], [a13, a23, a33]])


def vec_from_sym(A) -> np.ndarray:
    return np.array([A[0, 0], A[0, 1], A[0, 2], A[1, 1], A[1, 2], A[2, 2]])


def rotvec_to_matrix(w) -> np.ndarray:
    """Rodrigues: the rotation of angle |w| about w."""
    w = np.asarray(w, dtype=float)
    th = float(np.linalg.norm(w))
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    if th < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th**2 * K @ K


#: Names of the nine ellipsoid parameters, in the order of :func:`accelcal.mag.fit` vectors.
PARAMETERS = ("b_x", "b_y", "b_z", "A_xx", "A_xy", "A_xz", "A_yy", "A_yz", "A_zz")

__all__ = ["MagModel", "PARAMETERS", "rotvec_to_matrix", "sym_from_vec", "vec_from_sym"]
