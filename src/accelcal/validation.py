"""Input checks shared by every estimator: shapes, finiteness, pose count and geometry."""

from __future__ import annotations

import math

import numpy as np

from .errors import DegeneratePosesError, InputShapeError, NonFiniteError, TooFewPosesError

#: Unknowns of each model: full (b, s, θ) and bias-only (b); closed forms need one more.
N_UNKNOWNS = {"full": 9, "bias": 3}

#: Smallest eigenvalue of the mean outer product of the pose directions below which the
#: poses are called coplanar.  For poses spread over the sphere it is 1/3; for poses on
#: one great circle it is 0, plus the direction noise (≈ (σ/g)²).  1e-3 corresponds to
#: poses that stray only ~2° out of a common plane.
COPLANAR_TOL = 1e-3


def check_poses(z, model: str, batched: bool = False) -> np.ndarray:
    """Validate static pose means ``z`` for ``model`` ('full' or 'bias').

    Returns ``z`` as a float array.  Raises a typed :mod:`accelcal.errors` error with a
    one-line message for wrong shapes, non-finite values, fewer than q+1 poses, or a
    pose set whose directions are coplanar or along one axis only.
    """
    z = np.asarray(z, dtype=float)
    want = 3 if batched else 2
    if z.ndim != want or z.shape[-1] != 3:
        shape = "(trials, poses, 3)" if batched else "(poses, 3)"
        raise InputShapeError(f"pose measurements must have shape {shape}, got {z.shape}")
    if not np.all(np.isfinite(z)):
        raise NonFiniteError("pose measurements contain NaN or infinite values")
    need = N_UNKNOWNS[model] + 1
    n = z.shape[-2]
    if n < need:
        what = "full (bias, scale, non-orthogonality)" if model == "full" else "bias-only"
        raise TooFewPosesError(
            f"{n} static poses, but the {what} model needs at least {need} (q + 1 for q = {need - 1} unknowns)"
        )
    if not batched:
        _check_geometry(z)
    return z


def check_g(g) -> float:
    g = float(g)
    if not np.isfinite(g) or g <= 0:
        raise InputShapeError(f"gravity magnitude g must be a positive finite number, got {g}")
    return g


def _check_geometry(z: np.ndarray) -> None:
    """Coplanar or single-axis pose sets do not determine the bias along their normal."""
    c = z - z.mean(axis=0)
    C = c.T @ c
    tr = C[0, 0] + C[1, 1] + C[2, 2]
    if tr <= 1e-20 * float(np.sum(z * z)):
        raise DegeneratePosesError("all poses are identical: the sensor was never turned")
    # The scatter of the poses about their mean (bias-free) must be three-dimensional,
    # else they lie in one plane (or on one axis).  Eigenvalues of the trace-normalised
    # 3x3 scatter in closed form: numpy's eigvalsh costs more than the arithmetic.
    ev = _sym3_eigvals((C / tr).tolist())
    if ev[1] < COPLANAR_TOL:
        raise DegeneratePosesError("poses differ along one axis only: turn the sensor about at least two axes")
    if ev[0] < COPLANAR_TOL:
        raise DegeneratePosesError("poses lie in one plane: add poses out of that plane (e.g. turn the sensor upside down)")


def _sym3_eigvals(a) -> tuple[float, float, float]:
    """Ascending eigenvalues of a symmetric 3x3 matrix (trigonometric method)."""
    p1 = a[0][1] ** 2 + a[0][2] ** 2 + a[1][2] ** 2
    q = (a[0][0] + a[1][1] + a[2][2]) / 3
    p2 = (a[0][0] - q) ** 2 + (a[1][1] - q) ** 2 + (a[2][2] - q) ** 2 + 2 * p1
    if p2 <= 1e-30:
        return q, q, q
    p = math.sqrt(p2 / 6)
    b = [[(a[i][j] - (q if i == j else 0.0)) / p for j in range(3)] for i in range(3)]
    det = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
           + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]))
    phi = math.acos(min(1.0, max(-1.0, det / 2))) / 3
    e_max = q + 2 * p * math.cos(phi)
    e_min = q + 2 * p * math.cos(phi + 2 * math.pi / 3)
    return e_min, 3 * q - e_max - e_min, e_max
