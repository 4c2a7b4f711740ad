"""Tereshkov's virtual-platform AHRS and closed-form bias estimator, batched over runs.

Attitude (the first stage, eqs. 1–3).  ``C`` maps sensor ("body") vectors to the
virtual platform, which is kept level and north-aligned:

    Ċ = C ω̃_b - ω̃_p C                                   (1)
    f_p = C f_b                                          (2)
    ω_p = -k̃_p (f_ext - f_p),   k = -k g/|g|,  k = 1/(τ g)   (3)

With ``g_n = (0, 0, g)`` in NED, ``k_p = (0, 0, -k)`` and (3) reads
``ω_p = (-k d_E, k d_N, 0)``, ``d = f_ext - f_p``: the level torque.  Eq. (3) has no
vertical component; the paper holds the heading error at zero by the GNSS velocity
direction, which is done here by a vertical torque ``ω_p,D = (ψ_AHRS - ψ_course)/τ_ψ``
while the GNSS speed exceeds ``min_speed`` (τ_ψ = ``heading_tau``).

Bias estimation (the second stage).  The residual torque in the body frame is
``u = Cᵀ δω_p`` (on a flat non-rotating Earth the nominal platform rate is zero, so
``δω_p = ω_p``).  In the steady state (eq. 11)
``u = b_g - ω̃_b (ω̃_b + kgI)⁻¹ (b_g - k̃_p b_a)``, hence

* straight motion (ω_b = 0):   ``b_g = u``                                    (12)
* turning at yaw rate ω_z with the gyro bias compensated:
  ``b_a = g [[1/ω_z, -τ, 0], [τ, 1/ω_z, 0], [0, 0, 0]] u``                      (14)

Both pass through first-order low-pass filters (time constants ``gyro_filter_s`` and
``accel_filter_s``).  The estimates are subtracted from the IMU data before they
enter the AHRS (the gyro compensation is what (14) presumes); with this feedback
``u`` measures the *remaining* bias, and the filter is the integrator
``ḃ̂ = (closed form of u) / T``, i.e. the estimate follows the true bias as a first-order
low-pass filter with time constant T.  ``accel_feedback=False`` instead keeps the raw
accelerometer data in the AHRS and low-passes the closed form directly,
``ḃ̂_a = ((14) - b̂_a) / T``.  The estimator outputs ``b̂_g``, ``b̂_a`` for a primary
navigation filter to subtract ("black box" use).

Gating (the paper does not state it; the values are config choices).  The
compensated body z rate is low-passed (``rate_filter_s``).  The motion is *straight*
while ``|ω_z| < straight_rate`` and *turning* while ``|ω_z| > turn_rate``, both only
above ``min_speed``; each estimator updates only after its mode has lasted
``straight_settle_s`` / ``turn_settle_s`` (the closed forms hold in the steady state of
the attitude loop, whose time constant is τ).

Discretisation: ``C ← (I - ω̃_p dt) C exp(ω̃_b dt)`` per IMU sample, the body rotation
to fourth order in the angle, the (tiny) platform rotation to first order, the matrix
re-orthonormalised every :data:`RENORMALISE_EVERY` steps.  :func:`run_estimator` runs
many runs at once (numpy over runs, or, with numba, the compiled kernel
:mod:`accelcal.tereshkov._estimator_kernels`: the same step, run after run);
:func:`run_estimator_scalar` is the same algorithm for one run in plain Python floats
(an independent cross-check).

``accel_formula='eq13'`` replaces (14) by the least-squares solution of the general
steady-state relation (13) ``ω̃_b(ω̃_b + kgI)⁻¹ k̃_b b_a = u`` for ``(b_ax, b_ay)``
with the full body rate and the body-frame vertical ``k_b = Cᵀ k_p`` (an ablation for
tilted installations; the paper uses (14)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..kernels import compiled
from .errors import InputShapeError, InvalidParameterError, NonFiniteError
from .rotations import euler_to_dcm, skew

_KERNELS = "tereshkov._estimator_kernels"

#: Standard gravity [m/s²] and one degree [rad].
G = 9.80665
DEG = np.pi / 180.0

STRAIGHT, TURN, OTHER = 0, 1, 2
#: The attitude matrix is replaced by its nearest rotation every this many steps (the
#: first-order platform rotation leaves a non-orthogonality of |ω_p dt|² ≈ 1e-8 per step).
RENORMALISE_EVERY = 50


@dataclass(frozen=True)
class TereshkovParams:
    """Estimator settings.  Paper: τ = 4 s, both bias filters 40 s.

    Angular thresholds are in degrees per second; times in seconds.
    """

    tau: float = 4.0
    gyro_filter_s: float = 40.0
    accel_filter_s: float = 40.0
    g: float = G
    heading_tau: float = 4.0
    straight_rate_dps: float = 1.0
    turn_rate_dps: float = 3.0
    rate_filter_s: float = 1.0
    straight_settle_s: float = 12.0
    turn_settle_s: float = 8.0
    min_speed: float = 1.0
    accel_feedback: bool = True
    accel_formula: str = "eq14"
    estimate_gyro_z: bool = True
    update_gyro: bool = True
    update_accel: bool = True

    def __post_init__(self):
        for name in ("tau", "gyro_filter_s", "accel_filter_s", "g", "heading_tau", "rate_filter_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InvalidParameterError(f"{name} must be positive and finite, got {v}")
        for name in ("straight_settle_s", "turn_settle_s", "min_speed", "straight_rate_dps"):
            if not getattr(self, name) >= 0:
                raise InvalidParameterError(f"{name} must be non-negative, got {getattr(self, name)}")
        if not self.turn_rate_dps > self.straight_rate_dps:
            raise InvalidParameterError(
                f"turn_rate_dps ({self.turn_rate_dps}) must exceed straight_rate_dps ({self.straight_rate_dps})")
        if self.accel_formula not in ("eq14", "eq13"):
            raise InvalidParameterError(f"accel_formula must be 'eq14' or 'eq13', not {self.accel_formula!r}")

    @property
    def k(self) -> float:
        """Attitude correction gain ``k = 1/(τ g)`` [1/(m/s)]."""
        return 1.0 / (self.tau * self.g)


@dataclass
class EstimatorState:
    """Running state of a batch of estimators (arrays over runs)."""

    C: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    rate_z: np.ndarray
    mode: np.ndarray
    mode_time: np.ndarray
    gyro_time: np.ndarray
    accel_time: np.ndarray
    k: int = 0

    def copy(self) -> "EstimatorState":
        return EstimatorState(*(np.array(getattr(self, f)) for f in
                                ("C", "gyro_bias", "accel_bias", "rate_z", "mode", "mode_time",
                                 "gyro_time", "accel_time")), k=self.k)


def initial_state(accel0, course0, gyro_bias0=None, accel_bias0=None) -> EstimatorState:
    """Level the platform from mean accelerometer data ``accel0`` (R, 3) and align its
    heading with the GNSS course ``course0`` (R,); bias estimates start at zero."""
    f = np.asarray(accel0, dtype=float)
    if f.ndim != 2 or f.shape[1] != 3:
        raise InputShapeError(f"initial accelerometer data must have shape (runs, 3), got {f.shape}")
    R = len(f)
    roll = np.arctan2(-f[:, 1], -f[:, 2])
    pitch = np.arctan2(f[:, 0], np.hypot(f[:, 1], f[:, 2]))
    course = np.asarray(course0, dtype=float).reshape(R)
    # heading of the sensor x axis = course (yaw of ZYX angles equals it exactly)
    C = euler_to_dcm(roll, pitch, course)
    z3 = np.zeros((R, 3))
    return EstimatorState(
        C=C,
        gyro_bias=z3.copy() if gyro_bias0 is None else np.array(gyro_bias0, dtype=float).reshape(R, 3),
        accel_bias=z3.copy() if accel_bias0 is None else np.array(accel_bias0, dtype=float).reshape(R, 3),
        rate_z=np.zeros(R), mode=np.full(R, OTHER), mode_time=np.zeros(R),
        gyro_time=np.zeros(R), accel_time=np.zeros(R),
    )


@dataclass(frozen=True)
class TereshkovResult:
    """Decimated time histories of a batch of estimator runs.

    ``t`` (m,) [s]; ``gyro_bias``, ``accel_bias`` (R, m, 3) estimates [rad/s, m/s²];
    ``u`` (R, m, 3) residual torque [rad/s] at the record instants; ``mode`` (R, m)
    (0 straight, 1 turning, 2 neither) and ``mode_time`` (R, m) how long it has lasted [s];
    ``gyro_time``/``accel_time`` (R, m) seconds spent updating each estimate so far;
    ``C`` (R, m, 3, 3) sensor-to-platform attitude.
    """

    t: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    u: np.ndarray
    mode: np.ndarray
    mode_time: np.ndarray
    gyro_time: np.ndarray
    accel_time: np.ndarray
    C: np.ndarray
    params: TereshkovParams = field(default_factory=TereshkovParams)

    @property
    def n_runs(self) -> int:
        return self.gyro_bias.shape[0]


def concat_results(parts: list[TereshkovResult]) -> TereshkovResult:
    """Join the results of consecutive chunks along time."""
    if not parts:
        raise InputShapeError("no result chunks to join")
    cat = lambda name, ax: np.concatenate([getattr(p, name) for p in parts], axis=ax)
    return TereshkovResult(t=cat("t", 0), gyro_bias=cat("gyro_bias", 1), accel_bias=cat("accel_bias", 1),
                           u=cat("u", 1), mode=cat("mode", 1), mode_time=cat("mode_time", 1), gyro_time=cat("gyro_time", 1),
                           accel_time=cat("accel_time", 1), C=cat("C", 1), params=parts[0].params)


def _check(name, a, shape):
    a = np.asarray(a, dtype=float)
    if a.shape != shape:
        raise InputShapeError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or infinite values")
    return a


def run_estimator(gyro, accel, f_ext, course, speed, dt: float, params: TereshkovParams | None = None,
                  state: EstimatorState | None = None, record_every: int = 100):
    """Run the estimator over ``n`` IMU samples of ``R`` runs.

    Parameters
    ----------
    gyro, accel : array_like, shape (R, n, 3)
        Sensor-frame angular rate [rad/s] and specific force [m/s²], sample ``k`` for
        the step from ``k dt`` to ``(k + 1) dt``.
    f_ext : array_like, shape (R, n, 3)
        External specific force in NED from GNSS [m/s²].
    course, speed : array_like, shape (R, n)
        GNSS course over ground [rad] and horizontal speed [m/s].
    dt : float
        IMU sample interval [s].
    params : TereshkovParams
    state : EstimatorState, optional
        State to continue from (a previous chunk); by default the platform is levelled
        from the first second of accelerometer data and aligned with the first course.
    record_every : int
        Record the state at global sample indices divisible by this.

    Returns
    -------
    (TereshkovResult, EstimatorState)
    """
    params = params or TereshkovParams()
    gyro = np.asarray(gyro, dtype=float)
    if gyro.ndim != 3 or gyro.shape[-1] != 3:
        raise InputShapeError(f"gyro data must have shape (runs, samples, 3), got {gyro.shape}")
    R, n, _ = gyro.shape
    gyro = _check("gyro data", gyro, (R, n, 3))
    accel = _check("accelerometer data", accel, (R, n, 3))
    f_ext = _check("external specific force", f_ext, (R, n, 3))
    course = _check("course", course, (R, n))
    speed = _check("speed", speed, (R, n))
    if not (np.isfinite(dt) and dt > 0):
        raise InvalidParameterError(f"dt must be positive, got {dt}")
    if record_every < 1:
        raise InvalidParameterError(f"record_every must be at least 1, got {record_every}")
    if state is None:
        m0 = min(n, max(1, int(round(1.0 / dt))))
        state = initial_state(accel[:, :m0].mean(axis=1), course[:, 0])
    else:
        state = state.copy()
        if state.C.shape != (R, 3, 3):
            raise InputShapeError(f"state is for {state.C.shape[0]} runs, data for {R}")

    K = compiled(_KERNELS)
    if K is not None:
        return _run_compiled(K, gyro, accel, f_ext, course, speed > params.min_speed, dt, params, state, record_every)
    return _run_numpy(gyro, accel, f_ext, course, speed > params.min_speed, dt, params, state, record_every)


def _run_numpy(gyro, accel, f_ext, course, moving, dt, p: TereshkovParams, state: EstimatorState,
               record_every: int):
    """The numpy reference of the compiled kernel (:func:`run_estimator`'s arguments, checked).

    Structure of arrays, runs last: every per-step operation is one numpy call on (3, R) or
    (3, 3, R) blocks (the loop cost is the number of calls, not the runs)."""
    R, n, _ = gyro.shape
    W_in = np.ascontiguousarray(gyro.transpose(1, 2, 0))
    F_in = np.ascontiguousarray(accel.transpose(1, 2, 0))
    E_in = np.ascontiguousarray(f_ext.transpose(1, 2, 0))
    CO = np.ascontiguousarray(course.T)
    MOV = np.ascontiguousarray(moving.T)
    C = np.ascontiguousarray(state.C.transpose(1, 2, 0))
    v = SimpleNamespace(bg=state.gyro_bias.T.copy(), ba=state.accel_bias.T.copy(), wzf=state.rate_z.copy(),
                        mode=state.mode.copy(), mtime=state.mode_time.copy(), gtime=state.gyro_time.copy(),
                        atime=state.accel_time.copy())
    rec_idx = [i for i in range(n) if (state.k + i) % record_every == 0]
    out = _NumpyRecord(len(rec_idx), R)
    kh = 1.0 / p.heading_tau
    for i in range(n):
        w = W_in[i] - v.bg
        f = F_in[i] - v.ba if p.accel_feedback else F_in[i]
        fp = (C * f).sum(1)  # (2)  f_p = C f
        d = E_in[i] - fp
        herr = np.arctan2(C[1, 0], C[0, 0]) - CO[i]
        herr = (herr + np.pi) % (2 * np.pi) - np.pi
        wp = np.empty((3, R))
        wp[0] = -p.k * d[1]  # (3)  ω_p = -k̃_p (f_ext - f_p)
        wp[1] = p.k * d[0]
        wp[2] = np.where(MOV[i], kh * herr, 0.0)  # heading held by the GNSS course
        u = (C * wp[:, None]).sum(0)  # u = Cᵀ δω_p
        if out.r < len(rec_idx) and rec_idx[out.r] == i:
            out.take(v, u, C)
        _update_biases(v, w, wp, C, u, MOV[i], dt, p)
        C = _propagate(C, w, wp, dt, (state.k + i + 1) % RENORMALISE_EVERY == 0)
    C = C.transpose(2, 0, 1).copy()
    new_state = EstimatorState(C=C, gyro_bias=v.bg.T.copy(), accel_bias=v.ba.T.copy(), rate_z=v.wzf, mode=v.mode,
                               mode_time=v.mtime, gyro_time=v.gtime, accel_time=v.atime, k=state.k + n)
    t_rec = (state.k + np.array(rec_idx, dtype=float)) * dt
    return out.result(t_rec, p), new_state


class _NumpyRecord:
    """The recorded states of :func:`_run_numpy`, runs last until :meth:`result`."""

    def __init__(self, m: int, R: int):
        self.r = 0
        self.bg, self.ba, self.u = np.empty((m, 3, R)), np.empty((m, 3, R)), np.empty((m, 3, R))
        self.mode, self.C = np.empty((m, R), dtype=np.int8), np.empty((m, 3, 3, R))
        self.mt, self.gt, self.at = np.empty((m, R)), np.empty((m, R)), np.empty((m, R))

    def take(self, v, u, C):
        r = self.r
        self.bg[r] = v.bg; self.ba[r] = v.ba; self.u[r] = u; self.mode[r] = v.mode; self.mt[r] = v.mtime
        self.C[r] = C; self.gt[r] = v.gtime; self.at[r] = v.atime
        self.r += 1

    def result(self, t_rec, params) -> TereshkovResult:
        return TereshkovResult(t=t_rec, gyro_bias=self.bg.transpose(2, 0, 1), accel_bias=self.ba.transpose(2, 0, 1),
                               u=self.u.transpose(2, 0, 1), mode=self.mode.T, mode_time=self.mt.T,
                               gyro_time=self.gt.T, accel_time=self.at.T, C=self.C.transpose(3, 0, 1, 2),
                               params=params)


def _update_biases(v, w, wp, C, u, moving, dt: float, p: TereshkovParams):
    """One step of the motion gating and the bias updates of :func:`_run_numpy` (``v`` in place)."""
    # gating on the low-passed compensated body z rate
    v.wzf += (dt / p.rate_filter_s) * (w[2] - v.wzf)
    awz = np.abs(v.wzf)
    straight = moving & (awz < p.straight_rate_dps * DEG)
    turn = moving & (awz > p.turn_rate_dps * DEG)
    new_mode = np.where(straight, STRAIGHT, np.where(turn, TURN, OTHER))
    v.mtime = np.where(new_mode == v.mode, v.mtime + dt, 0.0)
    v.mode = new_mode
    upd_g = straight & (v.mtime >= p.straight_settle_s) & p.update_gyro
    upd_a = turn & (v.mtime >= p.turn_settle_s) & p.update_accel
    if upd_g.any():
        ng = 3 if p.estimate_gyro_z else 2
        v.bg[:ng] += ((dt / p.gyro_filter_s) * upd_g) * u[:ng]  # (12) through the low-pass filter
        v.gtime += dt * upd_g
    if upd_a.any():
        if p.accel_formula == "eq13":
            est = _accel_eq13(w, wp, C, u, p)
        else:
            est = _eq14(u, np.where(upd_a, v.wzf, 1.0), p.g, p.tau)
        step = est if p.accel_feedback else est - v.ba[:2]
        v.ba[:2] += ((dt / p.accel_filter_s) * upd_a) * step
        v.atime += dt * upd_a


def _propagate(C, w, wp, dt: float, renormalise: bool):
    """(1): C <- exp(-ω̃_p dt) C exp(ω̃_b dt); body rotation to 4th order in the angle, the
    platform rotation (|ω_p dt| < 1e-3 rad) to first order, re-orthonormalised when asked
    (every RENORMALISE_EVERY steps)."""
    R = C.shape[-1]
    a = w * dt
    A = (_SKEW @ a).reshape(3, 3, R)
    th2 = (a * a).sum(0)
    CA = (C[:, :, None] * A[None]).sum(1)
    C = C + (1 - th2 * (1 / 6 - th2 / 120)) * CA + (0.5 - th2 * (1 / 24 - th2 / 720)) * (CA[:, :, None] * A[None]).sum(1)
    P = (_SKEW @ (-wp * dt)).reshape(3, 3, R)
    C = C + (P[:, :, None] * C[None]).sum(1)
    if renormalise:
        C = np.ascontiguousarray(_orthonormalise(C.transpose(2, 0, 1)).transpose(1, 2, 0))
    return C


def _run_compiled(K, gyro, accel, f_ext, course, moving, dt, p: TereshkovParams, state: EstimatorState,
                  record_every: int):
    """:func:`run_estimator` by the compiled kernel (one run after the other, the same step)."""
    R, n, _ = gyro.shape
    rec_idx = np.flatnonzero((state.k + np.arange(n)) % record_every == 0)
    m = len(rec_idx)
    out = {"bg": np.empty((R, m, 3)), "ba": np.empty((R, m, 3)), "u": np.empty((R, m, 3)),
           "mode": np.empty((R, m), np.int8), "C": np.empty((R, m, 3, 3)), "mt": np.empty((R, m)),
           "gt": np.empty((R, m)), "at": np.empty((R, m))}
    st = state.copy()
    c = np.ascontiguousarray
    st.C, st.gyro_bias, st.accel_bias = c(st.C, dtype=float), c(st.gyro_bias, dtype=float), c(st.accel_bias, dtype=float)
    st.rate_z, st.mode_time = c(st.rate_z, dtype=float), c(st.mode_time, dtype=float)
    st.gyro_time, st.accel_time, st.mode = c(st.gyro_time, dtype=float), c(st.accel_time, dtype=float), c(st.mode)
    K.run(c(gyro), c(accel), c(f_ext), c(course), c(moving), float(dt), p.k, p.g, p.tau, 1.0 / p.heading_tau,
          dt / p.gyro_filter_s, dt / p.accel_filter_s, dt / p.rate_filter_s, p.straight_rate_dps * DEG,
          p.turn_rate_dps * DEG, p.straight_settle_s, p.turn_settle_s, 3 if p.estimate_gyro_z else 2,
          bool(p.accel_feedback), p.accel_formula == "eq13", bool(p.update_gyro), bool(p.update_accel),
          int(state.k), RENORMALISE_EVERY, st.C, st.gyro_bias, st.accel_bias, st.rate_z, st.mode, st.mode_time,
          st.gyro_time, st.accel_time, rec_idx, out["bg"], out["ba"], out["u"], out["mode"], out["C"], out["mt"],
          out["gt"], out["at"])
    st.k = state.k + n
    t_rec = (state.k + rec_idx.astype(float)) * dt
    res = TereshkovResult(t=t_rec, gyro_bias=out["bg"], accel_bias=out["ba"], u=out["u"], mode=out["mode"],
                          mode_time=out["mt"], gyro_time=out["gt"], accel_time=out["at"], C=out["C"], params=p)
    return res, st


def _eq14(u, rate_z, g: float, tau: float) -> np.ndarray:
    """Eq. (14) on the loop's layout: ``u`` (3, R), ``rate_z`` (R,) -> ``(b_ax, b_ay)`` (2, R)."""
    inv = 1.0 / rate_z
    return g * np.stack([u[0] * inv - tau * u[1], tau * u[0] + u[1] * inv])


#: ``(_SKEW @ a).reshape(3, 3, ...)`` is ``skew(a)`` for ``a`` of shape (3, ...).
_SKEW = np.zeros((9, 3))
_SKEW[1, 2], _SKEW[2, 1], _SKEW[3, 2], _SKEW[5, 0], _SKEW[6, 1], _SKEW[7, 0] = -1, 1, 1, -1, -1, 1


def _orthonormalise(C: np.ndarray) -> np.ndarray:
    """Nearest rotation matrices (polar factor) of ``C`` (..., 3, 3)."""
    U, _, Vt = np.linalg.svd(C)
    return U @ Vt


def _accel_eq13(w, wp, C, u, p: TereshkovParams):
    """Least-squares ``(b_ax, b_ay)`` from (13) with the full body rate and ``k_b = Cᵀ k_p``.

    Arguments in the loop's layout (runs last); returns (2, R).
    """
    w, C, u = w.T, C.transpose(2, 0, 1), u.T
    kg = p.k * p.g
    kb = -p.k * C[:, 2, :]  # Cᵀ (0, 0, -k)
    W = skew(w) @ np.linalg.inv(skew(w) + kg * np.eye(3))
    A = (W @ skew(kb))[:, :, :2]
    AtA = np.einsum("rji,rjk->rik", A, A)
    Atu = np.einsum("rji,rj->ri", A, u)
    det = AtA[:, 0, 0] * AtA[:, 1, 1] - AtA[:, 0, 1] ** 2
    det = np.where(np.abs(det) > 1e-30, det, 1e-30)
    bx = (AtA[:, 1, 1] * Atu[:, 0] - AtA[:, 0, 1] * Atu[:, 1]) / det
    by = (AtA[:, 0, 0] * Atu[:, 1] - AtA[:, 0, 1] * Atu[:, 0]) / det
    return np.stack([bx, by])


def steady_state_torque(gyro_bias, accel_bias, omega_b, params: TereshkovParams | None = None,
                        k_p=None) -> np.ndarray:
    """Eq. (11): ``u = b_g - ω̃_b (ω̃_b + kgI)⁻¹ (b_g - k̃_p b_a)`` (batched over leading axes).

    ``k_p`` defaults to ``(0, 0, -k)`` (level platform, NED).
    """
    params = params or TereshkovParams()
    bg = np.asarray(gyro_bias, dtype=float)
    ba = np.asarray(accel_bias, dtype=float)
    w = np.asarray(omega_b, dtype=float)
    kp = np.array([0.0, 0.0, -params.k]) if k_p is None else np.asarray(k_p, dtype=float)
    kg = params.k * params.g
    W = skew(w) @ np.linalg.inv(skew(w) + kg * np.eye(3))
    rhs = bg - np.einsum("...ij,...j->...i", skew(np.broadcast_to(kp, ba.shape)), ba)
    return bg - np.einsum("...ij,...j->...i", W, rhs)


def accel_bias_from_torque(u, rate_z, params: TereshkovParams | None = None) -> np.ndarray:
    """Eq. (14): ``b_a = g [[1/ω_z, -τ, 0], [τ, 1/ω_z, 0], [0, 0, 0]] u``."""
    params = params or TereshkovParams()
    u = np.asarray(u, dtype=float)
    wz = np.asarray(rate_z, dtype=float)
    if np.any(wz == 0):
        raise InvalidParameterError("eq. (14) needs a non-zero yaw rate")
    g, tau = params.g, params.tau
    return g * np.stack([u[..., 0] / wz - tau * u[..., 1], tau * u[..., 0] + u[..., 1] / wz,
                         np.zeros_like(u[..., 0])], axis=-1)


def _propagate_scalar(C, a0, a1, a2, q0, q1, q2):
    """C <- (I + P) C (I + s A + c A²), A = skew(a) (a = ω_b dt), P = skew(q) (q = -ω_p dt): the
    attitude step of :func:`run_estimator_scalar` in plain floats (lists of rows)."""
    th2 = a0 * a0 + a1 * a1 + a2 * a2
    s = 1 - th2 * (1 / 6 - th2 / 120)
    c = 0.5 - th2 * (1 / 24 - th2 / 720)
    B = [[1 - c * (a1 * a1 + a2 * a2), -s * a2 + c * a0 * a1, s * a1 + c * a0 * a2],
         [s * a2 + c * a0 * a1, 1 - c * (a0 * a0 + a2 * a2), -s * a0 + c * a1 * a2],
         [-s * a1 + c * a0 * a2, s * a0 + c * a1 * a2, 1 - c * (a0 * a0 + a1 * a1)]]
    CB = [[C[r][0] * B[0][j] + C[r][1] * B[1][j] + C[r][2] * B[2][j] for j in range(3)] for r in range(3)]
    return [[CB[0][j] - q2 * CB[1][j] + q1 * CB[2][j] for j in range(3)],
            [q2 * CB[0][j] + CB[1][j] - q0 * CB[2][j] for j in range(3)],
            [-q1 * CB[0][j] + q0 * CB[1][j] + CB[2][j] for j in range(3)]]


def run_estimator_scalar(gyro, accel, f_ext, course, speed, dt: float, params: TereshkovParams | None = None,
                         record_every: int = 100) -> TereshkovResult:
    """The same estimator for one run in plain Python floats (no numpy in the loop).

    An independent second implementation of :func:`run_estimator` (the tests check that
    both agree) and the per-step cost of the algorithm itself for a single run: a few
    hundred floating-point operations, no covariance.  Shapes: (n, 3) and (n,).
    The attitude update is the same (body rotation to 4th order, platform rotation to
    first order, re-orthonormalised every :data:`RENORMALISE_EVERY` steps).
    """
    p = params or TereshkovParams()
    W, F, E, CO, SP = (np.asarray(x, float) for x in (gyro, accel, f_ext, course, speed))
    n = len(W)
    if W.shape != (n, 3) or F.shape != (n, 3) or E.shape != (n, 3) or CO.shape != (n,) or SP.shape != (n,):
        raise InputShapeError("scalar estimator: gyro, accel, f_ext must be (n, 3), course and speed (n,)")
    m0 = min(n, max(1, int(round(1.0 / dt))))
    C = initial_state(F[:m0].mean(axis=0)[None], CO[:1]).C[0].tolist()
    Wl, Fl, El, COl, SPl = W.tolist(), F.tolist(), E.tolist(), CO.tolist(), SP.tolist()
    k, g, tau = p.k, p.g, p.tau
    kh, cg, ca, aw = 1.0 / p.heading_tau, dt / p.gyro_filter_s, dt / p.accel_filter_s, dt / p.rate_filter_s
    thr_s, thr_t = p.straight_rate_dps * DEG, p.turn_rate_dps * DEG
    ng = 3 if p.estimate_gyro_z else 2
    bg, ba = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    wzf, mode, mtime, gtime, atime = 0.0, OTHER, 0.0, 0.0, 0.0
    twopi, pi = 2.0 * math.pi, math.pi
    rec = {k_: [] for k_ in ("t", "bg", "ba", "u", "mode", "mt", "gt", "at", "C")}
    for i in range(n):
        w0, w1, w2 = Wl[i][0] - bg[0], Wl[i][1] - bg[1], Wl[i][2] - bg[2]
        if p.accel_feedback:
            f0, f1, f2 = Fl[i][0] - ba[0], Fl[i][1] - ba[1], Fl[i][2] - ba[2]
        else:
            f0, f1, f2 = Fl[i]
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
        fpN = c00 * f0 + c01 * f1 + c02 * f2
        fpE = c10 * f0 + c11 * f1 + c12 * f2
        dN, dE = El[i][0] - fpN, El[i][1] - fpE
        moving = SPl[i] > p.min_speed
        herr = (math.atan2(c10, c00) - COl[i] + pi) % twopi - pi
        p0, p1, p2 = -k * dE, k * dN, (kh * herr if moving else 0.0)
        u = [c00 * p0 + c10 * p1 + c20 * p2, c01 * p0 + c11 * p1 + c21 * p2, c02 * p0 + c12 * p1 + c22 * p2]
        if i % record_every == 0:
            rec["t"].append(i * dt); rec["bg"].append(list(bg)); rec["ba"].append(list(ba)); rec["u"].append(u)
            rec["mode"].append(mode); rec["mt"].append(mtime); rec["gt"].append(gtime); rec["at"].append(atime)
            rec["C"].append([list(r) for r in C])
        wzf += aw * (w2 - wzf)
        awz = abs(wzf)
        new = STRAIGHT if (moving and awz < thr_s) else (TURN if (moving and awz > thr_t) else OTHER)
        mtime = mtime + dt if new == mode else 0.0
        mode = new
        if mode == STRAIGHT and mtime >= p.straight_settle_s and p.update_gyro:
            for j in range(ng):
                bg[j] += cg * u[j]
            gtime += dt
        if mode == TURN and mtime >= p.turn_settle_s and p.update_accel:
            inv = 1.0 / wzf
            ex, ey = g * (u[0] * inv - tau * u[1]), g * (tau * u[0] + u[1] * inv)  # (14)
            if not p.accel_feedback:
                ex, ey = ex - ba[0], ey - ba[1]
            ba[0] += ca * ex
            ba[1] += ca * ey
            atime += dt
        C = _propagate_scalar(C, w0 * dt, w1 * dt, w2 * dt, -p0 * dt, -p1 * dt, -p2 * dt)
        if (i + 1) % RENORMALISE_EVERY == 0:
            C = _orthonormalise(np.array(C)[None])[0].tolist()
    a = lambda key: np.array(rec[key])[None]
    return TereshkovResult(t=np.array(rec["t"]), gyro_bias=a("bg"), accel_bias=a("ba"), u=a("u"), mode=a("mode"),
                           mode_time=a("mt"), gyro_time=a("gt"), accel_time=a("at"), C=a("C"), params=p)
