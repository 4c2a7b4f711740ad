"""Integrating sampled angular rates into a rotation, five ways, and the Jacobian of the exact-product ones.

Convention: body-frame rate ``ω`` [rad/s], ``Ṙ = R [ω]×``; the rotation ``R`` of an
interval maps vectors of the body frame at its end to the body frame at its start, so a
direction fixed in space (gravity) seen at the start as ``u0`` is seen at the end as
``Rᵀ u0``.  Samples are taken every ``h`` seconds and are the instantaneous rate (a band-
limited signal sampled, not an average over the sample interval).

==============  ===============================================================  ==========
method          what                                                             used by
==============  ===============================================================  ==========
``euler_sum``   one rotation vector, the plain sum ``h Σ ω_k``: exact only for   imucal
                rotations about one fixed axis
``euler``       first-order quaternion steps ``q ← q + h/2 q⊗ω_k``, normalised   naive
``rk4``         classical Runge-Kutta on the quaternion, rate linearly           IMU-TK
                interpolated between samples (midpoint = mean of the two)
``coning``      product of ``exp(φ_k)``, ``φ_k = h(ω_k+ω_{k+1})/2 + h²/12            this module
                ω_k×ω_{k+1}``: the two-sample coning correction (exact Magnus
                to third order for a linearly varying rate)
``magnus4``     product of ``exp(φ_k)``, fourth-order Magnus at the two Gauss    this module
                points, the rate interpolated by the cubic through the four
                samples around the step: ``φ_k = h/2 (w_a + w_b) + √3/12 h²
                w_a×w_b``
==============  ===============================================================  ==========

The Magnus form follows from ``Ṙ = R[ω]×``: ``R(h) = exp([φ]×)`` with ``φ = ∫ω +
½∬_{t2<t1} ω(t2)×ω(t1) + O(h⁵)``; its error is then that of the interpolated rate.  With
linear interpolation (``coning``, ``rk4``) the interpolation error is O(h²) in the rate;
with the cubic (``magnus4``) O(h⁴).  Which one to use is measured, not assumed
(:mod:`accelcal_repro.gyro.integrators`).

For the product methods the derivative of the final rotation with respect to the rates
is exact and cheap: perturbing step ``k`` by ``δφ_k`` turns ``R`` into ``R exp(S_kᵀ
J_r(φ_k) δφ_k)``, with ``S_k`` the product of the later steps and ``J_r`` the right
Jacobian of SO(3); :func:`integrate_intervals` sums this over all steps with suffix
products computed by a log-depth scan (no Python loop over samples).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputShapeError

METHODS = ("euler_sum", "euler", "rk4", "coning", "magnus4")
#: Methods that are a product of ``exp(φ_k)`` and have an exact Jacobian.
PRODUCT_METHODS = ("coning", "magnus4")

_GA, _GB = 0.5 - np.sqrt(3.0) / 6.0, 0.5 + np.sqrt(3.0) / 6.0  # Gauss points on [0, 1]


def _cubic_weights(tau: float) -> np.ndarray:
    """Lagrange weights of the samples at -1, 0, 1, 2 for the cubic's value at ``tau``."""
    return np.array([-tau * (tau - 1) * (tau - 2) / 6, (tau + 1) * (tau - 1) * (tau - 2) / 2,
                     -(tau + 1) * tau * (tau - 2) / 2, (tau + 1) * tau * (tau - 1) / 6])


_WA, _WB = _cubic_weights(_GA), _cubic_weights(_GB)


def skew(v) -> np.ndarray:
    """``[v]×`` for ``v`` (..., 3)."""
    v = np.asarray(v, float)
    S = np.zeros(v.shape + (3,))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def expm_so3(phi) -> np.ndarray:
    """Rotation matrices ``exp([φ]×)`` for rotation vectors (..., 3) (Rodrigues, series near 0)."""
    phi = np.asarray(phi, float)
    t2 = np.sum(phi * phi, axis=-1)[..., None, None]
    t = np.sqrt(t2)
    small = t2 < 1e-8
    ts = np.where(small, 1.0, t)
    a = np.where(small, 1 - t2 / 6 + t2 * t2 / 120, np.sin(ts) / ts)
    b = np.where(small, 0.5 - t2 / 24 + t2 * t2 / 720, (1 - np.cos(ts)) / (ts * ts))
    K = skew(phi)
    return np.eye(3) + a * K + b * (K @ K)


def right_jacobian(phi) -> np.ndarray:
    """Right Jacobian of SO(3): ``exp(φ + δ) ≈ exp(φ) exp(J_r(φ) δ)``, for (..., 3)."""
    phi = np.asarray(phi, float)
    t2 = np.sum(phi * phi, axis=-1)[..., None, None]
    t = np.sqrt(t2)
    small = t2 < 1e-6
    ts = np.where(small, 1.0, t)
    a = np.where(small, 0.5 - t2 / 24 + t2 * t2 / 720, (1 - np.cos(ts)) / (ts * ts))
    b = np.where(small, 1.0 / 6 - t2 / 120 + t2 * t2 / 5040, (ts - np.sin(ts)) / (ts * ts * ts))
    K = skew(phi)
    return np.eye(3) - a * K + b * (K @ K)


def log_so3(R) -> np.ndarray:
    """Rotation vector of rotation matrices (..., 3, 3) (angle in [0, π])."""
    R = np.asarray(R, float)
    c = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)[..., None]
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = np.sin(th)
    near0 = th < 1e-6
    out = np.where(near0, 0.5 * w, th / (2 * np.where(near0, 1.0, s)) * w)
    far = (th[..., 0] > np.pi - 1e-4)
    if np.any(far):  # near π: from the symmetric part
        Rf = R[far]
        B = (Rf + np.swapaxes(Rf, -1, -2)) / 2 + np.eye(3)
        k = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        v = B[np.arange(len(B)), :, k]
        v /= np.linalg.norm(v, axis=-1, keepdims=True)
        v *= np.sign(np.sum(v * w[far], axis=-1, keepdims=True) + 1e-300)
        out[far] = v * th[far]
    return out


def quat_to_matrix(q) -> np.ndarray:
    """Rotation matrices of unit quaternions ``(w, x, y, z)`` (..., 4)."""
    q = np.asarray(q, float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - w * z)
    R[..., 0, 2] = 2 * (x * z + w * y)
    R[..., 1, 0] = 2 * (x * y + w * z)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - w * x)
    R[..., 2, 0] = 2 * (x * z - w * y)
    R[..., 2, 1] = 2 * (y * z + w * x)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def _qdot(q, w):
    """``½ q ⊗ (0, w)`` for quaternions (m, 4) and rates (m, 3)."""
    qw, qv = q[:, :1], q[:, 1:]
    return 0.5 * np.concatenate([-np.sum(qv * w, axis=1, keepdims=True),
                                 qw * w + np.cross(qv, w)], axis=1)


def _check(omega, starts, stops):
    omega = np.asarray(omega, float)
    if omega.ndim != 2 or omega.shape[1] != 3:
        raise InputShapeError(f"rates must have shape (n, 3), got {omega.shape}")
    starts = np.atleast_1d(np.asarray(starts, dtype=np.int64))
    stops = np.atleast_1d(np.asarray(stops, dtype=np.int64))
    if starts.shape != stops.shape or np.any(starts < 0) or np.any(stops >= len(omega)) or np.any(stops <= starts):
        raise InputShapeError("intervals must satisfy 0 <= start < stop < n (samples start..stop, inclusive)")
    return omega, starts, stops


def _step_index(starts, stops, n: int):
    """Base sample of every step, padded: (m, L) indices (padding clamped to the ``n``
    samples), (m, L) mask of real steps."""
    L = int((stops - starts).max())
    k = starts[:, None] + np.arange(L)[None, :]
    return np.minimum(k, n - 1), k < stops[:, None]


def integrate_sequential(omega, h, starts, stops, method: str) -> np.ndarray:
    """Rotations (m, 3, 3) of the intervals ``[start, stop]`` (samples, inclusive; ``h`` a
    constant step or the sample times) by
    ``euler_sum``, ``euler`` or ``rk4`` (any method of :data:`METHODS`: the product ones
    go to :func:`integrate_intervals`).  Time steps are loop iterations, vectorised over
    the intervals."""
    omega, starts, stops = _check(omega, starts, stops)
    if method in PRODUCT_METHODS:
        return integrate_intervals(omega, h, starts, stops, method).R
    k, mask = _step_index(starts, stops, len(omega))
    dts = _step_lengths(h, k, len(omega))
    dts = np.broadcast_to(dts, k.shape)[..., None]  # (m, L, 1)
    if method == "euler_sum":
        return expm_so3(np.sum(np.where(mask[..., None], dts * omega[k], 0.0), axis=1))
    if method not in METHODS:
        raise InputShapeError(f"unknown integrator {method!r}; known: {', '.join(METHODS)}")
    m = len(starts)
    q = np.zeros((m, 4))
    q[:, 0] = 1.0
    for j in range(k.shape[1]):
        w0, w1, on = omega[k[:, j]], omega[np.minimum(k[:, j] + 1, len(omega) - 1)], mask[:, j:j + 1]
        h = dts[:, j]
        if method == "euler":
            qn = q + h * _qdot(q, w0)
        else:  # IMU-TK's quatIntegrationStepRK4
            wm = 0.5 * (w0 + w1)
            k1 = _qdot(q, w0)
            k2 = _qdot(q + 0.5 * h * k1, wm)
            k3 = _qdot(q + 0.5 * h * k2, wm)
            k4 = _qdot(q + h * k3, w1)
            qn = q + h * (k1 + 2 * k2 + 2 * k3 + k4) / 6
        qn /= np.linalg.norm(qn, axis=1, keepdims=True)
        q = np.where(on, qn, q)
    return quat_to_matrix(q)


def _step_lengths(h, k, n):
    """Per-step length (m, L) from a constant step ``h`` or the sample times ``h`` (n,)."""
    if np.ndim(h) == 0:
        return float(h)
    t = np.asarray(h, float)
    return t[np.minimum(k + 1, n - 1)] - t[k]


def _magnus_weights(h, k, n):
    """Lagrange weights (2, 4, m, L) of the samples k-1..k+2 at the two Gauss points of each
    step: the constants for a constant step, else from the sample times (constants where
    the four samples are not distinct, at the recording's ends)."""
    if np.ndim(h) == 0:
        return np.stack([_WA, _WB])[:, :, None, None]
    t = np.asarray(h, float)
    idx = [np.clip(k + o, 0, n - 1) for o in (-1, 0, 1, 2)]
    dt = t[idx[2]] - t[idx[1]]
    ok = (idx[0] < idx[1]) & (idx[2] < idx[3]) & (dt > 0)
    sdt = np.where(ok, dt, 1.0)
    s = [np.where(ok, (t[i] - t[idx[1]]) / sdt, float(o)) for i, o in zip(idx, (-1, 0, 1, 2))]
    out = np.empty((2, 4) + k.shape)
    for g, tau in enumerate((_GA, _GB)):
        for j in range(4):
            w = np.ones(k.shape)
            for i in range(4):
                if i != j:
                    w = w * (tau - s[i]) / (s[j] - s[i])
            out[g, j] = w
    return out


def _increments(omega, h, k, method):
    """``φ_k`` (m, L, 3) and its derivatives ``[(offset, D (m, L, 3, 3))]`` w.r.t. the rate
    samples ``k + offset`` (indices clamped to the recording); ``h`` a constant step or the
    sample times."""
    n = len(omega)
    dt = _step_lengths(h, k, n)
    hh = dt if np.ndim(dt) == 0 else dt[..., None]
    hm = dt if np.ndim(dt) == 0 else dt[..., None, None]
    if method == "coning":
        w0, w1 = omega[np.minimum(k, n - 1)], omega[np.minimum(k + 1, n - 1)]
        phi = 0.5 * hh * (w0 + w1) + hh * hh / 12.0 * np.cross(w0, w1)
        half = 0.5 * hm * np.eye(3)
        return phi, [(0, half - hm * hm / 12.0 * skew(w1)), (1, half + hm * hm / 12.0 * skew(w0))]
    if method == "magnus4":
        W = [omega[np.clip(k + o, 0, n - 1)] for o in (-1, 0, 1, 2)]
        L = _magnus_weights(h, k, n)
        wa = sum(L[0, j][..., None] * w for j, w in enumerate(W))
        wb = sum(L[1, j][..., None] * w for j, w in enumerate(W))
        c = np.sqrt(3.0) / 12.0 * hh * hh
        phi = 0.5 * hh * (wa + wb) + c * np.cross(wa, wb)
        cm = np.sqrt(3.0) / 12.0 * hm * hm
        da = 0.5 * hm * np.eye(3) - cm * skew(wb)  # ∂φ/∂w_a
        db = 0.5 * hm * np.eye(3) + cm * skew(wa)  # ∂φ/∂w_b
        return phi, [(o, L[0, j][..., None, None] * da + L[1, j][..., None, None] * db)
                     for j, o in enumerate((-1, 0, 1, 2))]
    raise InputShapeError(f"{method!r} is not a product integrator; use one of {', '.join(PRODUCT_METHODS)}")


def suffix_products(E, mask) -> np.ndarray:
    """``P[:, k] = E[:, k] E[:, k+1] ... E[:, L-1]`` for (m, L, 3, 3) (entries outside
    ``mask`` are replaced by the identity).

    Two levels of blocks of about ``sqrt(L)`` steps: suffix products inside every block
    (one loop over the block length, all blocks at once), then over the block totals,
    then one product combining them: about three 3x3 products per step and ``2 sqrt(L)``
    Python iterations, instead of a loop over the samples.
    """
    m, L = E.shape[:2]
    b = max(1, int(np.ceil(np.sqrt(L))))
    nb = -(-L // b)
    P = np.broadcast_to(np.eye(3), (m, nb * b, 3, 3)).copy()
    P[:, :L] = np.where(mask[..., None, None], E, np.eye(3))
    P = P.reshape(m, nb, b, 3, 3)
    for j in range(b - 2, -1, -1):  # inside each block
        P[:, :, j] = P[:, :, j] @ P[:, :, j + 1]
    later = np.broadcast_to(np.eye(3), (m, nb, 3, 3)).copy()  # product of all later blocks
    for i in range(nb - 2, -1, -1):
        later[:, i] = P[:, i + 1, 0] @ later[:, i + 1]
    return (P @ later[:, :, None]).reshape(m, nb * b, 3, 3)[:, :L]


def total_products(E, mask) -> np.ndarray:
    """``E[:, 0] E[:, 1] ... E[:, L-1]`` (m, 3, 3) by pairwise reduction (outside ``mask``: identity)."""
    P = np.where(mask[..., None, None], E, np.eye(3))
    while P.shape[1] > 1:
        if P.shape[1] % 2:
            P = np.concatenate([P, np.broadcast_to(np.eye(3), (len(P), 1, 3, 3))], axis=1)
        P = P[:, 0::2] @ P[:, 1::2]
    return P[:, 0]


@dataclass(frozen=True)
class Integration:
    """What :func:`integrate_intervals` returns (``m`` intervals)."""

    R: np.ndarray  #: (m, 3, 3) rotation of each interval
    dphi_dC: np.ndarray | None = None  #: (m, 3, 9): ``R(C + δC) ≈ R exp([dphi_dC vec(δC)]×)``
    G: np.ndarray | None = None  #: (m, 3, 3): a common rate offset ``δω`` rotates by ``G δω``
    Q: np.ndarray | None = None  #: (m, 3, 3): covariance of the rotation from white rate noise


def integrate_intervals(omega, h, starts, stops, method: str = "magnus4", *, raw=None,
                        rate_cov=None) -> Integration:
    """Rotations of the intervals by a product method, their Jacobian in ``C`` and their noise.

    Parameters
    ----------
    omega : array_like, shape (n, 3)
        Rates [rad/s] of the whole recording (neighbouring samples outside an interval
        are used by ``magnus4``'s cubic).
    h : float or array_like (n,)
        Constant sample interval [s], or the sample times [s] (every step its own length;
        ``magnus4`` interpolates through the actual times).
    starts, stops : array_like of int, shape (m,)
        First and last sample of each interval (steps ``start -> stop``).
    method : {'coning', 'magnus4'}
    raw : array_like, shape (n, 3), optional
        ``y`` with ``omega = y Cᵀ``: when given, the derivative of each rotation with
        respect to ``C`` (row-major) and ``G`` (see :class:`Integration`).
    rate_cov : array_like, shape (3, 3), optional
        Covariance of the white noise of one rate sample [rad²/s²] (for sums: the
        per-sample variance times the integrated autocorrelation time): when given, the
        covariance ``Q`` of each interval's rotation vector error, ``Σ_j G_j Σ G_jᵀ``.
    """
    omega, starts, stops = _check(omega, starts, stops)
    if len(starts) <= 2 * GROUP:
        return _integrate(omega, h, starts, stops, method, raw, rate_cov)
    # intervals of similar length together: the padding of each group to its longest stays small
    order = np.argsort(stops - starts, kind="stable")
    parts = [(g, _integrate(omega, h, starts[g], stops[g], method, raw, rate_cov))
             for g in np.array_split(order, -(-len(order) // GROUP))]
    fields = {}
    for name in ("R", "dphi_dC", "G", "Q"):
        if getattr(parts[0][1], name) is None:
            fields[name] = None
            continue
        out = np.empty((len(starts),) + getattr(parts[0][1], name).shape[1:])
        for g, it in parts:
            out[g] = getattr(it, name)
        fields[name] = out
    return Integration(**fields)


#: Intervals integrated together (one padded array) by :func:`integrate_intervals`.
GROUP = 10


def _integrate(omega, h, starts, stops, method, raw, rate_cov) -> Integration:
    k, mask = _step_index(starts, stops, len(omega))
    phi, coefs = _increments(omega, h, k, method)
    phi = np.where(mask[..., None], phi, 0.0)
    if raw is None and rate_cov is None:
        return Integration(total_products(expm_so3(phi), mask))
    P = suffix_products(expm_so3(phi), mask)
    R = P[:, 0]
    m, L = k.shape
    S = np.concatenate([P[:, 1:], np.broadcast_to(np.eye(3), (m, 1, 3, 3))], axis=1)  # later steps
    B = np.where(mask[..., None, None], np.swapaxes(S, -1, -2) @ right_jacobian(phi), 0.0)
    n = len(omega)
    Gpos = np.zeros((m, L + 3, 3, 3))  # ∂φ_end/∂ω at sample start - 1 + position
    dC = np.zeros((m, 3, 3, 3)) if raw is not None else None
    y = None if raw is None else np.asarray(raw, float)
    for off, D in coefs:
        BD = B @ D  # (m, L, 3, 3): ∂φ_end / ∂ω_{k+off}
        Gpos[:, off + 1:off + 1 + L] += BD
        if y is not None:  # Σ_l BD[l, i, a] y[l, b], as one batched matrix product
            dC += (np.swapaxes(BD.reshape(m, L, 9), 1, 2) @ y[np.clip(k + off, 0, n - 1)]).reshape(m, 3, 3, 3)
    Q = None
    if rate_cov is not None:  # Σ_p G_p Σ G_pᵀ = X Xᵀ with X = [G_p Lc]_p
        w, V = np.linalg.eigh(np.asarray(rate_cov, float))
        X = np.swapaxes(Gpos @ (V * np.sqrt(np.clip(w, 0.0, None))), 1, 2).reshape(m, 3, -1)
        Q = X @ np.swapaxes(X, 1, 2)
    return Integration(R, None if dC is None else dC.reshape(m, 3, 9), Gpos.sum(axis=1), Q)


__all__ = ["Integration", "METHODS", "PRODUCT_METHODS", "expm_so3", "integrate_intervals", "integrate_sequential",
           "log_so3",
           "quat_to_matrix", "right_jacobian", "skew", "suffix_products", "total_products"]
