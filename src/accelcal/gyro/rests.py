"""What the rests tell about the gyro: its bias (from all of them), its noise, its time base.

Rests.  The gyro's rests are the accelerometer's shrunk to where the gyro is still
(:func:`gyro_rests`, :func:`still_intervals`): every fit, evaluation and test of the gyro uses them.

Bias.  Every rest measures ``b + G f_i + (Earth rate)``: the bias, the g-sensitivity
times the rest's specific force, and the Earth's rotation projected on the sensor
(7.3e-5 rad/s at most, ≈ 0.004 °/s).  Three ways to take ``b`` (``bias=``):

* ``'all'`` — the mean of all rests, each weighted by its own standard error
  (its samples' scatter with their autocorrelation); with the g-sensitivity the
  weighted least squares of ``b`` and ``G`` (12 unknowns) on the rest means;
* ``'interpolated'`` — a bias that moves: linear in time between the centres of the
  rests, so each motion gets the bias of the rests around it (a drifting bias,
  a warm-up); with the g-sensitivity, ``G`` from the least squares above and each
  rest's mean minus ``G f_i`` interpolated;
* ``'first'`` — the initial rest only, as IMU-TK does.

The scatter of the rest means about the chosen model, against their standard errors
(``χ²``), says whether the bias moved during the session (:class:`BiasEstimate`).

Noise.  The integrated rate of a motion accumulates the gyro's white noise: its variance
per sample *for sums* is the per-sample variance times the integrated autocorrelation
time, i.e. ``mean_std² × n`` of a rest; pooled over the rests (:func:`rest_noise`).

Time base.  The integrators use a constant step ``h``: the mean step of the time column,
i.e. the sample index.  Host receive times jitter by milliseconds while the sensor samples
on its own clock; integrating the jittered steps would add that jitter to every motion.
:func:`sample_interval` reports the jitter and the gaps (dropped samples).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..static import static_poses_from_intervals
from .errors import GyroInputError

BIAS_MODES = ("all", "interpolated", "first")
#: A step this many times the median is a gap (dropped samples).
GAP_FACTOR = 1.5


@dataclass(frozen=True)
class TimeBase:
    h: float  #: constant step used [s]
    rate: float  #: 1 / h [Hz]
    jitter: float  #: std of the steps / median step
    gaps: np.ndarray  #: indices i with t[i+1] - t[i] > GAP_FACTOR × median


def sample_interval(t) -> TimeBase:
    """The constant step of a time column (mean step), its jitter and its gaps."""
    t = np.asarray(t, float)
    dt = np.diff(t)
    if t.ndim != 1 or len(t) < 3 or not np.all(np.isfinite(t)) or np.any(dt <= 0):
        raise GyroInputError("the time column must be finite and strictly increasing (at least 3 samples)")
    med = float(np.median(dt))
    gaps = np.flatnonzero(dt > GAP_FACTOR * med)
    good = dt[dt <= GAP_FACTOR * med]
    h = float(good.mean()) if len(good) else med
    return TimeBase(h, 1.0 / h, float(np.std(good) / med) if len(good) > 1 else 0.0, gaps)


def check_time_base(t_acc, t_gyro, h: float) -> None:
    """The gyro must be sampled with the accelerometer (same rows, same times within h/2)."""
    t_acc, t_gyro = np.asarray(t_acc, float), np.asarray(t_gyro, float)
    if t_acc.shape != t_gyro.shape:
        raise GyroInputError(f"the gyro has {t_gyro.size} samples, the accelerometer {t_acc.size}: their time "
                             "bases do not match; give gyro and accelerometer sampled together (--gyro FILE with the "
                             "same time column)")
    off = float(np.max(np.abs(t_acc - t_gyro)))
    if off > 0.5 * h:
        i = int(np.argmax(np.abs(t_acc - t_gyro)))
        raise GyroInputError(f"gyro and accelerometer times differ by {off:.4g} s at sample {i} (more than half a "
                             f"sample, {0.5 * h:.3g} s): their time bases do not match; resample both onto one "
                             "time column (--gyro FILE)")


@dataclass(frozen=True)
class RestStatistics:
    """Gyro statistics of each rest (raw unit)."""

    means: np.ndarray  #: (p, 3)
    mean_std: np.ndarray  #: (p, 3) standard error of each mean (autocorrelation included)
    noise_std: np.ndarray  #: (p, 3) per-sample std
    t_mid: np.ndarray  #: (p,) centre time [s]
    intervals: np.ndarray  #: (p, 2) [start, stop)


def rest_statistics(t, gyro, intervals) -> RestStatistics:
    """Mean, standard error and noise of the gyro at each rest ``[start, stop)``."""

    iv = np.asarray(intervals, dtype=np.int64).reshape(-1, 2)
    # one at a time: detected rests may overlap by a few samples (a brief blip between two quiet runs)
    each = [static_poses_from_intervals(t, gyro, iv[i:i + 1]) for i in range(len(iv))]
    return RestStatistics(np.concatenate([e.means for e in each]), np.concatenate([e.mean_std for e in each]),
                          np.concatenate([e.noise_std for e in each]), np.concatenate([e.t_mid for e in each]), iv)


#: Samples averaged when a rest's ends are checked for rotation (:func:`still_intervals`): a short
#: window for a turn's sharp start, longer ones for a slow one.
STILL_WINDOWS = (5, 25)
#: A rest ends where the averaged rate leaves the rest's median by this many of its own standard deviations.
STILL_SIGMAS = 5.0


def _still_run(seg: np.ndarray, w: int, floor=None) -> tuple[int, int, np.ndarray]:
    """``[start, stop)`` inside one rest's samples where no ``w``-sample mean of the rate moves
    (:func:`still_intervals`), and that mean's spread."""
    n = len(seg)
    core = slice(n // 4, n - n // 4 - w + 1)
    avg = np.cumsum(np.vstack([np.zeros((1, 3)), seg]), axis=0)
    avg = (avg[w:] - avg[:-w]) / w  # avg[j]: samples j .. j+w-1
    mid = np.median(avg[core], axis=0)
    spread = 1.4826 * np.median(np.abs(avg[core] - mid), axis=0)
    if floor is not None:
        spread = np.maximum(spread, floor)
    if not np.all(spread > 0):
        return 0, n, spread  # quantised to one level at rest: nothing to measure the ends against
    bad = np.flatnonzero(np.any(np.abs(avg - mid) > STILL_SIGMAS * spread, axis=1))
    c = n // 2
    lo, hi = bad[bad + w - 1 < c], bad[bad + w - 1 >= c]
    return (int(lo.max()) + w if len(lo) else 0), (int(hi.min()) if len(hi) else n), spread


#: Per axis, the squared rate (in the rest's noise) above which an edge sample counts as moving.
EDGE_ENERGY = 2.0


def _edge_trim(seg: np.ndarray, start: int, stop: int) -> tuple[int, int]:
    """The tails of a turn that no window flags (a rate of a few noise levels over a few samples):
    from each end of ``[start, stop)`` inwards, the prefix that maximises ``Σ (|z|² -
    3 EDGE_ENERGY)`` (``z`` the rate in its per-sample noise) goes.  On noise alone the sum
    drifts down, so it removes a sample or two at most; at a turn's tail it takes the tail."""
    n = stop - start
    core = seg[start + n // 4:stop - n // 4]
    sd = 1.4826 * np.median(np.abs(core), axis=0)
    if n < 8 or not np.all(sd > 0):
        return start, stop
    e = np.sum((seg[start:stop] / sd) ** 2, axis=1) - 3 * EDGE_ENERGY
    head, tail = np.cumsum(e[: n // 4]), np.cumsum(e[::-1][: n // 4])
    cut_a = int(np.argmax(head)) + 1 if head.max() > 0 else 0
    cut_b = int(np.argmax(tail)) + 1 if tail.max() > 0 else 0
    return start + cut_a, stop - cut_b


def still_intervals(gyro, intervals, min_samples: int = 2) -> np.ndarray:
    """The rests ``[start, stop)`` shrunk to where the gyro is still.

    Rests found on the accelerometer begin too early and end too late: gravity's direction
    hardly moves in the first and last hundredths of a degree of a turn, the gyro sees them.
    Those samples' rotation is lost to the motion and lands in the rest's mean (the bias):
    a systematic error of up to tenths of a degree on some motions, which the loop's
    candidates then explain (a time offset above all: its direction is the rate at the
    motion's ends).  From the rest's centre outwards, a rest ends before the first mean of
    the rate over :data:`STILL_WINDOWS` samples that leaves the rest's median by more than
    :data:`STILL_SIGMAS` times that mean's own spread (median absolute deviation over the
    rest's central half, so coloured noise counts as it is; a longer window's spread is at
    least the white noise's share of the shortest's).  At least ``min_samples`` around the
    centre are kept."""
    g = np.asarray(gyro, float)
    iv = np.asarray(intervals, dtype=np.int64).reshape(-1, 2).copy()
    w0 = STILL_WINDOWS[0]
    for i, (a, b) in enumerate(iv):
        n = b - a
        seg = g[a:b] - np.median(g[a + n // 4:b - n // 4], axis=0) if n >= 4 * w0 else None
        if seg is None:
            continue
        start, stop, spread = _still_run(seg, w0)
        for w in STILL_WINDOWS[1:]:
            if n >= 4 * w and np.all(spread > 0):
                s2, e2, _ = _still_run(seg, w, spread * np.sqrt(w0 / w))
                start, stop = max(start, s2), min(stop, e2)
        start, stop = _edge_trim(seg, start, stop)
        if stop - start < min_samples:
            c = n // 2
            start, stop = max(0, c - min_samples // 2), min(n, c - min_samples // 2 + min_samples)
        iv[i] = a + start, a + stop
    return iv


#: Fewest samples a rest keeps when it is shrunk to where the gyro is still (its noise is measured on them).
MIN_STILL_SAMPLES = 30


def accel_directions(accel, means, mean_std):
    """Unit gravity directions of the poses (p, 3), their covariance (p, 3, 3) and the
    calibrated specific force (p, 3) [m/s²], from an accelerometer calibration's ``apply``."""
    z = np.asarray(means, float)
    f = np.asarray(accel.apply(z), float)
    eps = 1e-3 * np.maximum(np.abs(z), 1.0)
    J = np.stack([(np.asarray(accel.apply(z + eps[:, [k]] * np.eye(3)[k]), float) - f) / eps[:, [k]]
                  for k in range(3)], axis=2)  # (p, 3, 3): ∂f/∂z (apply is affine)
    cov_f = np.einsum("pik,pk,pjk->pij", J, np.asarray(mean_std, float) ** 2, J)
    norm = np.linalg.norm(f, axis=1)
    u = f / norm[:, None]
    P = (np.eye(3)[None] - u[:, :, None] * u[:, None, :]) / norm[:, None, None]
    return u, P @ cov_f @ np.swapaxes(P, -1, -2), f


@dataclass(frozen=True)
class GyroRests:
    """The gyro's own rests and what the accelerometer says at them (:func:`gyro_rests`)."""

    intervals: np.ndarray  #: (p, 2) [start, stop): the accelerometer's rests shrunk to where the gyro is still
    stats: RestStatistics  #: the gyro's statistics on them
    u: np.ndarray  #: (p, 3) unit gravity directions
    u_cov: np.ndarray  #: (p, 3, 3) their covariance
    f: np.ndarray  #: (p, 3) calibrated specific force [m/s²]


def gyro_rests(t, gyro, poses, accel, acc=None, min_samples: int = MIN_STILL_SAMPLES) -> GyroRests:
    """The rests every gyro fit, evaluation and test uses: the accelerometer's ``poses`` shrunk
    to where the gyro is still (:func:`still_intervals`).

    At the start and end of a turn gravity's direction hardly moves, so the accelerometer
    counts those samples as rest while the gyro still turns: their rotation is lost to the
    motion and lands in the rest's mean (the bias), tenths of a degree on some motions.
    The gravity directions are averaged over the same samples when the raw accelerometer
    samples ``acc`` are given (else the poses' means, over the longer rests)."""
    iv = still_intervals(gyro, poses.intervals, min_samples)
    if acc is None:
        means, mean_std = poses.means, poses.mean_std
    else:
        at = rest_statistics(t, np.asarray(acc, float), iv)
        means, mean_std = at.means, at.mean_std
    u, u_cov, f = accel_directions(accel, means, mean_std)
    return GyroRests(iv, rest_statistics(t, gyro, iv), u, u_cov, f)


def rest_noise(rs: RestStatistics) -> np.ndarray:
    """Per-axis variance of one sample *for sums* (σ² τ), pooled over the rests (raw unit²)."""
    n = (rs.intervals[:, 1] - rs.intervals[:, 0])[:, None]
    return np.sum(rs.mean_std ** 2 * n * n, axis=0) / np.sum(n, axis=0)


@dataclass(frozen=True)
class BiasEstimate:
    """The bias model and how well the rests agree with it."""

    mode: str
    bias: np.ndarray  #: (3,) constant part (raw unit); for 'interpolated' the weighted mean
    g_sensitivity: np.ndarray | None  #: (3, 3) raw unit per m/s²
    bias_se: np.ndarray  #: (3,) standard error of ``bias``
    g_sensitivity_se: np.ndarray | None
    chi2: float  #: scatter of the rest means about the model, in their standard errors
    dof: int
    rest_residuals: np.ndarray  #: (p, 3) rest means minus the model
    rest_bias: np.ndarray  #: (p, 3) each rest's mean minus its g-sensitivity term (what 'interpolated' follows)

    @property
    def excess(self) -> float:
        return float(np.sqrt(self.chi2 / self.dof)) if self.dof > 0 else float("nan")


def fit_bias(rs: RestStatistics, mode: str = "all", f_rest=None) -> BiasEstimate:
    """The gyro bias from the rests (module docstring).  ``f_rest`` (p, 3) [m/s²], the
    calibrated specific force of each rest, turns on the g-sensitivity: ``G`` by weighted
    least squares of the rest means on ``[1, f]`` (modes 'all' and 'interpolated'; the
    latter then follows each rest's mean minus ``G f_i`` in time)."""
    if mode not in BIAS_MODES:
        raise GyroInputError(f"unknown gyro bias mode {mode!r}; known: {', '.join(BIAS_MODES)}")
    m, se = rs.means, np.maximum(rs.mean_std, 1e-150)  # squared, still a normal float
    p = len(m)
    if f_rest is not None and mode == "first":
        raise GyroInputError("the g-sensitivity needs the bias from all rests (bias mode 'all' or 'interpolated')")
    if f_rest is not None:
        X = np.column_stack([np.ones(p), np.asarray(f_rest, float)])  # (p, 4)
        coef, cov_diag = np.zeros((4, 3)), np.zeros((4, 3))
        for a in range(3):
            Xw, yw = X / se[:, a:a + 1], m[:, a] / se[:, a]
            cov = np.linalg.inv(Xw.T @ Xw)
            coef[:, a] = cov @ (Xw.T @ yw)
            cov_diag[:, a] = np.diag(cov)
        res = m - X @ coef
        return BiasEstimate(mode, coef[0], coef[1:].T, np.sqrt(cov_diag[0]), np.sqrt(cov_diag[1:]).T,
                            float(np.sum((res / se) ** 2)), 3 * (p - 4), res, m - X[:, 1:] @ coef[1:])
    w = 1.0 / se ** 2
    b = np.sum(w * m, axis=0) / np.sum(w, axis=0)
    res = m - b
    chi2 = float(np.sum((res / se) ** 2))
    if mode == "first":
        return BiasEstimate(mode, m[0], None, rs.mean_std[0], None, chi2, 3 * (p - 1), m - m[0], m)
    return BiasEstimate(mode, b, None, np.sqrt(1.0 / np.sum(w, axis=0)), None, chi2, 3 * (p - 1), res, m)


def bias_series(est: BiasEstimate, rs: RestStatistics, t) -> np.ndarray:
    """The bias at every sample (n, 3): constant, or linear between rest centres ('interpolated')."""
    t = np.asarray(t, float)
    if est.mode != "interpolated":
        return np.broadcast_to(est.bias, (len(t), 3)).copy()
    return np.column_stack([np.interp(t, rs.t_mid, est.rest_bias[:, a]) for a in range(3)])


def motion_bias_variance(est: BiasEstimate, rs: RestStatistics, before, after) -> np.ndarray:
    """Variance (m, 3) of the bias removed during each motion (between rests ``before`` and ``after``)."""
    before, after = np.asarray(before), np.asarray(after)
    if est.mode == "interpolated":
        return 0.25 * (rs.mean_std[before] ** 2 + rs.mean_std[after] ** 2)
    return np.broadcast_to(est.bias_se ** 2, (len(before), 3)).copy()


def measuring_range(gyro, gyro_range=None):
    """``(lo, hi)`` of the gyro's output: as given, or for integer counts inside 0..65535 or
    -32768..32767 those limits; None when unknown."""
    if gyro_range is not None:
        return float(gyro_range[0]), float(gyro_range[1])
    g = np.asarray(gyro, float)
    if np.all(g == np.round(g)):
        if g.min() >= 0 and g.max() <= 65535:
            return 0.0, 65535.0
        if g.min() >= -32768 and g.max() <= 32767:
            return -32768.0, 32767.0
    return None


def saturated_samples(gyro, gyro_range=None) -> np.ndarray:
    """Samples (n,) bool where an axis is at its measuring range.

    ``gyro_range`` (lo, hi) in raw units when known; else, for integer counts inside
    0..65535 or -32768..32767, those limits.  In any case a flat top: three or more equal
    consecutive samples within 3 % of an axis's extreme excursion from its median (an
    analog stage that clips before the converter).
    """
    g = np.asarray(gyro, float)
    sat = np.zeros(len(g), bool)
    lo, hi = measuring_range(g, gyro_range) or (None, None)
    if lo is not None:
        margin = 0.002 * (hi - lo)
        sat |= np.any((g <= lo + margin) | (g >= hi - margin), axis=1)
    med = np.median(g, axis=0)
    dev = g - med
    for a in range(3):
        top, bot = dev[:, a].max(), dev[:, a].min()
        near = (dev[:, a] >= 0.97 * top) | (dev[:, a] <= 0.97 * bot)
        same = np.concatenate([[False], g[1:, a] == g[:-1, a]])
        flat = same & np.concatenate([same[1:], [False]])  # sample equal to both neighbours
        flat_run = flat | np.roll(flat, 1) | np.roll(flat, -1)
        sat |= near & flat_run & (np.abs(dev[:, a]) > 0)
    return sat


__all__ = ["BIAS_MODES", "BiasEstimate", "GyroRests", "MIN_STILL_SAMPLES", "RestStatistics", "TimeBase", "accel_directions",
           "bias_series", "check_time_base", "fit_bias", "gyro_rests", "measuring_range", "motion_bias_variance",
           "rest_noise", "rest_statistics", "sample_interval", "saturated_samples", "still_intervals"]
