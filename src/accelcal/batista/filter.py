"""Online bias and gravity filter of Batista et al. (2011), Sec. IV, eq. (7).

State ``x = (v, g, b)`` in body coordinates, with the calibrated accelerometer
``a_m = v̇ + S(ω) v - g + b + n_a`` (eq. 6) as input and the velocity as measurement::

    ẋ = A(t) x + B a_m + n_x,   y = C x + n_y,
    A = [[-S(ω), I, -I], [0, -S(ω), 0], [0, 0, 0]],  B = (I, 0, 0),  C = (I, 0, 0),

``E[n_x n_xᵀ] = Ξ δ``, ``E[n_y n_yᵀ] = Θ δ`` (continuous intensities; the paper uses
``Ξ = diag(1e-3 I, 1e-4 I, 1e-5 I)``, ``Θ = 0.1 I``).

Discretisation (samples every ``dt``; the filter propagates from ``t_k`` to
``t_{k+1}`` when the samples at ``t_{k+1}`` arrive, then updates with ``y_{k+1}``):

* ``ω`` is held at the midpoint ``(ω_k + ω_{k+1})/2`` over the interval; then
  ``Φ = exp(A dt)`` is exact in closed form: with ``E = exp(-S(ω) dt)``,
  ``J0 = ∫₀^dt exp(-S(ω) u) du`` and ``J1 = ∫₀^dt u exp(-S(ω) u) du``::

      Φ = [[E, dt E, -J0], [0, E, 0], [0, 0, I]]

  (the ``v``–``g`` block is ``dt E`` because ``-S`` commutes with itself).
* ``a_m`` is interpolated linearly between samples (first-order hold), so the input
  adds ``(J1/dt) a_k + (J0 - J1/dt) a_{k+1}`` to ``v``.  A zero-order hold would not do:
  ``a_m`` contains ``-g``, which turns at ``|ω| g`` (about 5 m/s³ at 0.5 rad/s), and
  holding it for ``dt = 0.01 s`` biases the integrated acceleration by
  ``|ω| g dt / 2 ≈ 0.025 m/s²`` — a fake bias twenty times the accelerometer noise.
* ``Q = ∫₀^dt Φ(s) Ξ Φ(s)ᵀ ds`` in closed form for ``Ξ = diag(q_v I, q_g I, q_b I)``
  (terms of order ``|ω|⁴ dt⁷`` dropped), and ``R = Θ / dt`` (the covariance of a
  sampled white noise of intensity ``Θ``).

:func:`discretize_van_loan` computes ``Φ``, the input matrices and ``Q`` by matrix
exponentials (Van Loan 1978) for any ``Ξ``; the tests check the closed forms against it.

The step loops of :func:`kalman_filter` and :func:`covariance_sequence` run as compiled
kernels (:mod:`accelcal.batista._filter_kernels`, the same discretisation per step) when
numba is available (:mod:`accelcal.kernels`); the numpy loops here are the reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputShapeError, NonFiniteError
from ..kernels import compiled
from .model import skew

_KERNELS = "batista._filter_kernels"

#: State names in the order of the filter's state vector.
STATES = ("v_x", "v_y", "v_z", "g_x", "g_y", "g_z", "b_x", "b_y", "b_z")
#: Filter parameters of Batista et al. (2011), Sec. V-B: Ξ blocks (v, g, b) and Θ.
PAPER_XI = (1e-3, 1e-4, 1e-5)
PAPER_THETA = 0.1

_SERIES_BELOW = 0.02  # rotation angle per step below which the coefficient series are used


def system_matrix(omega) -> np.ndarray:
    """``A(t)`` of eq. (7) for angular velocities ``omega`` (..., 3) -> (..., 9, 9)."""
    S = skew(omega)
    A = np.zeros(S.shape[:-2] + (9, 9))
    A[..., :3, :3] = -S
    A[..., :3, 3:6] = np.eye(3)
    A[..., :3, 6:9] = -np.eye(3)
    A[..., 3:6, 3:6] = -S
    return A


def rotation_coefficients(th: np.ndarray):
    """Rodrigues-type coefficients of θ = |ω| dt that build :func:`rotation_blocks`.

    Parameters
    ----------
    th : array_like
        Rotation angles θ = |ω| dt [rad], any shape.

    Returns
    -------
    list of numpy.ndarray
        ``a, b, c, d, e`` (each of the shape of ``th``): ``sin θ/θ``, ``(1 - cos θ)/θ²``,
        ``(θ - sin θ)/θ³``, ``(sin θ - θ cos θ)/θ³`` and ``∫₀¹ x (1 - cos θx) dx / θ²``,
        by their Taylor series below θ = 0.02 (where the closed forms lose digits).
    """
    th = np.asarray(th, float)
    t2 = th * th
    series = [c0 + t2 * (c1 + t2 * (c2 + t2 * c3)) for c0, c1, c2, c3 in (
        (1.0, -1 / 6, 1 / 120, -1 / 5040),
        (0.5, -1 / 24, 1 / 720, -1 / 40320),
        (1 / 6, -1 / 120, 1 / 5040, -1 / 362880),
        (1 / 3, -1 / 30, 1 / 840, -1 / 45360),
        (0.125, -1 / 144, 1 / 5760, -1 / 403200))]
    small = th < _SERIES_BELOW
    if np.all(small):
        return series
    ts = np.where(small, 1.0, th)  # safe divisor
    s, c = np.sin(ts), np.cos(ts)
    closed = (s / ts, (1 - c) / ts**2, (ts - s) / ts**3, (s - ts * c) / ts**3,
              (0.5 - (c + ts * s - 1) / ts**2) / ts**2)
    return [np.where(small, ser, clo) for ser, clo in zip(series, closed)]


def rotation_blocks(omega, dt: float):
    """``E = exp(-S(ω) dt)``, ``J0 = ∫₀^dt exp(-S(ω)u) du``, ``J1 = ∫₀^dt u exp(-S(ω)u) du``.

    Closed forms (with ``K = S(ω) dt``, ``θ = |ω| dt``)::

        E  = I - (sin θ/θ) K + ((1 - cos θ)/θ²) K²
        J0 = dt [I - ((1 - cos θ)/θ²) K + ((θ - sin θ)/θ³) K²]
        J1 = dt² [I/2 - ((sin θ - θ cos θ)/θ³) K + (∫₀¹ x (1 - cos θx) dx / θ²) K²]

    Parameters
    ----------
    omega : array_like, shape (..., 3)
    dt : float

    Returns
    -------
    E, J0, J1 : numpy.ndarray, each (..., 3, 3)
    """
    w = np.asarray(omega, float) * dt
    K = skew(w)
    th2 = np.einsum("...i,...i->...", w, w)
    K2 = w[..., :, None] * w[..., None, :] - th2[..., None, None] * np.eye(3)  # S(w)² = w wᵀ - |w|² I
    a, b, c, d, e = (x[..., None, None] for x in rotation_coefficients(np.sqrt(th2)))
    eye = np.eye(3)
    E = eye - a * K + b * K2
    J0 = dt * (eye - b * K + c * K2)
    J1 = dt * dt * (0.5 * eye - d * K + e * K2)
    return E, J0, J1


def transition(omega, dt: float):
    """``Φ = exp(A dt)`` (…, 9, 9) and the input matrices ``(G0, G1)`` (…, 9, 3) of one step.

    ``x_{k+1} = Φ x_k + G0 a_k + G1 a_{k+1}`` for ``a_m`` linear between the samples.
    """
    E, J0, J1 = rotation_blocks(omega, dt)
    shape = E.shape[:-2]
    Phi = np.zeros(shape + (9, 9))
    Phi[..., :3, :3] = E
    Phi[..., :3, 3:6] = dt * E
    Phi[..., :3, 6:9] = -J0
    Phi[..., 3:6, 3:6] = E
    Phi[..., 6:9, 6:9] = np.eye(3)
    G0 = np.zeros(shape + (9, 3))
    G1 = np.zeros(shape + (9, 3))
    G0[..., :3, :] = J1 / dt
    G1[..., :3, :] = J0 - J1 / dt
    return Phi, G0, G1


def process_noise(omega, dt: float, xi=PAPER_XI) -> np.ndarray:
    """``Q = ∫₀^dt Φ(s) Ξ Φ(s)ᵀ ds`` for ``Ξ = diag(q_v I, q_g I, q_b I)``, (…, 9, 9)."""
    qv, qg, qb = (float(q) for q in xi)
    S = skew(omega)
    S2 = S @ S
    _, J0, J1 = rotation_blocks(omega, dt)
    eye = np.eye(3)
    Q = np.zeros(S.shape[:-2] + (9, 9))
    Q[..., :3, :3] = (qv * dt + (qg + qb) * dt**3 / 3) * eye + qb * dt**5 / 60 * S2
    Q[..., :3, 3:6] = qg * dt**2 / 2 * eye
    vb = -qb * (dt * J0 - J1)  # -q_b ∫₀^dt J0(s) ds, exactly
    Q[..., :3, 6:9] = vb
    Q[..., 3:6, :3] = qg * dt**2 / 2 * eye
    Q[..., 6:9, :3] = np.swapaxes(vb, -1, -2)
    Q[..., 3:6, 3:6] = qg * dt * eye
    Q[..., 6:9, 6:9] = qb * dt * eye
    return Q


def discretize_van_loan(omega, dt: float, xi) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reference discretisation by matrix exponentials, for one ``ω`` (3,) and any ``Ξ`` (9, 9).

    Returns ``Φ``, ``G0``, ``G1`` (first-order hold of ``a_m``) and ``Q``.
    """
    from scipy.linalg import expm  # here: scipy.linalg costs 0.5 s to import

    A = system_matrix(omega)
    Xi = np.diag(np.repeat(xi, 3)) if np.ndim(xi) == 1 else np.asarray(xi, float)
    B = np.zeros((9, 3))
    B[:3] = np.eye(3)
    # FOH input: a(s) = a_k + (a_{k+1} - a_k) s/dt; integrate with an augmented exponential.
    M = np.zeros((15, 15))
    M[:9, :9] = A
    M[:9, 9:12] = B
    M[9:12, 12:15] = np.eye(3) / dt
    Ea = expm(M * dt)
    Phi, Gam0, Gam1 = Ea[:9, :9], Ea[:9, 9:12], Ea[:9, 12:15]  # Gam1 = ∫ Φ(dt-s) B s/dt ds
    VL = np.zeros((18, 18))
    VL[:9, :9] = -A
    VL[:9, 9:] = Xi
    VL[9:, 9:] = A.T
    Ev = expm(VL * dt)
    Q = Ev[9:, 9:].T @ Ev[:9, 9:]
    return Phi, Gam0 - Gam1, Gam1, 0.5 * (Q + Q.T)


def measurement_covariance(theta, dt: float) -> np.ndarray:
    """Covariance ``Θ/dt`` of the sampled velocity noise (``Θ`` scalar or 3x3 intensity)."""
    th = np.asarray(theta, float)
    if th.ndim != 0 and th.shape != (3, 3):
        raise InputShapeError(f"theta must be a scalar or 3x3, got shape {th.shape}")
    return (th * np.eye(3) if th.ndim == 0 else th) / dt


@dataclass(frozen=True)
class FilterResult:
    """A run of the filter: estimates ``x`` and the filter's own ``sigma = sqrt(diag P)``.

    Both at the times ``t`` (the recorded, possibly decimated, samples), shape (n, 9),
    states in the order of :data:`STATES`.
    """

    t: np.ndarray
    x: np.ndarray
    sigma: np.ndarray
    states: tuple[str, ...] = STATES

    @property
    def velocity(self) -> np.ndarray:
        return self.x[:, :3]

    @property
    def gravity(self) -> np.ndarray:
        return self.x[:, 3:6]

    @property
    def bias(self) -> np.ndarray:
        return self.x[:, 6:9]


def _check_series(t, *arrays):
    t = np.asarray(t, float)
    if t.ndim != 1 or len(t) < 2:
        raise InputShapeError("t must be a 1-D array of at least two sample times")
    dts = np.diff(t)
    dt = float(np.mean(dts))
    if not np.all(np.abs(dts - dt) <= 1e-6 * dt) or dt <= 0:
        raise InputShapeError("the filter needs uniformly sampled, increasing times")
    out = []
    for a in arrays:
        a = np.asarray(a, float)
        if a.shape[-2:] != (len(t), 3):
            raise InputShapeError(f"signals must have shape (..., {len(t)}, 3), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise NonFiniteError("filter inputs contain NaN or infinite values")
        out.append(a)
    return t, dt, out


def _check_shape(name: str, a: np.ndarray, shape: tuple) -> np.ndarray:
    if a.shape != shape:
        raise InputShapeError(f"{name} must have shape {shape}, got {a.shape}")
    return a


def _initial_covariance(P0) -> np.ndarray:
    """``P0`` (9, 9), or its diagonal (9,), as a new (9, 9) array."""
    P0 = np.asarray(P0, float)
    P = np.diag(P0) if P0.ndim == 1 else np.array(P0)
    return _check_shape("P0", P, (9, 9))


def _kalman_numpy(dt, a_m, omega_m, y, x, P, xi, Rd, keep, xs, ss):
    """The numpy reference of the compiled filter kernel: :func:`kalman_filter`'s recursion
    from ``(x, P)`` at ``t[0]``, writing the kept estimates and their σ into ``xs``, ``ss``
    (row 0 already holds ``t[0]``'s)."""
    n = len(a_m)
    wbar = 0.5 * (omega_m[1:] + omega_m[:-1])
    Phi_all, G0_all, G1_all = transition(wbar, dt)
    Q_all = process_noise(wbar, dt, xi)
    j = 1
    for k in range(n - 1):
        Phi = Phi_all[k]
        x = Phi @ x + G0_all[k] @ a_m[k] + G1_all[k] @ a_m[k + 1]
        P = Phi @ P @ Phi.T + Q_all[k]
        S = P[:3, :3] + Rd
        K = np.linalg.solve(S, P[:3, :]).T  # P Cᵀ S⁻¹ (S symmetric)
        x = x + K @ (y[k + 1] - x[:3])
        IKC = np.eye(9)
        IKC[:, :3] -= K
        P = IKC @ P @ IKC.T + K @ Rd @ K.T  # Joseph form
        if j < len(keep) and keep[j] == k + 1:
            xs[j], ss[j] = x, np.sqrt(np.diag(P))
            j += 1


def kalman_filter(t, a_m, omega_m, y, x0, P0, xi=PAPER_XI, theta=PAPER_THETA, record_every: int = 1) -> FilterResult:
    """The time-varying Kalman filter of Sec. IV for one run (its own covariance).

    Parameters
    ----------
    t : array_like, shape (n,)
        Uniform sample times [s].
    a_m : array_like, shape (n, 3)
        Calibrated accelerometer samples [m/s²].
    omega_m : array_like, shape (n, 3)
        Gyro samples [rad/s] (used in ``A(t)``).
    y : array_like, shape (n, 3)
        Velocity measurements [m/s] (``y[0]`` is not used: ``x0`` is the estimate at ``t[0]``).
    x0 : array_like, shape (9,)
        Initial ``(v, g, b)``.
    P0 : array_like, shape (9, 9) or (9,)
        Initial covariance (or its diagonal).
    xi : sequence of 3 floats
        Intensities ``(q_v, q_g, q_b)`` of ``Ξ = diag(q_v I, q_g I, q_b I)``.
    theta : float or (3, 3)
        Intensity ``Θ`` of the velocity noise.
    record_every : int
        Keep every ``record_every``-th sample of the estimates.

    Returns
    -------
    FilterResult
    """
    t, dt, (a_m, omega_m, y) = _check_series(t, a_m, omega_m, y)
    x = _check_shape("x0", np.array(x0, float), (9,))
    P = _initial_covariance(P0)
    xi = _check_shape("xi", np.array(xi, float), (3,))
    Rd = measurement_covariance(theta, dt)
    n = len(t)
    keep = np.arange(0, n, record_every)
    xs, ss = np.empty((len(keep), 9)), np.empty((len(keep), 9))
    xs[0], ss[0] = x, np.sqrt(np.diag(P))
    K = compiled(_KERNELS)
    if K is not None:
        qv, qg, qb = (float(q) for q in xi)
        mask = np.zeros(n, bool)
        mask[keep] = True
        c = np.ascontiguousarray
        K.kalman_filter(dt, c(a_m), c(omega_m), c(y), x, c(P), c(Rd, dtype=float), qv, qg, qb, mask, xs, ss)
        return FilterResult(t=t[keep], x=xs, sigma=ss)
    _kalman_numpy(dt, a_m, omega_m, y, x, P, xi, Rd, keep, xs, ss)
    return FilterResult(t=t[keep], x=xs, sigma=ss)


def covariance_sequence(t, omega, P0, xi=PAPER_XI, theta=PAPER_THETA, return_covariance: bool = False):
    """Kalman gains and posterior covariances along one angular-velocity history.

    The covariance recursion of the filter depends on the data only through ``ω`` in
    ``A(t)``; along a shared trajectory it can be computed once and its gains applied to
    many Monte Carlo runs (see :func:`accelcal_repro.batista2011.montecarlo.filter_montecarlo`).

    Returns
    -------
    K : numpy.ndarray, shape (n, 9, 3)
        Gain used at sample ``k`` (``K[0]`` is zero: no update at ``t[0]``).
    sigma : numpy.ndarray, shape (n, 9)
        ``sqrt(diag P)`` after the update at every sample.
    P : numpy.ndarray, shape (n, 9, 9)
        The posterior covariances, only if ``return_covariance``.
    """
    t, dt, (omega,) = _check_series(t, omega)
    P = _initial_covariance(P0)
    xi = _check_shape("xi", np.array(xi, float), (3,))
    Rd = measurement_covariance(theta, dt)
    n = len(t)
    Ks = np.zeros((n, 9, 3))
    Ps = np.empty((n, 9, 9))
    Ps[0] = P
    K = compiled(_KERNELS)
    if K is not None:
        qv, qg, qb = (float(q) for q in xi)
        K.covariance_sequence(dt, np.ascontiguousarray(omega), np.ascontiguousarray(P),
                              np.ascontiguousarray(Rd, dtype=float), qv, qg, qb, Ks, Ps)
        sigma = np.sqrt(np.einsum("kii->ki", Ps))
        return (Ks, sigma, Ps) if return_covariance else (Ks, sigma)
    wbar = 0.5 * (omega[1:] + omega[:-1])
    Phi_all, _, _ = transition(wbar, dt)
    Q_all = process_noise(wbar, dt, xi)
    eye = np.eye(9)
    for k in range(n - 1):
        Phi = Phi_all[k]
        P = Phi @ P @ Phi.T + Q_all[k]
        K = np.linalg.solve(P[:3, :3] + Rd, P[:3, :]).T
        IKC = eye.copy()
        IKC[:, :3] -= K
        P = IKC @ P @ IKC.T + K @ Rd @ K.T
        Ks[k + 1] = K
        Ps[k + 1] = P
    sigma = np.sqrt(np.einsum("kii->ki", Ps))
    return (Ks, sigma, Ps) if return_covariance else (Ks, sigma)


def observability_gramian(t, omega) -> np.ndarray:
    """``W = Σ_k Φ(t_k, t_0)ᵀ Cᵀ C Φ(t_k, t_0) dt`` of eq. (7) over the samples ``t`` (9, 9).

    Sec. IV: the system is observable on ``[t_0, t_f]`` if and only if the direction of
    ``ω`` changes; otherwise ``W`` is singular, with null vector ``(0, n, n)`` for ``ω``
    along ``n`` (the components of ``g`` and ``b`` along the rotation axis are
    indistinguishable).
    """
    t, dt, (omega,) = _check_series(t, omega)
    Phi_all, _, _ = transition(0.5 * (omega[1:] + omega[:-1]), dt)
    Phi = np.eye(9)
    W = Phi[:3].T @ Phi[:3] * dt
    for k in range(len(t) - 1):
        Phi = Phi_all[k] @ Phi
        W += Phi[:3].T @ Phi[:3] * dt
    return 0.5 * (W + W.T)


__all__ = [
    "PAPER_THETA",
    "PAPER_XI",
    "STATES",
    "FilterResult",
    "covariance_sequence",
    "discretize_van_loan",
    "kalman_filter",
    "measurement_covariance",
    "observability_gramian",
    "process_noise",
    "rotation_blocks",
    "rotation_coefficients",
    "system_matrix",
    "transition",
]
