"""Land-vehicle (tractor) simulation for the Tereshkov bias estimator.

Frames and conventions
----------------------
* ``n``: local North-East-Down on a flat, non-rotating Earth (the paper's setting),
  gravity ``g_n = (0, 0, g)``; specific force ``f = a - g_n`` (at rest ``f_n = (0, 0, -g)``).
* ``b``: vehicle body, x forward, y right, z down; ``C_nb = R_z(ψ) R_y(θ) R_x(φ)``.
* ``s``: IMU sensor frame.  The installation (mounting) rotation ``C_bs`` maps sensor
  to body vectors, ``C_bs = R_z(ψ_m) R_y(θ_m) R_x(φ_m)``; the estimator knows nothing of
  it ("any installation error is implicitly treated as a redefinition of body frame axes").

Trajectory
----------
A path is analytic in time, so that any chunk of it can be evaluated exactly and the
simulation can stream through long runs without holding them in memory.  The yaw rate
``r(t)`` and the speed ``v(t)`` are sums of smooth (half-cosine) steps; the heading
``ψ = ψ0 + ∫ r`` has a closed form.  Roll and pitch are sums of a few sinusoids
(terrain), plus a lean of the body in turns proportional to the lateral acceleration
``v r``.  The velocity is along the body x axis (no sideslip): ``v_n = v (cθ cψ, cθ sψ, -sθ)``,
so the pitch is also the slope of the path.

Sensors
-------
IMU at ``imu_rate`` (the sample ``k`` stands for the interval ``[k dt, (k + 1) dt)`` and
is the truth at its midpoint): ``ω_s = C_bsᵀ ω_b + b_g + n_g``, ``f_s = C_bsᵀ f_b + b_a + n_a``,
white noise from noise densities.  GNSS velocity at ``gnss_rate`` with white noise
(horizontal and vertical std); the external specific force is the difference quotient
of consecutive GNSS velocities minus gravity, linearly interpolated to the IMU sample
times (latency-aligned, as a post-processing receiver would); the course over ground
and horizontal speed are interpolated from the same noisy velocities.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from accelcal.tereshkov.errors import InputShapeError, InvalidParameterError
from accelcal.tereshkov.estimator import DEG, G  # noqa: F401  (G: the paper's tractors are on the Earth's surface)
from accelcal.tereshkov.rotations import euler_to_dcm


# ----------------------------------------------------------------------------- paths


@dataclass(frozen=True)
class Path:
    """A batch of ``R`` analytic vehicle paths (one per Monte Carlo run).

    Yaw-rate steps ``yaw_dr`` [rad/s] start at ``yaw_t`` [s] and take ``yaw_ramp`` s;
    speed steps ``speed_dv`` [m/s] start at ``speed_t`` and take ``speed_ramp`` s
    (padding entries have a zero step).  Terrain roll and pitch are
    ``Σ amp sin(2π t / period + phase)`` [rad]; ``lean`` is the body roll per unit
    lateral acceleration [rad / (m/s²)] (outward in turns).
    """

    duration: float
    psi0: np.ndarray
    v0: np.ndarray
    yaw_t: np.ndarray
    yaw_dr: np.ndarray
    speed_t: np.ndarray
    speed_dv: np.ndarray
    roll_terrain: np.ndarray  # (R, K, 3): amp, period, phase
    pitch_terrain: np.ndarray  # (R, K, 3)
    yaw_ramp: float = 3.0
    speed_ramp: float = 4.0
    lean: float = 0.0

    @property
    def n_runs(self) -> int:
        return len(self.psi0)

    def take(self, idx) -> "Path":
        """The runs ``idx`` of the batch."""
        idx = np.asarray(idx)
        kw = {k: getattr(self, k)[idx] for k in
              ("psi0", "v0", "yaw_t", "yaw_dr", "speed_t", "speed_dv", "roll_terrain", "pitch_terrain")}
        return Path(self.duration, yaw_ramp=self.yaw_ramp, speed_ramp=self.speed_ramp, lean=self.lean, **kw)


def _terrain(rng, n_terms, amp_deg, period_s):
    amp = rng.uniform(*amp_deg, n_terms) * DEG
    per = rng.uniform(*period_s, n_terms)
    ph = rng.uniform(0.0, 2 * np.pi, n_terms)
    return np.stack([amp, per, ph], axis=-1)


def field_path(rng: np.random.Generator, duration: float, straight_s=(30.0, 90.0),
               turn_deg=(180.0, 360.0), turn_rate_dps=(5.0, 10.0), cruise_mps=(2.5, 4.0),
               turn_speed_mps=(1.5, 2.5), turn_direction: str = "random",
               first_straight_s: float | None = None, yaw_ramp: float = 3.0,
               speed_ramp: float = 4.0, gap_s: float = 1.0) -> dict:
    """Straight segments joined by turn arcs (field work of a tractor), one run.

    Each straight keeps a cruise speed drawn from ``cruise_mps`` for a time drawn from
    ``straight_s`` (``first_straight_s`` for the first one, if given); the vehicle then
    slows to a turn speed, turns by an angle from ``turn_deg`` at a yaw rate from
    ``turn_rate_dps`` (sign random or alternating), and speeds up again.  Speed ramps
    never overlap yaw ramps (``gap_s`` between them), so the straights are straight.

    Returns a dict of 1-D event arrays for :func:`stack_paths`.
    """
    if turn_direction not in ("random", "alternate"):
        raise InvalidParameterError(f"turn_direction must be 'random' or 'alternate', not {turn_direction!r}")
    if min(straight_s) <= 0 or min(turn_rate_dps) <= 0 or min(turn_deg) <= 0:
        raise InvalidParameterError("straight durations, turn angles and turn rates must be positive")
    v = rng.uniform(*cruise_mps)
    v0, psi0 = v, rng.uniform(0.0, 2 * np.pi)
    yt, ydr, st, sdv = [], [], [], []
    sign = rng.choice((-1.0, 1.0))
    t = 0.0
    first = True
    while t < duration:
        d_s = first_straight_s if (first and first_straight_s is not None) else rng.uniform(*straight_s)
        first = False
        t_dec = t + d_s
        v_turn = rng.uniform(*turn_speed_mps)
        st.append(t_dec), sdv.append(v_turn - v)
        t_yaw = t_dec + speed_ramp + gap_s
        rate = rng.uniform(*turn_rate_dps) * DEG
        angle = rng.uniform(*turn_deg) * DEG
        if turn_direction == "random":
            sign = rng.choice((-1.0, 1.0))
        else:
            sign = -sign
        d_turn = angle / rate
        yt += [t_yaw, t_yaw + d_turn]
        ydr += [sign * rate, -sign * rate]
        t_acc = t_yaw + d_turn + yaw_ramp + gap_s
        v_new = rng.uniform(*cruise_mps)
        st.append(t_acc), sdv.append(v_new - v_turn)
        v = v_new
        t = t_acc + speed_ramp
    return {"psi0": psi0, "v0": v0, "yaw_t": np.array(yt), "yaw_dr": np.array(ydr),
            "speed_t": np.array(st), "speed_dv": np.array(sdv)}


def straight_path(rng: np.random.Generator, duration: float, cruise_mps=(2.5, 4.0),
                  hold_s=(30.0, 90.0), speed_ramp: float = 4.0) -> dict:
    """A single straight line (constant heading) with speed changes every ``hold_s`` s."""
    v = rng.uniform(*cruise_mps)
    v0, psi0 = v, rng.uniform(0.0, 2 * np.pi)
    st, sdv = [], []
    t = rng.uniform(*hold_s)
    while t < duration:
        v_new = rng.uniform(*cruise_mps)
        st.append(t), sdv.append(v_new - v)
        v = v_new
        t += speed_ramp + rng.uniform(*hold_s)
    return {"psi0": psi0, "v0": v0, "yaw_t": np.zeros(0), "yaw_dr": np.zeros(0),
            "speed_t": np.array(st), "speed_dv": np.array(sdv)}


def stack_paths(runs: list[dict], duration: float, rng: np.random.Generator, yaw_ramp: float = 3.0,
                speed_ramp: float = 4.0, lean_deg_per_mps2: float = 0.0, terrain_terms: int = 3,
                terrain_amp_deg=(0.2, 0.8), terrain_period_s=(20.0, 90.0)) -> Path:
    """Batch single-run event dicts into a :class:`Path`, adding terrain roll and pitch.

    Terrain: ``terrain_terms`` sinusoids each for roll and pitch, amplitudes drawn
    from ``terrain_amp_deg`` and periods from ``terrain_period_s``.
    """
    if duration <= 0:
        raise InvalidParameterError(f"duration must be positive, got {duration}")
    if yaw_ramp <= 0 or speed_ramp <= 0:
        raise InvalidParameterError("yaw and speed ramp times must be positive")
    R = len(runs)

    def pad(key):
        n = max(1, max(len(r[key]) for r in runs))
        out = np.zeros((R, n))
        for i, r in enumerate(runs):
            out[i, : len(r[key])] = r[key]
        if key.endswith("_t"):  # padding events sit after the end of the run
            for i, r in enumerate(runs):
                out[i, len(r[key]):] = duration + 1e6
        return out

    terr = lambda: np.stack([_terrain(rng, terrain_terms, terrain_amp_deg, terrain_period_s) for _ in range(R)])
    return Path(
        duration=float(duration),
        psi0=np.array([r["psi0"] for r in runs], dtype=float),
        v0=np.array([r["v0"] for r in runs], dtype=float),
        yaw_t=pad("yaw_t"), yaw_dr=pad("yaw_dr"), speed_t=pad("speed_t"), speed_dv=pad("speed_dv"),
        roll_terrain=terr(), pitch_terrain=terr(),
        yaw_ramp=float(yaw_ramp), speed_ramp=float(speed_ramp), lean=float(lean_deg_per_mps2) * DEG,
    )


def _ramp_sum(t: np.ndarray, times: np.ndarray, steps: np.ndarray, T: float):
    """Σ_j steps_j S((t - times_j)/T) with the half-cosine step S; value, rate, integral.

    Events wholly before ``t.min()`` enter through prefix sums, so only the events
    whose ramps overlap ``[t.min(), t.max()]`` are evaluated per sample.
    Shapes: ``t`` (n,), ``times``/``steps`` (R, S); results (R, n).
    """
    R = times.shape[0]
    done = times + T <= t.min()
    c0 = np.where(done, steps, 0.0).sum(axis=1)  # Σ steps of finished ramps
    c1 = np.where(done, steps * (times + T / 2), 0.0).sum(axis=1)
    active = ~done & (times < t.max())
    value = np.repeat(c0[:, None], len(t), axis=1)
    integral = c0[:, None] * t[None, :] - c1[:, None]
    rate = np.zeros((R, len(t)))
    if active.any():
        cols = np.flatnonzero(active.any(axis=0))
        tj = times[:, cols][:, None, :]
        dj = np.where(active[:, cols], steps[:, cols], 0.0)[:, None, :]
        x = (t[None, :, None] - tj) / T
        xc = np.clip(x, 0.0, 1.0)
        S = 0.5 * (1.0 - np.cos(np.pi * xc))
        dS = np.where((x > 0) & (x < 1), 0.5 * np.pi * np.sin(np.pi * xc), 0.0) / T
        I = np.where(x <= 0, 0.0, np.where(x < 1, xc / 2 - np.sin(np.pi * xc) / (2 * np.pi), x - 0.5)) * T
        value += (dj * S).sum(-1)
        rate += (dj * dS).sum(-1)
        integral += (dj * I).sum(-1)
    return value, rate, integral


def _sines(t, terms):
    amp, per, ph = terms[..., 0][:, None, :], terms[..., 1][:, None, :], terms[..., 2][:, None, :]
    w = 2 * np.pi / per
    arg = w * t[None, :, None] + ph
    return (amp * np.sin(arg)).sum(-1), (amp * w * np.cos(arg)).sum(-1)


@dataclass(frozen=True)
class VehicleState:
    """Truth of a batch of paths at times ``t`` (arrays ``(R, n, ...)``)."""

    t: np.ndarray
    heading: np.ndarray
    yaw_rate: np.ndarray
    speed: np.ndarray
    roll: np.ndarray
    pitch: np.ndarray
    C_nb: np.ndarray
    omega_b: np.ndarray
    v_n: np.ndarray
    a_n: np.ndarray
    f_b: np.ndarray


def vehicle_state(path: Path, t, g: float = G) -> VehicleState:
    """Exact kinematics of ``path`` at times ``t`` (1-D, s): attitude, rates, velocity, forces."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1:
        raise InputShapeError(f"times must be one-dimensional, got shape {t.shape}")
    r, rdot, dpsi = _ramp_sum(t, path.yaw_t, path.yaw_dr, path.yaw_ramp)
    dv, vdot, _ = _ramp_sum(t, path.speed_t, path.speed_dv, path.speed_ramp)
    psi = path.psi0[:, None] + dpsi
    v = path.v0[:, None] + dv
    phi_t, phid_t = _sines(t, path.roll_terrain)
    th, thd = _sines(t, path.pitch_terrain)
    # lean outward in turns: roll = -lean * lateral acceleration (v r), right turn r > 0
    phi = phi_t - path.lean * v * r
    phid = phid_t - path.lean * (vdot * r + v * rdot)
    sf, cf, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    sp, cp = np.sin(psi), np.cos(psi)
    omega = np.stack([phid - r * st, thd * cf + r * sf * ct, -thd * sf + r * cf * ct], axis=-1)
    e = np.stack([ct * cp, ct * sp, -st], axis=-1)
    e_th = np.stack([-st * cp, -st * sp, -ct], axis=-1)
    e_psi = np.stack([-ct * sp, ct * cp, np.zeros_like(ct)], axis=-1)
    v_n = v[..., None] * e
    a_n = vdot[..., None] * e + v[..., None] * (thd[..., None] * e_th + r[..., None] * e_psi)
    C = euler_to_dcm(phi, th, psi)
    fn = a_n - np.array([0.0, 0.0, g])
    f_b = np.einsum("...ji,...j->...i", C, fn)
    return VehicleState(t=t, heading=psi, yaw_rate=r, speed=v, roll=phi, pitch=th, C_nb=C,
                        omega_b=omega, v_n=v_n, a_n=a_n, f_b=f_b)


# ----------------------------------------------------------------------------- sensors


@dataclass(frozen=True)
class SensorSpec:
    """Sensor settings shared by a batch.

    Noise densities: gyro ``gyro_noise`` [rad/s/√Hz], accelerometer ``accel_noise``
    [m/s²/√Hz] (per-sample std = density × √rate); GNSS velocity white noise
    ``gnss_sigma_h`` (north, east) and ``gnss_sigma_v`` (down) [m/s] per epoch.
    """

    imu_rate: float = 100.0
    gnss_rate: float = 10.0
    gyro_noise: float = 0.02 * DEG
    accel_noise: float = 150e-6 * G
    gnss_sigma_h: float = 0.01
    gnss_sigma_v: float = 0.02
    g: float = G

    def __post_init__(self):
        if self.imu_rate <= 0 or self.gnss_rate <= 0 or self.gnss_rate > self.imu_rate:
            raise InvalidParameterError("rates must be positive and the GNSS rate at most the IMU rate")
        if min(self.gyro_noise, self.accel_noise, self.gnss_sigma_h, self.gnss_sigma_v) < 0:
            raise InvalidParameterError("noise levels must be non-negative")


@dataclass(frozen=True)
class VehicleBatch:
    """Everything needed to synthesise the sensor data of ``R`` runs.

    ``C_bs`` (R, 3, 3) installation rotations (sensor to body); ``gyro_bias``,
    ``accel_bias`` (R, 3) in the sensor frame [rad/s, m/s²]; ``seeds`` (R,) integers:
    each run draws its noise from its own streams, so a run's data do not depend on
    the other runs of the batch (two runs with the same seed and path see the same noise).
    """

    path: Path
    sensors: SensorSpec
    C_bs: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    seeds: np.ndarray
    labels: dict = field(default_factory=dict)

    def __post_init__(self):
        R = self.path.n_runs
        for name, shape in (("C_bs", (R, 3, 3)), ("gyro_bias", (R, 3)), ("accel_bias", (R, 3)), ("seeds", (R,))):
            if np.shape(getattr(self, name)) != shape:
                raise InputShapeError(f"{name} must have shape {shape}, got {np.shape(getattr(self, name))}")
        if not (np.all(np.isfinite(self.gyro_bias)) and np.all(np.isfinite(self.accel_bias))):
            raise InputShapeError("biases must be finite")

    @property
    def n_runs(self) -> int:
        return self.path.n_runs

    @property
    def n_steps(self) -> int:
        return int(round(self.path.duration * self.sensors.imu_rate))


def installation_dcm(roll_deg, pitch_deg, yaw_deg) -> np.ndarray:
    """Installation rotation ``C_bs = R_z(ψ_m) R_y(θ_m) R_x(φ_m)`` from angles in degrees."""
    return euler_to_dcm(np.asarray(roll_deg) * DEG, np.asarray(pitch_deg) * DEG, np.asarray(yaw_deg) * DEG)


def _streams(seeds):
    out = []
    for s in np.asarray(seeds).tolist():
        imu, gnss = np.random.SeedSequence(int(s)).spawn(2)
        out.append((np.random.default_rng(imu), np.random.default_rng(gnss)))
    return out


@dataclass(frozen=True)
class SensorChunk:
    """Sensor data of a batch for IMU samples ``k0 .. k0 + n - 1`` (arrays ``(R, n, ...)``).

    ``t`` are the interval start times ``k dt``; the samples are the truth at ``t + dt/2``.
    ``f_ext`` is the GNSS-derived external specific force in NED, ``course`` the GNSS
    course over ground [rad, unwrapped], ``speed`` the GNSS horizontal speed [m/s].
    """

    k0: int
    t: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    f_ext: np.ndarray
    course: np.ndarray
    speed: np.ndarray


def gnss_velocity(batch: VehicleBatch, streams=None) -> tuple[np.ndarray, np.ndarray]:
    """Noisy GNSS velocities at epochs ``j / gnss_rate`` covering the run: ``(t_e, v (R, E, 3))``."""
    s = batch.sensors
    dte = 1.0 / s.gnss_rate
    E = int(np.ceil(batch.path.duration * s.gnss_rate)) + 3
    t_e = np.arange(E) * dte
    v = np.empty((batch.n_runs, E, 3))
    step = 2000
    for a in range(0, E, step):
        v[:, a:a + step] = vehicle_state(batch.path, t_e[a:a + step], s.g).v_n
    streams = streams or _streams(batch.seeds)
    sig = np.array([s.gnss_sigma_h, s.gnss_sigma_h, s.gnss_sigma_v])
    for i, (_, rg) in enumerate(streams):
        v[i] += rg.standard_normal((E, 3)) * sig
    return t_e, v


def sensor_chunks(batch: VehicleBatch, chunk_s: float = 10.0):
    """Generate the IMU and GNSS data of ``batch`` chunk by chunk (:class:`SensorChunk`)."""
    s = batch.sensors
    dt = 1.0 / s.imu_rate
    n_chunk = max(1, int(round(chunk_s * s.imu_rate)))
    streams = _streams(batch.seeds)
    t_e, v_e = gnss_velocity(batch, streams)
    dte = t_e[1] - t_e[0]
    acc_mid = np.diff(v_e, axis=1) / dte  # at (j + 1/2) dte
    course_e = np.unwrap(np.arctan2(v_e[..., 1], v_e[..., 0]), axis=1)
    speed_e = np.hypot(v_e[..., 0], v_e[..., 1])
    g_n = np.array([0.0, 0.0, s.g])
    C_sb = np.swapaxes(batch.C_bs, -1, -2)
    sg = s.gyro_noise * np.sqrt(s.imu_rate)
    sa = s.accel_noise * np.sqrt(s.imu_rate)
    N = batch.n_steps
    for k0 in range(0, N, n_chunk):
        n = min(n_chunk, N - k0)
        t = (k0 + np.arange(n)) * dt
        tm = t + dt / 2
        st = vehicle_state(batch.path, tm, s.g)
        gyro = np.einsum("rij,rnj->rni", C_sb, st.omega_b) + batch.gyro_bias[:, None, :]
        accel = np.einsum("rij,rnj->rni", C_sb, st.f_b) + batch.accel_bias[:, None, :]
        noise = np.stack([rng.standard_normal((n, 6)) for rng, _ in streams])
        gyro += sg * noise[..., :3]
        accel += sa * noise[..., 3:]
        # GNSS: linear interpolation of mid-epoch accelerations, and of epoch course/speed
        pos = tm / dte - 0.5
        j = np.clip(np.floor(pos).astype(int), 0, acc_mid.shape[1] - 2)
        w = (pos - j)[None, :, None]
        f_ext = (1 - w) * acc_mid[:, j] + w * acc_mid[:, j + 1] - g_n
        pe = tm / dte
        je = np.clip(np.floor(pe).astype(int), 0, len(t_e) - 2)
        we = (pe - je)[None, :]
        course = (1 - we) * course_e[:, je] + we * course_e[:, je + 1]
        speed = (1 - we) * speed_e[:, je] + we * speed_e[:, je + 1]
        yield SensorChunk(k0=k0, t=t, gyro=gyro, accel=accel, f_ext=f_ext, course=course, speed=speed)
