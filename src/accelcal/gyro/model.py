"""The gyroscope error model and its relation to IMU-TK's, imucal's and Kalibr's.

accelcal's model (the *correcting* form: raw sample in, angular rate out)::

    ω = C (y - b - G f),        C = T K

* ``y`` the raw gyro sample (rad/s, deg/s or counts: :attr:`GyroModel.raw_unit`),
  ``ω`` the angular rate [rad/s] in the **accelerometer frame** of the accelerometer
  calibration (accelcal's lower-triangular ``M``: x along the x accelerometer, y in the
  plane of the x and y accelerometers), ``f`` the calibrated specific force [m/s²].
* ``b`` the bias (raw unit), from the rests (all of them, not only the first).
* ``K = diag(C)`` the scale [rad/s per raw unit] and ``T = C K⁻¹`` the misalignment:
  unit diagonal, six off-diagonals, the gyro axes relative to the accelerometer frame.
  Nine parameters in ``C``: three scales, three non-orthogonalities and the three angles
  of the gyro triad's rotation relative to the accelerometer frame.
* ``G`` the optional g-sensitivity (raw unit per m/s²), a bias proportional to the
  specific force.

The three peers write the same map differently; :meth:`GyroModel.to_imutk`,
:meth:`~GyroModel.to_imucal`, :meth:`~GyroModel.to_kalibr` and the ``from_*`` class
methods convert exactly (tested round trips):

======  ========================================================  ===========================
peer    their model                                               relation to ``C``
======  ========================================================  ===========================
IMU-TK  ``ω = T K (y - b)``; ``T = [[1, -yz, zy], [xz, 1, -zx],``  the same ``T`` and ``K``;
        ``[-xy, yx, 1]]`` (6 misalignments), ``K`` diagonal          no g-sensitivity.  Its
        (3 scales); ``src/calibration.cpp``, ``calibration.h``     frame: *its* accelerometer
                                                                   frame (z along the z
                                                                   accelerometer), see
                                                                   :func:`frame_rotation`
imucal  ``y = K_g R_g ω + K_ga a + b_g`` (sensor model,           ``K_g R_g = C⁻¹`` (×180/π
        ``ferraris_calibration_info.py``): ``K_g`` diagonal        for its deg/s output):
        (row norms), ``R_g`` rows = unit sensing axes,             ``K_g`` = row norms of
        ``K_ga`` g-sensitivity                                      ``C⁻¹``; ``K_ga = G``
Kalibr  ``y = M C_gyro_i ω + A C_gyro_i a + b``               ``M C_gyro_i = C⁻¹``: an LQ
        (``scale-misalignment``, ``IccSensors.py`` l. 1049):       decomposition (``M``
        ``M`` lower triangular (6), ``C_gyro_i`` a rotation (3),   positive diagonal); ``A =
        ``A`` g-sensitivity of the force in the gyro frame         G C_gyro_iᵀ``
======  ========================================================  ===========================

``C`` is what the estimators fit: it enters the integrated rotation linearly, which keeps
the Jacobians simple and makes every parametrisation above a function of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputShapeError
from ..units import ANGULAR_RATE_UNITS

#: Raw gyro units and their nominal factor to rad/s (None: counts, the sensitivity is estimated).
RAW_UNITS = ANGULAR_RATE_UNITS
#: Names of the nine entries of ``C`` and of the IMU-TK misalignments, in order.
C_PARAMETERS = ("Cxx", "Cxy", "Cxz", "Cyx", "Cyy", "Cyz", "Czx", "Czy", "Czz")
IMUTK_MISALIGNMENTS = ("mis_yz", "mis_zy", "mis_zx", "mis_xz", "mis_xy", "mis_yx")


def _mat(a, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise InputShapeError(f"{name} must be a finite 3x3 matrix, got shape {a.shape}")
    return a


def _vec(a, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputShapeError(f"{name} must be 3 finite numbers, got shape {a.shape}")
    return a


@dataclass(frozen=True, eq=False)
class GyroModel:
    """``ω = C (y - b - G f)`` (module docstring).

    Attributes
    ----------
    C : ndarray, shape (3, 3)
        Rad/s per raw unit; ``T K``.
    bias : ndarray, shape (3,)
        Raw unit.
    g_sensitivity : ndarray, shape (3, 3), or None
        ``G``, raw unit per m/s² (None: not modelled).
    raw_unit : {'rad/s', 'deg/s', 'counts'}
    """

    C: np.ndarray
    bias: np.ndarray
    g_sensitivity: np.ndarray | None = None
    raw_unit: str = "rad/s"

    def __post_init__(self):
        object.__setattr__(self, "C", _mat(self.C, "C"))
        object.__setattr__(self, "bias", _vec(self.bias, "bias"))
        if self.g_sensitivity is not None:
            object.__setattr__(self, "g_sensitivity", _mat(self.g_sensitivity, "g_sensitivity"))
        if self.raw_unit not in RAW_UNITS:
            raise InputShapeError(f"raw_unit must be one of {', '.join(RAW_UNITS)}, got {self.raw_unit!r}")
        if abs(np.linalg.det(self.C)) < 1e-300:
            raise InputShapeError("C is singular: not a gyro model")

    # ------------------------------------------------------------------ IMU-TK's view

    @property
    def K(self) -> np.ndarray:
        """IMU-TK's scale: ``diag(C)`` [rad/s per raw unit] as a diagonal matrix."""
        return np.diag(np.diag(self.C))

    @property
    def T(self) -> np.ndarray:
        """IMU-TK's misalignment: ``C K⁻¹`` (unit diagonal)."""
        return self.C / np.diag(self.C)[None, :]

    def scale_factors(self, nominal: float | None = None) -> np.ndarray:
        """``diag(C) / nominal - 1``: the scale error relative to the nominal factor (rad/s per
        raw unit; default the unit's own, 1 or π/180; required for counts)."""
        k = RAW_UNITS[self.raw_unit] if nominal is None else float(nominal)
        if k is None:
            raise InputShapeError("counts have no nominal factor to rad/s: pass the nominal sensitivity")
        return np.diag(self.C) / k - 1.0

    @property
    def sensing_axes(self) -> np.ndarray:
        """Unit sensing axis of each gyro (rows) in the accelerometer frame: rows of ``C⁻¹``, normalised."""
        A = np.linalg.inv(self.C)
        return A / np.linalg.norm(A, axis=1, keepdims=True)

    @property
    def axis_misalignment_deg(self) -> np.ndarray:
        """Angle [deg] between each gyro's sensing axis and the same accelerometer-frame axis."""
        return np.rad2deg(np.arccos(np.clip(np.abs(np.diag(self.sensing_axes)), -1.0, 1.0)))

    # ------------------------------------------------------------------ applying

    def correct(self, raw, specific_force=None) -> np.ndarray:
        """Angular rate [rad/s] of raw samples ``raw`` (n, 3); ``specific_force`` (n, 3) [m/s²]
        is needed when the model has a g-sensitivity."""
        y = np.asarray(raw, dtype=float) - self.bias
        if self.g_sensitivity is not None:
            if specific_force is None:
                raise InputShapeError("this gyro model has a g-sensitivity: pass the calibrated specific force")
            y = y - np.asarray(specific_force, float) @ self.g_sensitivity.T
        return y @ self.C.T

    def measure(self, rate, specific_force=None) -> np.ndarray:
        """Inverse of :meth:`correct`: the raw samples a rate [rad/s] (n, 3) produces (simulation)."""
        y = np.linalg.solve(self.C, np.asarray(rate, float).T).T + self.bias
        if self.g_sensitivity is not None and specific_force is not None:
            y = y + np.asarray(specific_force, float) @ self.g_sensitivity.T
        return y

    # ------------------------------------------------------------------ peers

    def to_imutk(self) -> dict:
        """IMU-TK's ``T`` (3x3), ``K`` (3x3), ``b`` (3) and the six named misalignments."""
        T = self.T
        mis = {"mis_yz": -T[0, 1], "mis_zy": T[0, 2], "mis_zx": -T[1, 2],
               "mis_xz": T[1, 0], "mis_xy": -T[2, 0], "mis_yx": T[2, 1]}
        return {"T": T, "K": self.K, "b": self.bias.copy(), **{k: float(v) for k, v in mis.items()}}

    @classmethod
    def from_imutk(cls, T, K, b, raw_unit: str = "rad/s") -> GyroModel:
        """From IMU-TK's ``x = T K (y - b)`` (its ``.calib`` layout: T, K, b)."""
        T, K = _mat(T, "T"), _mat(K, "K")
        return cls(C=T @ np.diag(np.diag(K)), bias=b, raw_unit=raw_unit)

    def to_imucal(self, out_unit: str = "deg/s") -> dict:
        """imucal's ``K_g``, ``R_g``, ``b_g``, ``K_ga`` for output in ``out_unit`` (imucal: deg/s)."""
        A = np.linalg.inv(self.C) * RAW_UNITS[out_unit]  # raw per out_unit
        k = np.linalg.norm(A, axis=1)
        G = np.zeros((3, 3)) if self.g_sensitivity is None else self.g_sensitivity
        return {"K_g": np.diag(k), "R_g": A / k[:, None], "b_g": self.bias.copy(), "K_ga": G.copy()}

    @classmethod
    def from_imucal(cls, K_g, R_g, b_g, K_ga=None, out_unit: str = "deg/s", raw_unit: str = "deg/s") -> GyroModel:
        """From imucal's ``y = K_g R_g ω + K_ga a + b_g`` (ω in ``out_unit``)."""
        A = _mat(K_g, "K_g") @ _mat(R_g, "R_g") / RAW_UNITS[out_unit]  # raw per rad/s
        G = None if K_ga is None else _mat(K_ga, "K_ga")
        return cls(C=np.linalg.inv(A), bias=b_g, g_sensitivity=G, raw_unit=raw_unit)

    def to_kalibr(self) -> dict:
        """Kalibr's ``M`` (lower triangular, positive diagonal), ``C_gyro_i`` (rotation), ``A``, ``b``
        with ``y = M C_gyro_i ω + A C_gyro_i a + b`` (Kalibr expects rad/s raw data; its ``A``
        multiplies the specific force in the gyro frame, ``IccSensors.py`` l. 1049)."""
        L, Q = lq(np.linalg.inv(self.C))
        G = np.zeros((3, 3)) if self.g_sensitivity is None else self.g_sensitivity
        return {"M": L, "C_gyro_i": Q, "A": G @ Q.T, "b": self.bias.copy()}

    @classmethod
    def from_kalibr(cls, M, C_gyro_i, b, A=None, raw_unit: str = "rad/s") -> GyroModel:
        """From Kalibr's ``y = M C_gyro_i ω + A C_gyro_i a + b``."""
        G = None if A is None else _mat(A, "A") @ _mat(C_gyro_i, "C_gyro_i")
        return cls(C=np.linalg.inv(_mat(M, "M") @ _mat(C_gyro_i, "C_gyro_i")), bias=b, g_sensitivity=G,
                   raw_unit=raw_unit)

    def rotated(self, Q) -> GyroModel:
        """The same gyro with its output expressed in a frame rotated by ``Q`` (``ω' = Q ω``)."""
        return GyroModel(C=_mat(Q, "Q") @ self.C, bias=self.bias, g_sensitivity=self.g_sensitivity,
                         raw_unit=self.raw_unit)

    # ------------------------------------------------------------------ serialisation

    def to_dict(self) -> dict:
        imutk = self.to_imutk()
        d = {"model": "omega = C (y - b - G f), C = T K", "raw_unit": self.raw_unit, "rate_unit": "rad/s",
             "C": self.C.tolist(), "bias": self.bias.tolist(),
             "g_sensitivity": None if self.g_sensitivity is None else self.g_sensitivity.tolist(),
             "T": imutk["T"].tolist(), "K": np.diag(self.K).tolist(),
             "misalignment": {k: imutk[k] for k in IMUTK_MISALIGNMENTS},
             "axis_misalignment_deg": self.axis_misalignment_deg.tolist()}
        if RAW_UNITS[self.raw_unit] is not None:
            d["scale_factors"] = self.scale_factors().tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> GyroModel:
        G = d.get("g_sensitivity")
        return cls(C=d["C"], bias=d["bias"], g_sensitivity=None if G is None else G, raw_unit=d["raw_unit"])

    def __eq__(self, other) -> bool:
        if not isinstance(other, GyroModel):
            return NotImplemented
        same_g = (self.g_sensitivity is None) == (other.g_sensitivity is None) and (
            self.g_sensitivity is None or np.array_equal(self.g_sensitivity, other.g_sensitivity))
        return (self.raw_unit == other.raw_unit and np.array_equal(self.C, other.C)
                and np.array_equal(self.bias, other.bias) and same_g)


def lq(A) -> tuple[np.ndarray, np.ndarray]:
    """``A = L Q`` with ``L`` lower triangular (positive diagonal) and ``Q`` a rotation (det +1).

    A proper rotation needs ``det A > 0``; otherwise ``Q`` is a reflection.
    """
    A = _mat(A, "A")
    q, r = np.linalg.qr(A.T)  # A.T = q r  ->  A = r.T q.T
    s = np.sign(np.diag(r))
    s[s == 0] = 1.0
    return (r.T * s[None, :]), (s[:, None] * q.T)


def frame_rotation(sensing_matrix) -> np.ndarray:
    """Rotation ``Q`` from a peer's accelerometer frame to accelcal's.

    ``sensing_matrix`` ``A`` maps the specific force in the peer's frame to raw
    accelerometer output (IMU-TK: ``(T_a K_a)⁻¹``; imucal: ``K_a R_a``).  accelcal's frame
    makes that matrix lower triangular: ``A = M Q`` with ``M`` lower triangular, so
    ``x_accelcal = Q x_peer``, and a peer's gyro model becomes ``model.rotated(Q)``.
    IMU-TK's own accelerometer frame is upper triangular (its z axis along the z
    accelerometer): a small rotation, of the size of its non-orthogonalities.
    """
    return lq(sensing_matrix)[1]


__all__ = ["C_PARAMETERS", "GyroModel", "IMUTK_MISALIGNMENTS", "RAW_UNITS", "frame_rotation", "lq"]
