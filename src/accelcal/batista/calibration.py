"""Offline calibration of Batista et al. (2011), Sec. III and Table I.

Multiplying eq. (3) by ``F⁻¹`` gives, at every static sample ``i`` with known
body-to-table rotation ``R_i`` (eq. 5)::

    F⁻¹ a_m(t_i) + R_iᵀ ᵀg - F2 (R_iᵀ ᵀg)² - b' = 0

with ``ᵀg`` gravity in table coordinates (unknown, because the table's levelling
offset is unknown).  Table I:

1. Ignore the quadratic term: stack ``[D_a(t_i), R_iᵀ, -I] (f; ᵀg; b') = 0`` into ``X``
   and take the right singular vector of the smallest singular value.
2. Normalise it so that ``|ᵀg|`` is the known gravity magnitude and its z component
   has the known sign.
3. With the current estimate ``ĝ`` stack
   ``[D_a(t_i), R_iᵀ, -diag((R_iᵀ ĝ)²), -I] (f; ᵀg; f2; b') = 0`` into ``X2``, take its
   smallest right singular vector,
4. and normalise it as in 2.
5. Repeat 3-4 until ``|ĝ_new - ĝ_old|`` falls below a threshold (or an iteration cap:
   then the result says ``converged=False``).

``f`` stacks the rows of ``F⁻¹`` and ``D_a(t) = I₃ ⊗ a_mᵀ(t)``.

:func:`calibrate` builds ``X`` sample by sample and takes its SVD, literally as in the
paper.  :func:`calibrate_batch` solves many Monte Carlo runs at once from per-window
sufficient statistics (count, sum and scatter of ``a_m``): the right singular vectors
of ``X`` are the eigenvectors of ``XᵀX``, which these statistics give exactly because
``R`` is constant within a static window.  Both compute the same estimator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import DegeneratePosesError, InputShapeError, NonFiniteError, NotConvergedError

#: Parameter names, in the order of :meth:`TableCalibration.vector` and of the CRLB.
PARAMETERS = tuple(
    [f"F_inv_{i}{j}" for i in range(1, 4) for j in range(1, 4)]
    + [f"b_prime_{a}" for a in "xyz"] + [f"f2_{a}" for a in "xyz"] + [f"g_table_{a}" for a in "xyz"]
)
#: Parameter groups (name prefix -> slice of :data:`PARAMETERS`).
GROUPS = {"F_inv": slice(0, 9), "b_prime": slice(9, 12), "f2": slice(12, 15), "g_table": slice(15, 18)}

#: The homogeneous system has a one-dimensional null space only if the second smallest
#: singular value clearly exceeds the smallest; for a rich design the ratio is of order
#: g/noise, for rotations that leave a parameter undetermined it sinks to ~1.
NULLSPACE_RATIO = 3.0


@dataclass(frozen=True)
class TableCalibration:
    """Result of Table I for one data set.

    ``F_inv`` (3, 3), ``b_prime`` (3,) [m/s²], ``f2`` (3,) (diagonal of ``F2``, zero for
    the linear-only variant), ``g_table`` (3,) gravity in table coordinates [m/s²];
    ``iterations`` the number of quadratic (step 3-4) solves, ``converged`` whether the
    gravity estimate stopped changing within ``max_iter``, ``gravity_change`` the last
    change ``|ĝ_new - ĝ_old|``, ``singular_values`` those of the last stacked system.
    """

    method: str
    F_inv: np.ndarray
    b_prime: np.ndarray
    f2: np.ndarray
    g_table: np.ndarray
    iterations: int
    converged: bool
    gravity_change: float
    singular_values: np.ndarray = field(default_factory=lambda: np.empty(0))

    @property
    def F(self) -> np.ndarray:
        return np.linalg.inv(self.F_inv)

    @property
    def bias(self) -> np.ndarray:
        """Bias in the sensor output ``b = F b'`` [m/s²]."""
        return self.F @ self.b_prime

    def vector(self) -> np.ndarray:
        """Parameters in the order of :data:`PARAMETERS` (18,)."""
        return np.concatenate([self.F_inv.ravel(), self.b_prime, self.f2, self.g_table])


@dataclass(frozen=True)
class TableCalibrationBatch:
    """Table I over many runs: the fields of :class:`TableCalibration` with a leading run axis."""

    method: str
    F_inv: np.ndarray  # (T, 3, 3)
    b_prime: np.ndarray  # (T, 3)
    f2: np.ndarray  # (T, 3)
    g_table: np.ndarray  # (T, 3)
    iterations: np.ndarray  # (T,) int
    converged: np.ndarray  # (T,) bool
    gravity_change: np.ndarray  # (T,)

    @property
    def bias(self) -> np.ndarray:
        return np.linalg.solve(self.F_inv, self.b_prime[..., None])[..., 0]

    def vectors(self) -> np.ndarray:
        """(T, 18) in the order of :data:`PARAMETERS`."""
        T = len(self.b_prime)
        return np.concatenate([self.F_inv.reshape(T, 9), self.b_prime, self.f2, self.g_table], axis=1)


# ----------------------------------------------------------------------- the literal form


def stack_system(a_m, R, g_hat=None) -> np.ndarray:
    """The stacked matrix ``X`` (``g_hat`` None, 15 columns) or ``X2`` (18 columns).

    Columns are ordered as the paper's unknown vector: ``(f, ᵀg, b')`` or
    ``(f, ᵀg, f2, b')``; three rows per sample.
    """
    a_m = np.asarray(a_m, float)
    R = np.asarray(R, float)
    n = len(a_m)
    Da = np.zeros((n, 3, 9))
    for j in range(3):
        Da[:, j, 3 * j:3 * j + 3] = a_m
    blocks = [Da, np.swapaxes(R, -1, -2)]
    if g_hat is not None:
        gb = np.einsum("nji,j->ni", R, np.asarray(g_hat, float))
        blocks.append(-_diag(gb * gb))
    blocks.append(np.broadcast_to(-np.eye(3), (n, 3, 3)))
    return np.concatenate(blocks, axis=2).reshape(3 * n, -1)


def _diag(v: np.ndarray) -> np.ndarray:
    out = np.zeros(v.shape + (3,))
    for j in range(3):
        out[..., j, j] = v[..., j]
    return out


def _unpack(x: np.ndarray, quadratic: bool):
    """Split a solution vector (…, 15 or 18) into (F_inv, g_table, f2, b_prime)."""
    F_inv = x[..., :9].reshape(x.shape[:-1] + (3, 3))
    g_t = x[..., 9:12]
    if quadratic:
        return F_inv, g_t, x[..., 12:15], x[..., 15:18]
    return F_inv, g_t, np.zeros_like(g_t), x[..., 12:15]


def _normalise(x: np.ndarray, g: float, z_sign: float) -> np.ndarray:
    """Scale null vectors (…, m) so that ``|ᵀg| = g`` and ``sign(ᵀg_z) = z_sign`` (Table I, 2/4)."""
    gt = x[..., 9:12]
    norm = np.linalg.norm(gt, axis=-1)
    if np.any(norm <= 1e-12 * np.linalg.norm(x, axis=-1)):
        raise DegeneratePosesError("the null vector has no gravity component: the rotations do not determine gravity")
    sign = np.where(gt[..., 2] * z_sign < 0, -1.0, 1.0)
    return x * (sign * g / norm)[..., None]


def _check(a_m, R):
    a_m = np.asarray(a_m, float)
    R = np.asarray(R, float)
    if a_m.ndim != 2 or a_m.shape[1] != 3:
        raise InputShapeError(f"a_m must have shape (samples, 3), got {a_m.shape}")
    if R.shape != (len(a_m), 3, 3):
        raise InputShapeError(f"R must have shape ({len(a_m)}, 3, 3) (one rotation per sample), got {R.shape}")
    if not (np.all(np.isfinite(a_m)) and np.all(np.isfinite(R))):
        raise NonFiniteError("a_m or R contains NaN or infinite values")
    if len(a_m) < 6:
        raise DegeneratePosesError(f"{len(a_m)} samples give {3 * len(a_m)} equations for 18 unknowns")
    return a_m, R


def _null_vector(X: np.ndarray):
    _, sv, Vt = np.linalg.svd(X, full_matrices=False)
    if sv[-2] < NULLSPACE_RATIO * sv[-1] or sv[-2] < 1e-12 * sv[0]:
        raise DegeneratePosesError(
            "the table rotations do not determine the calibration (null space of X not one-dimensional): "
            "add attitudes about other axes"
        )
    return Vt[-1], sv


def calibrate(a_m, R, g: float, tol: float = 1e-10, max_iter: int = 50, quadratic: bool = True,
              z_sign: float = 1.0, strict: bool = False) -> TableCalibration:
    """Table I of Batista et al. (2011) on static samples with known table rotations.

    Parameters
    ----------
    a_m : array_like, shape (n, 3)
        Static accelerometer samples [m/s²].
    R : array_like, shape (n, 3, 3)
        Body-to-table rotation of each sample (from the rate table).
    g : float
        Known gravity magnitude [m/s²].
    tol : float
        Stop when ``|ĝ_new - ĝ_old| < tol`` [m/s²] (Table I, step 5).
    max_iter : int
        Cap on the quadratic solves (steps 3-4).
    quadratic : bool
        False stops after steps 1-2 (model without ``F2``; ``f2`` reported as zero).
    z_sign : float
        Known sign of the z component of gravity in table coordinates (+1 for a
        z-down table frame).
    strict : bool
        Raise :class:`NotConvergedError` instead of returning ``converged=False``.

    Returns
    -------
    TableCalibration

    Raises
    ------
    InputShapeError, NonFiniteError, DegeneratePosesError, NotConvergedError
    """
    a_m, R = _check(a_m, R)
    x, sv = _null_vector(stack_system(a_m, R))
    x = _normalise(x, g, z_sign)
    F_inv, g_t, f2, bp = _unpack(x, False)
    if not quadratic:
        return TableCalibration("batista2011_linear", F_inv, bp, f2, g_t, 0, True, 0.0, sv)
    change, it, converged = np.inf, 0, False
    while it < max_iter:
        x, sv = _null_vector(stack_system(a_m, R, g_t))
        x = _normalise(x, g, z_sign)
        it += 1
        F_inv, g_new, f2, bp = _unpack(x, True)
        change = float(np.linalg.norm(g_new - g_t))
        g_t = g_new
        if change < tol:
            converged = True
            break
    if strict and not converged:
        raise NotConvergedError(
            f"Table I did not converge in {max_iter} iterations (last gravity change {change:.3g} m/s²)")
    return TableCalibration("batista2011", F_inv, bp, f2, g_t, it, converged, change, sv)


# ------------------------------------------------------------------------- batched form


@dataclass(frozen=True)
class WindowStatistics:
    """Sufficient statistics of static windows: ``count`` (K,), ``sum`` (T, K, 3), ``scatter`` (T, K, 3, 3).

    ``sum`` is ``Σ a_m`` and ``scatter`` ``Σ a_m a_mᵀ`` over the samples of each window.
    """

    count: np.ndarray
    sum: np.ndarray
    scatter: np.ndarray

    @classmethod
    def from_samples(cls, a_windows) -> "WindowStatistics":
        """From samples of shape (K, n, 3) or (T, K, n, 3)."""
        a = np.asarray(a_windows, float)
        if a.ndim == 3:
            a = a[None]
        if a.ndim != 4 or a.shape[-1] != 3:
            raise InputShapeError(f"window samples must have shape (runs, windows, samples, 3), got {a.shape}")
        return cls(count=np.full(a.shape[1], a.shape[2], dtype=float), sum=a.sum(axis=2),
                   scatter=np.einsum("tkni,tknj->tkij", a, a))

    @property
    def means(self) -> np.ndarray:
        return self.sum / self.count[None, :, None]


def gram_matrix(stats: WindowStatistics, R_steps, g_hat=None) -> np.ndarray:
    """``XᵀX`` (or ``X2ᵀX2``) of every run from window statistics, (T, m, m).

    ``X`` has rows ``[D_a(a), C_k]`` with ``C_k`` constant in window ``k``, so
    ``XᵀX = Σ_k [[I₃ ⊗ Σaaᵀ, (Σa) ⊗ C_k rows], [·ᵀ, n_k C_kᵀ C_k]]``.
    """
    Rt = np.swapaxes(np.asarray(R_steps, float), -1, -2)  # (K, 3, 3)
    T, K = stats.sum.shape[:2]
    C = [np.broadcast_to(Rt, (T, K, 3, 3))]
    if g_hat is not None:
        gb = np.einsum("kij,tj->tki", Rt, np.asarray(g_hat, float))
        C.append(-_diag(gb * gb))
    C.append(np.broadcast_to(-np.eye(3), (T, K, 3, 3)))
    C = np.concatenate(C, axis=-1)  # (T, K, 3, m)
    m = C.shape[-1]
    G = np.zeros((T, 9 + m, 9 + m))
    Q = stats.scatter.sum(axis=1)
    for j in range(3):
        G[:, 3 * j:3 * j + 3, 3 * j:3 * j + 3] = Q
        G[:, 3 * j:3 * j + 3, 9:] = np.einsum("tka,tkc->tac", stats.sum, C[:, :, j, :])
    G[:, 9:, :9] = np.swapaxes(G[:, :9, 9:], 1, 2)
    G[:, 9:, 9:] = np.einsum("k,tkjc,tkjd->tcd", stats.count, C, C)
    return G


def _null_vectors(G: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh(G)
    if np.any(w[:, 1] < NULLSPACE_RATIO**2 * np.abs(w[:, 0])) or np.any(w[:, 1] < 1e-24 * w[:, -1]):
        raise DegeneratePosesError(
            "the table rotations do not determine the calibration (null space of X not one-dimensional): "
            "add attitudes about other axes"
        )
    return V[:, :, 0]


def calibrate_batch(stats: WindowStatistics, R_steps, g: float, tol: float = 1e-10, max_iter: int = 50,
                    quadratic: bool = True, z_sign: float = 1.0) -> TableCalibrationBatch:
    """Table I for many runs at once from window statistics (same estimator as :func:`calibrate`).

    Runs whose gravity estimate stops changing are frozen; the others iterate up to
    ``max_iter`` and are reported with ``converged=False``.

    Parameters
    ----------
    stats : WindowStatistics
        Per-run, per-window count, sum and scatter of ``a_m``.
    R_steps : array_like, shape (K, 3, 3)
        Body-to-table rotation of each window (shared by all runs).
    g, tol, max_iter, quadratic, z_sign
        As in :func:`calibrate`.

    Returns
    -------
    TableCalibrationBatch
    """
    R_steps = np.asarray(R_steps, float)
    if R_steps.shape != (stats.sum.shape[1], 3, 3):
        raise InputShapeError(f"R_steps must have shape ({stats.sum.shape[1]}, 3, 3), got {R_steps.shape}")
    if not (np.all(np.isfinite(stats.sum)) and np.all(np.isfinite(stats.scatter))):
        raise NonFiniteError("window statistics contain NaN or infinite values")
    T = stats.sum.shape[0]
    x = _normalise(_null_vectors(gram_matrix(stats, R_steps)), g, z_sign)
    F_inv, g_t, f2, bp = _unpack(x, False)
    zeros = np.zeros(T)
    if not quadratic:
        return TableCalibrationBatch("batista2011_linear", F_inv, bp, f2, g_t, zeros.astype(int),
                                     np.ones(T, bool), zeros)
    x = np.concatenate([x[:, :12], np.zeros((T, 3)), x[:, 12:]], axis=1)
    it = np.zeros(T, int)
    change = np.full(T, np.inf)
    active = np.ones(T, bool)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if not len(idx):
            break
        sub = WindowStatistics(stats.count, stats.sum[idx], stats.scatter[idx])
        xn = _normalise(_null_vectors(gram_matrix(sub, R_steps, x[idx, 9:12])), g, z_sign)
        change[idx] = np.linalg.norm(xn[:, 9:12] - x[idx, 9:12], axis=1)
        x[idx] = xn
        it[idx] += 1
        active[idx[change[idx] < tol]] = False
    F_inv, g_t, f2, bp = _unpack(x, True)
    return TableCalibrationBatch("batista2011", F_inv, bp, f2, g_t, it, ~active, change)


__all__ = [
    "GROUPS",
    "PARAMETERS",
    "TableCalibration",
    "TableCalibrationBatch",
    "WindowStatistics",
    "calibrate",
    "calibrate_batch",
    "gram_matrix",
    "stack_system",
]
