"""Input checks shared by every estimator: shapes, finiteness, pose count and geometry.

The checks of a single problem run in a few microseconds because the closed forms
themselves do (Burkhard et al. 2024 time them against NLLS): finiteness and geometry
are read from the pose moments (``Σ z``, ``Σ z zᵀ``) that every estimator needs anyway,
and the exact reference check on the centred poses (:func:`check_geometry`) runs only
when the moments do not show the geometry to be clearly fine.  The decisions, and the
errors raised, are those of the reference checks.
"""

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

#: The moment check passes a pose set only if every eigenvalue of its trace-normalised
#: scatter exceeds twice COPLANAR_TOL: the scatter computed from uncentred moments
#: differs from the centred one by rounding of relative size ~1e-16 * Σ|z|² / trace, far
#: below that margin (the check also requires trace > 1e-8 Σ|z|²), so a set it passes
#: passes the reference check too.  Anything else goes to the reference check.
_MOMENT_MARGIN = 2.0
_MIN_SPREAD = 1e-8


def check_poses(z, model: str, batched: bool = False) -> np.ndarray:
    """Validate static pose means ``z`` for ``model`` ('full' or 'bias').

    Returns ``z`` as a float array.  Raises a typed :mod:`accelcal.errors` error with a
    one-line message for wrong shapes, fewer than q+1 poses, non-finite values (or
    values whose squares overflow), or a pose set whose directions are coplanar or
    along one axis only; a non-finite value takes precedence over too few poses.
    """
    z = pose_array(z, model, batched)
    if batched:
        if not np.all(np.isfinite(z)):
            raise NonFiniteError("pose measurements contain NaN or infinite values")
        return z
    s1 = z.sum(axis=0).tolist()
    S2 = (z.T @ z).tolist()
    if not math.isfinite(S2[0][0] + S2[1][1] + S2[2][2]):
        check_finite(z)
        raise NonFiniteError("pose measurements too large: their squares overflow (rescale the data)")
    if not geometry_is_clearly_fine(s1, S2, len(z)):
        check_geometry(z)
    return z


def pose_array(z, model: str, batched: bool = False) -> np.ndarray:
    """``z`` as a float array of shape (poses, 3) (or (trials, poses, 3)) with at least
    q + 1 poses; finiteness is checked first when there are too few poses, so that the
    error is the same as from :func:`check_poses`.  The caller checks finiteness."""
    z = np.asarray(z, dtype=float)
    if z.ndim != (3 if batched else 2) or z.shape[-1] != 3:
        shape = "(trials, poses, 3)" if batched else "(poses, 3)"
        raise InputShapeError(f"pose measurements must have shape {shape}, got {z.shape}")
    need = N_UNKNOWNS[model] + 1
    n = z.shape[-2]
    if n < need:
        check_finite(z)
        what = "full (bias, scale, non-orthogonality)" if model == "full" else "bias-only"
        raise TooFewPosesError(
            f"{n} static poses, but the {what} model needs at least {need} (q + 1 for q = {need - 1} unknowns)"
        )
    return z


def check_finite(z: np.ndarray) -> None:
    if not np.all(np.isfinite(z)):
        raise NonFiniteError("pose measurements contain NaN or infinite values")


def check_g(g) -> float:
    try:
        value = float(g)
    except (TypeError, ValueError):
        raise InputShapeError(f"gravity magnitude g must be a positive finite number, got {g!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise InputShapeError(f"gravity magnitude g must be a positive finite number, got {value}")
    return value


def geometry_is_clearly_fine(s1, S2, n) -> bool:
    """True if the pose moments ``s1 = Σ z`` (3) and ``S2 = Σ z zᵀ`` (3x3 nested lists)
    show the poses to be spread in three dimensions with a wide margin (see
    ``_MOMENT_MARGIN``).  False means "not shown": run :func:`check_geometry`."""
    x, y, w = s1[0] / n, s1[1] / n, s1[2] / n
    (a, b, c), (_, d, e), (_, _, f) = S2
    # scatter about the mean: Σ z zᵀ - n z̄ z̄ᵀ
    C = [[a - n * x * x, b - n * x * y, c - n * x * w], [0.0, d - n * y * y, e - n * y * w],
         [0.0, 0.0, f - n * w * w]]
    return scatter_is_clearly_3d(C, a + d + f)


def scatter_is_clearly_3d(C, sum_sq: float) -> bool:
    """True if the scatter ``C = Σ (z - z̄)(z - z̄)ᵀ`` (3x3 nested lists, upper triangle
    read) has trace above ``_MIN_SPREAD * Σ |z|²`` and every eigenvalue of ``C / trace``
    above ``_MOMENT_MARGIN * COPLANAR_TOL``: then :func:`check_geometry` passes too."""
    (a, b, c), (_, d, e), (_, _, f) = C
    tr = a + d + f
    if not tr > _MIN_SPREAD * sum_sq:
        return False
    # all eigenvalues of C/tr above the shift <=> C/tr - shift I is positive definite
    # <=> its Cholesky pivots are positive
    shift = _MOMENT_MARGIN * COPLANAR_TOL
    a, b, c, d, e, f = a / tr - shift, b / tr, c / tr, d / tr - shift, e / tr, f / tr - shift
    if not a > 0:
        return False
    d2 = d - b * b / a
    if not d2 > 0:
        return False
    e2 = e - b * c / a
    return f - c * c / a - e2 * e2 / d2 > 0


def degenerate_trials(z: np.ndarray, clear: np.ndarray | None = None) -> np.ndarray:
    """(T,) True for the trials of ``z`` (T, n, 3) whose poses :func:`check_poses` refuses
    as degenerate (identical, along one axis, coplanar): the batched estimators mark them
    as the single-problem ones raise, ``DegeneratePosesError``.

    ``clear`` (T,) marks trials already shown clearly three-dimensional by a sound moment
    screen (a compiled batch kernel's, from the moments it forms anyway); without it the
    screen of :func:`scatter_is_clearly_3d` runs vectorised over the trials.  Only the
    trials the screen does not pass (almost none in a Monte Carlo) get the reference check,
    one by one, so every decision is that of the single-problem check."""
    if clear is None:
        clear = _screen_trials(z)
    out = np.zeros(len(z), dtype=bool)
    for t in np.flatnonzero(~np.asarray(clear, dtype=bool)):
        try:
            check_geometry(z[t])
        except DegeneratePosesError:
            out[t] = True
    return out


def _screen_trials(z: np.ndarray) -> np.ndarray:
    """:func:`geometry_is_clearly_fine` of every trial of ``z`` (T, n, 3) at once: the same
    arithmetic on arrays (NaN compares False, as there)."""
    n = z.shape[1]
    m = z.mean(axis=1)
    S2 = np.einsum("tni,tnj->tij", z, z)
    with np.errstate(all="ignore"):
        C = S2 - n * m[:, :, None] * m[:, None, :]
        a, b, c, d, e, f = C[:, 0, 0], C[:, 0, 1], C[:, 0, 2], C[:, 1, 1], C[:, 1, 2], C[:, 2, 2]
        tr = a + d + f
        ok = tr > _MIN_SPREAD * (S2[:, 0, 0] + S2[:, 1, 1] + S2[:, 2, 2])
        shift = _MOMENT_MARGIN * COPLANAR_TOL
        a, b, c, d, e, f = a / tr - shift, b / tr, c / tr, d / tr - shift, e / tr, f / tr - shift
        d2 = d - b * b / a
        e2 = e - b * c / a
        return ok & (a > 0) & (d2 > 0) & (f - c * c / a - e2 * e2 / d2 > 0)


def check_geometry(z: np.ndarray) -> None:
    """Reference check: coplanar or single-axis pose sets do not determine the bias
    along their normal (eigenvalues of the centred scatter of the poses)."""
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
