"""Simulated multi-position gyro sessions with an exactly known rotation per motion.

A motion turns the sensor about up to three body axes at once, each by a minimum-jerk
angle profile ``Φ s(τ)``, ``s = 10τ³ - 15τ⁴ + 6τ⁵``, the profiles staggered in time so
that the rotation axis moves (coning, what separates the integrators).  With ``A_j(t) =
exp([a_j]× φ_j(t))`` the orientation is ``R(t) = A_1 A_2 A_3`` and the body rate is
exact::

    ω = A_3ᵀ A_2ᵀ a_1 φ̇_1 + A_3ᵀ a_2 φ̇_2 + a_3 φ̇_3

so the rotation of the motion is ``A_1(Φ_1) A_2(Φ_2) A_3(Φ_3)`` to machine precision,
whatever the sample rate.  Rates are sampled instantaneously; the peak of ``|φ̇_j|`` is
``1.875 Φ_j / T_j``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fit import MotionSet
from .integrate import expm_so3, log_so3

_PEAK = 1.875  # max of s'(τ) for the minimum-jerk profile


def _s(tau):
    tau = np.clip(tau, 0.0, 1.0)
    return tau ** 3 * (10 - 15 * tau + 6 * tau * tau)


def _ds(tau):
    inside = (tau > 0) & (tau < 1)
    return np.where(inside, 30 * tau ** 2 * (1 - tau) ** 2, 0.0)


@dataclass(frozen=True)
class Motion:
    """Up to three simultaneous rotations ``a_j`` (body axes, unit) by ``angles`` [rad],
    each over ``durations`` [s] starting at ``offsets`` [s]."""

    axes: np.ndarray
    angles: np.ndarray
    durations: np.ndarray
    offsets: np.ndarray

    @property
    def duration(self) -> float:
        return float(np.max(self.offsets + self.durations))

    def rates(self, t) -> np.ndarray:
        """Body rates [rad/s] at times ``t`` (k,) from the motion's start."""
        t = np.asarray(t, float)
        tau = (t[:, None] - self.offsets) / self.durations  # (k, j)
        phi = self.angles * _s(tau)
        dphi = self.angles / self.durations * _ds(tau)
        A = expm_so3(self.axes[None, :, :] * phi[:, :, None])  # (k, j, 3, 3)
        w = np.zeros((len(t), 3))
        tail = np.broadcast_to(np.eye(3), (len(t), 3, 3))
        for j in range(len(self.angles) - 1, -1, -1):  # ω = Σ_j (A_{j+1} ... A_last)ᵀ a_j φ̇_j
            w += np.einsum("kji,j->ki", tail, self.axes[j]) * dphi[:, j:j + 1]
            tail = A[:, j] @ tail
        return w

    def orientations(self, t) -> np.ndarray:
        """Orientation (k, 3, 3) at times ``t`` relative to the start (body -> start body)."""
        tau = (np.asarray(t, float)[:, None] - self.offsets) / self.durations
        A = expm_so3(self.axes[None, :, :] * (self.angles * _s(tau))[:, :, None])
        R = np.broadcast_to(np.eye(3), (len(tau), 3, 3))
        for j in range(len(self.angles)):
            R = R @ A[:, j]
        return R

    def rotation(self) -> np.ndarray:
        """The motion's rotation (end body frame -> start body frame)."""
        R = np.eye(3)
        for a, phi in zip(self.axes, self.angles):
            R = R @ expm_so3(a * phi)
        return R


def random_motion(rng: np.random.Generator, angle_deg: float, peak_rate_dps: float, n_axes: int = 3) -> Motion:
    """A motion of about ``angle_deg`` in total whose fastest axis peaks at ``peak_rate_dps``.

    The total angle is split at random over ``n_axes`` random orthogonal axes; every
    profile lasts ``T = 1.875 max_j Φ_j / peak`` (the largest turn peaks at the given rate;
    one duration keeps the motion's bandwidth that of a hand motion, not of a brief flick
    of a small turn), and they start staggered by up to a third of ``T``.
    """
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    axes = Q.T[:n_axes]
    share = rng.dirichlet(np.full(n_axes, 2.0))
    angles = np.deg2rad(angle_deg) * share * rng.choice([-1.0, 1.0], n_axes)
    peak = np.deg2rad(peak_rate_dps)
    durations = np.full(n_axes, max(_PEAK * np.abs(angles).max() / peak, 1e-3))
    offsets = rng.uniform(0.0, durations[0] / 3, n_axes)
    offsets -= offsets.min()
    return Motion(axes, angles, durations, offsets)


@dataclass(frozen=True)
class SimulatedSession:
    """A simulated session and its truth."""

    data: MotionSet  #: noisy data (y = raw - true bias)
    clean: MotionSet  #: the same without noise (for the CRLB)
    C: np.ndarray  #: true C
    rotations: np.ndarray  #: (m, 3, 3) exact rotation of each motion
    rates: np.ndarray  #: (n, 3) true body rate of every sample [rad/s]


def simulate_session(rng: np.random.Generator, *, n_motions: int = 20, angle_deg: float = 90.0,
                     peak_rate_dps: float = 100.0, fs: float = 100.0, C=None, gyro_noise: float = 0.0,
                     direction_noise: float = 0.0, rest_s: float = 2.0, n_axes: int = 3,
                     bias_var=None) -> SimulatedSession:
    """Rests alternating with random motions; gyro ``y = C⁻¹ ω + noise``.

    Parameters
    ----------
    gyro_noise : float
        White noise std of one raw sample (raw unit; rad/s for ``C ≈ I``).
    direction_noise : float
        Std [rad] of each tangent component of the rest gravity directions.
    bias_var : float, optional
        Variance of the bias error assumed removed in each motion (only enters the
        predicted covariance; the simulated data have no bias error).
    """
    C = np.eye(3) if C is None else np.asarray(C, float)
    h = 1.0 / fs
    n_rest = max(3, int(round(rest_s * fs)))
    R_world = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    R_world *= np.sign(np.linalg.det(R_world))
    up = np.array([0.0, 0.0, 1.0])
    chunks, starts, stops, u, rots = [np.zeros((n_rest, 3))], [], [], [R_world.T @ up], []
    pos = n_rest
    for _ in range(n_motions):
        mo = random_motion(rng, angle_deg, peak_rate_dps, n_axes)
        k = int(np.ceil(mo.duration * fs)) + 1
        w = mo.rates(np.arange(k) * h)
        starts.append(pos - 1)  # last rest sample: rate zero, as in a real session
        chunks.append(w)
        pos += k
        stops.append(pos)  # first sample of the next rest
        chunks.append(np.zeros((n_rest, 3)))
        pos += n_rest
        R = mo.rotation()
        rots.append(R)
        R_world = R_world @ R
        u.append(R_world.T @ up)
    rates = np.concatenate(chunks)
    y_clean = rates @ np.linalg.inv(C).T
    y = y_clean + gyro_noise * rng.standard_normal(y_clean.shape)
    u = np.array(u)
    P = np.eye(3)[None] - u[:, :, None] * u[:, None, :]
    u_noisy = u + direction_noise * np.einsum("pij,pj->pi", P, rng.standard_normal(u.shape))
    u_noisy /= np.linalg.norm(u_noisy, axis=1, keepdims=True)
    m = n_motions
    bv = np.zeros((m, 3)) if bias_var is None else np.full((m, 3), float(bias_var))
    yv = np.full(3, max(gyro_noise, 1e-12) ** 2)
    # a floor on the direction noise keeps the covariance invertible for noise-free data
    cov_floor = max(direction_noise, 1e-9) ** 2 * P
    common = dict(h=h, starts=np.array(starts), stops=np.array(stops), rest_before=np.arange(m),
                  rest_after=np.arange(1, m + 1), y_var=yv, bias_var=bv)
    data = MotionSet(y=y, u=u_noisy, u_cov=cov_floor, **common)
    clean = MotionSet(y=y_clean, u=u, u_cov=cov_floor, **common)
    return SimulatedSession(data, clean, C, np.array(rots), rates)


def simulate_recording(rng: np.random.Generator, *, n_motions: int = 24, angle_deg: float = 100.0,
                       peak_rate_dps: float = 150.0, fs: float = 100.0, rest_s: float = 3.0, init_rest_s: float = 20.0,
                       g: float = 9.81, M=None, acc_bias=None, acc_noise: float = 0.01, C=None, gyro_bias=None,
                       gyro_noise: float = 0.003, g_sensitivity=None, axis=None, bias_walk_psd: float = 0.0,
                       motion_rel_std: float = 0.0, rest_offset_std: float = 0.0) -> dict:
    """A whole multi-position recording (time series) with its truth: an initial rest, then
    motions between rests; the sensor turns about itself (no linear acceleration).

    Accelerometer ``M f + b + noise`` (f the specific force, ``|f| = g``), gyro ``C⁻¹ ω +
    b_g + G f + noise``.  ``axis`` (3,): every motion turns about this one body axis
    (alternating sense), instead of random moving axes.

    What real sessions add (:mod:`accelcal.gyro.noise`): ``bias_walk_psd`` [rad²/s³] a
    random walk of the gyro bias (rate random walk, every axis); ``motion_rel_std`` a
    per-motion error of the rate, ``ω (I + E_i)`` with ``E_i``'s entries N(0, std²) (a
    rotation error of about ``std × angle`` in every direction: a time-stamp or scale
    error of that motion); ``rest_offset_std`` [rad] a per-rest offset of the accelerometer,
    N(0, (g std)²) on each axis (a placement the accelerometer model misses).

    Returns ``t``, ``acc``, ``gyro``, ``rest_intervals`` (the rests' ``[start, stop)``) and
    the truth (``C``, ``M``, the biases, ``G``).
    """
    M = np.eye(3) if M is None else np.asarray(M, float)
    C = np.eye(3) if C is None else np.asarray(C, float)
    ab = np.zeros(3) if acc_bias is None else np.asarray(acc_bias, float)
    gb = np.zeros(3) if gyro_bias is None else np.asarray(gyro_bias, float)
    h = 1.0 / fs
    up = np.array([0.0, 0.0, 1.0])
    R_world = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    R_world *= np.sign(np.linalg.det(R_world))
    n0, nr = int(round(init_rest_s * fs)), int(round(rest_s * fs))
    R, w, rests = _trajectory(rng, R_world, n0, nr, fs, n_motions, angle_deg, peak_rate_dps, axis, motion_rel_std)
    f = g * np.einsum("nji,j->ni", R, up)  # specific force in the body frame
    acc = f @ M.T + ab + acc_noise * rng.standard_normal(f.shape)
    if rest_offset_std:
        for a, b in rests:
            acc[a:b] += g * rest_offset_std * rng.standard_normal(3)
    gyro = w @ np.linalg.inv(C).T + gb + gyro_noise * rng.standard_normal(w.shape)
    if bias_walk_psd:
        walk = np.cumsum(np.sqrt(bias_walk_psd * h) * rng.standard_normal(w.shape), axis=0)
        gyro = gyro + walk @ np.linalg.inv(C).T
    if g_sensitivity is not None:
        gyro = gyro + f @ np.asarray(g_sensitivity, float).T
    return {"t": np.arange(len(f)) * h, "acc": acc, "gyro": gyro, "rates": w, "C": C, "M": M, "acc_bias": ab,
            "gyro_bias": gb, "g_sensitivity": g_sensitivity, "g": g, "rest_intervals": np.array(rests)}


def _trajectory(rng, R_world, n0: int, nr: int, fs: float, n_motions: int, angle_deg: float, peak_rate_dps: float,
                axis, motion_rel_std: float):
    """The session's orientations (n, 3, 3) and body rates (n, 3), sample by sample, and its
    rests' ``[start, stop)``: ``n0`` samples of initial rest, then each motion and ``nr``
    samples of rest (:func:`simulate_recording`)."""
    h = 1.0 / fs
    Rs, ws, rests, pos = [np.broadcast_to(R_world, (n0, 3, 3))], [np.zeros((n0, 3))], [(0, n0)], n0
    for i in range(n_motions):
        if axis is None:
            mo = random_motion(rng, angle_deg, peak_rate_dps)
        else:
            ang = np.deg2rad(angle_deg) * (-1) ** i
            mo = Motion(np.asarray(axis, float)[None] / np.linalg.norm(axis), np.array([ang]),
                        np.array([_PEAK * abs(ang) / np.deg2rad(peak_rate_dps)]), np.zeros(1))
        tt = np.arange(1, int(np.ceil(mo.duration * fs)) + 1) * h
        Rs.append(R_world @ mo.orientations(tt))
        w = mo.rates(tt)
        ws.append(w + w @ (motion_rel_std * rng.standard_normal((3, 3))).T if motion_rel_std else w)
        R_world = R_world @ mo.rotation()
        Rs.append(np.broadcast_to(R_world, (nr, 3, 3)))
        ws.append(np.zeros((nr, 3)))
        pos += len(tt)
        rests.append((pos, pos + nr))
        pos += nr
    return np.concatenate(Rs), np.concatenate(ws), rests


def random_gyro_matrix(rng: np.random.Generator, scale_std: float = 0.02, misalignment_std_deg: float = 1.0,
                       nominal: float = 1.0) -> np.ndarray:
    """A plausible ``C``: ``nominal (I + diag(s)) + off-diagonal misalignments`` (rad)."""
    off = np.deg2rad(misalignment_std_deg) * rng.standard_normal((3, 3))
    np.fill_diagonal(off, 0.0)
    return nominal * (np.eye(3) + np.diag(scale_std * rng.standard_normal(3)) + off)


def rotation_error_deg(R_est, R_true) -> np.ndarray:
    """Angle [deg] of ``R_trueᵀ R_est`` for stacks (m, 3, 3)."""

    return np.rad2deg(np.linalg.norm(log_so3(np.swapaxes(R_true, -1, -2) @ R_est), axis=-1))


__all__ = ["Motion", "SimulatedSession", "random_gyro_matrix", "random_motion", "rotation_error_deg",
           "simulate_recording", "simulate_session"]
