"""Attitude trajectories for the simulations of Batista et al. (2011), Sec. V.

Two kinds:

* the **stepped table attitude** of the calibration (Sec. V-A): the table holds a
  sequence of attitudes; each step lasts ``step_s`` (22 s) and begins with a
  ``transition_s`` (2 s) move from the previous attitude; ``window_s`` (4 s) of static
  data are used per step; ``static_s`` (180 s) of rest precede the first step and
  follow the last.  The paper shows its attitude sequence only as a figure (Fig. 1);
  :func:`stepped_attitudes` builds one from grids of Euler angles.
* **continuous attitudes** for the online filter (Sec. V-B): Euler angles that are
  sums of sinusoids and ramps (the direction of ``ω`` then changes), or a rotation
  about one fixed body axis (the direction of ``ω`` never changes; Sec. IV's
  observability condition fails).

Conventions are those of :mod:`accelcal.batista.model` (ZYX Euler angles, ``R`` body to
reference, NED reference, ``ω`` in body coordinates).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accelcal.errors import InputShapeError
from accelcal.batista.model import (
    axis_angle_rotation,
    euler_rate_matrix,
    euler_rate_matrix_dot,
    euler_to_rotation,
    skew,
)


# --------------------------------------------------------------------------- stepped


def stepped_attitudes(roll_deg, pitch_deg, yaw_deg) -> np.ndarray:
    """Table attitudes of the calibration: every (pitch, roll) pair, yaw cycling.

    The sequence visits every pitch in ``pitch_deg`` (outer loop) and, for each, every
    roll in ``roll_deg`` (inner loop); step ``k`` takes the yaw ``yaw_deg[k mod len]``.
    With roll over a full turn and pitch over ±60° the body-frame gravity
    ``g (-sin θ, cos θ sin φ, cos θ cos φ)`` visits the whole sphere except the caps
    beyond 60° from the body x axis; the cycling yaw turns the table's vertical axis
    relative to gravity so that the table's levelling offset is seen from all sides.

    Returns
    -------
    numpy.ndarray, shape (K, 3)
        ``(φ, θ, ψ)`` in radians, ``K = len(roll_deg) * len(pitch_deg)``.
    """
    roll, pitch, yaw = (np.atleast_1d(np.asarray(v, float)) for v in (roll_deg, pitch_deg, yaw_deg))
    if roll.ndim != 1 or pitch.ndim != 1 or yaw.ndim != 1 or not (len(roll) and len(pitch) and len(yaw)):
        raise InputShapeError("roll_deg, pitch_deg and yaw_deg must be non-empty lists of angles")
    P, Rl = np.meshgrid(pitch, roll, indexing="ij")
    k = np.arange(P.size)
    eul = np.column_stack([Rl.ravel(), P.ravel(), yaw[k % len(yaw)]])
    return np.deg2rad(eul)


@dataclass(frozen=True)
class StepSchedule:
    """Timing of the stepped calibration trajectory (all in seconds, samples at ``rate``)."""

    n_steps: int
    rate: float = 100.0
    transition_s: float = 2.0
    step_s: float = 22.0
    window_s: float = 4.0
    window_start_s: float = 12.0
    static_s: float = 180.0

    def __post_init__(self):
        if self.n_steps < 1:
            raise InputShapeError("the stepped trajectory needs at least one step")
        if not (self.transition_s <= self.window_start_s
                and self.window_start_s + self.window_s <= self.step_s):
            raise InputShapeError("the data window must lie in the static part of each step")

    @property
    def duration(self) -> float:
        return 2 * self.static_s + self.n_steps * self.step_s

    @property
    def samples_per_window(self) -> int:
        return int(round(self.window_s * self.rate))

    def step_start(self, k) -> np.ndarray:
        return self.static_s + np.asarray(k) * self.step_s

    def window_times(self) -> np.ndarray:
        """Sample times of the data windows, shape ``(n_steps, samples_per_window)``."""
        t0 = self.step_start(np.arange(self.n_steps)) + self.window_start_s
        return t0[:, None] + np.arange(self.samples_per_window)[None, :] / self.rate


def stepped_euler_series(euler_steps, schedule: StepSchedule, rate: float | None = None):
    """Euler angles along the whole stepped trajectory (for figures; Fig. 1 of the paper).

    During a transition the angles move from the previous attitude to the next along a
    smooth (cosine) blend, each angle the short way round (so an angle may leave
    [-180°, 180°) during a transition); they are constant otherwise.

    Returns
    -------
    t : numpy.ndarray, shape (n,)
    euler : numpy.ndarray, shape (n, 3) [rad]
    step_index : numpy.ndarray, shape (n,) of int (-1 in the initial rest)
    """
    e = np.asarray(euler_steps, float)
    rate = schedule.rate if rate is None else float(rate)
    t = np.arange(int(round(schedule.duration * rate)) + 1) / rate
    k = np.floor((t - schedule.static_s) / schedule.step_s).astype(int)
    k = np.clip(k, -1, schedule.n_steps - 1)
    cur = e[np.clip(k, 0, None)]
    prev = e[np.clip(k - 1, 0, None)]
    prev = cur - (cur - prev + np.pi) % (2 * np.pi) + np.pi  # move the short way round
    tau = np.where(k >= 0, (t - schedule.step_start(np.clip(k, 0, None))) / schedule.transition_s, 1.0)
    w = np.where(tau < 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(tau, 0, 1)), 1.0)[:, None]
    return t, prev + w * (cur - prev), k


# ------------------------------------------------------------------------ continuous


@dataclass(frozen=True)
class Attitude:
    """A sampled continuous attitude: ``R`` body to reference, ``ω`` and ``ω̇`` in body axes."""

    t: np.ndarray  # (n,)
    R: np.ndarray  # (n, 3, 3)
    omega: np.ndarray  # (n, 3) rad/s
    omega_dot: np.ndarray  # (n, 3) rad/s²

    @property
    def euler(self) -> np.ndarray:
        """ZYX Euler angles ``(φ, θ, ψ)`` of ``R`` [rad], (n, 3)."""
        return rotation_to_euler(self.R)


def rotation_to_euler(R) -> np.ndarray:
    """ZYX Euler angles of body-to-reference rotations (..., 3, 3) -> (..., 3) [rad]."""
    R = np.asarray(R, float)
    return np.stack([np.arctan2(R[..., 2, 1], R[..., 2, 2]),
                     -np.arcsin(np.clip(R[..., 2, 0], -1, 1)),
                     np.arctan2(R[..., 1, 0], R[..., 0, 0])], -1)


def euler_sinusoid_attitude(t, offset_deg, amplitude_deg, frequency_hz, phase_deg=(0, 0, 0),
                            rate_deg_s=(0, 0, 0)) -> Attitude:
    """Euler angles ``e_j(t) = o_j + A_j sin(2π f_j t + p_j) + r_j t`` (j = roll, pitch, yaw).

    With incommensurate frequencies on at least two angles, the direction of
    ``ω = E(φ, θ) ė`` changes all the time: the observability condition of Sec. IV holds
    on every window longer than a fraction of the slowest period.
    """
    t = np.asarray(t, float)
    o, A, p, r = (np.deg2rad(np.asarray(v, float)) for v in (offset_deg, amplitude_deg, phase_deg, rate_deg_s))
    w = 2 * np.pi * np.asarray(frequency_hz, float)
    arg = w * t[:, None] + p
    e = o + A * np.sin(arg) + r * t[:, None]
    ed = A * w * np.cos(arg) + r
    edd = -A * w * w * np.sin(arg)
    E = euler_rate_matrix(e)
    omega = np.einsum("nij,nj->ni", E, ed)
    omega_dot = np.einsum("nij,nj->ni", euler_rate_matrix_dot(e, ed), ed) + np.einsum("nij,nj->ni", E, edd)
    return Attitude(t=t, R=euler_to_rotation(e), omega=omega, omega_dot=omega_dot)


def constant_axis_attitude(t, axis_body, base_euler_deg, mean_rate_deg_s, amplitude_deg=0.0,
                           frequency_hz=0.0) -> Attitude:
    """Rotation about one fixed body axis ``n``: ``R(t) = R0 exp(S(n) α(t))``.

    ``α(t) = r t + A sin(2π f t)``, so ``ω = α̇ n`` keeps its direction (its magnitude may
    vary).  This violates the observability condition of Sec. IV: the components of
    ``g`` and ``b`` along ``n`` cannot be told apart.
    """
    t = np.asarray(t, float)
    n = np.asarray(axis_body, float)
    if n.shape != (3,) or not np.linalg.norm(n) > 0:
        raise InputShapeError("axis_body must be a non-zero 3-vector")
    n = n / np.linalg.norm(n)
    r, A = np.deg2rad(mean_rate_deg_s), np.deg2rad(amplitude_deg)
    w = 2 * np.pi * float(frequency_hz)
    alpha = r * t + A * np.sin(w * t)
    ad = r + A * w * np.cos(w * t)
    add = -A * w * w * np.sin(w * t)
    R0 = euler_to_rotation(np.deg2rad(np.asarray(base_euler_deg, float)))
    R = R0 @ axis_angle_rotation(n, alpha)
    return Attitude(t=t, R=R, omega=ad[:, None] * n, omega_dot=add[:, None] * n)


def motion_signals(att: Attitude, g_reference, lever_arm=(0.0, 0.0, 0.0)) -> dict[str, np.ndarray]:
    """Body-frame velocity, gravity and specific force of a sensor on a rotating table.

    The sensor sits at ``lever_arm`` (body coordinates, m) from the table's centre of
    rotation, which is fixed in the reference frame, so ``v = ω × r``, ``v̇ = ω̇ × r``,
    ``g_B = Rᵀ g_ref`` and the true specific force is ``a = v̇ + ω × v - g_B``
    (Sec. II).

    Returns
    -------
    dict with ``v``, ``v_dot``, ``g``, ``a`` (each (n, 3)).
    """
    r = np.asarray(lever_arm, float)
    v = np.cross(att.omega, r)
    v_dot = np.cross(att.omega_dot, r)
    g = np.einsum("nji,j->ni", att.R, np.asarray(g_reference, float))
    a = v_dot + np.cross(att.omega, v) - g
    return {"v": v, "v_dot": v_dot, "g": g, "a": a}


__all__ = [
    "Attitude",
    "StepSchedule",
    "constant_axis_attitude",
    "euler_sinusoid_attitude",
    "motion_signals",
    "rotation_to_euler",
    "skew",
    "stepped_attitudes",
    "stepped_euler_series",
]
