"""The time offset between an accelerometer and a gyroscope recorded apart (separate files,
separate topics), measured from the motions both of them see.

When the sensor turns, the direction ``u = a/|a|`` of the specific force in the sensor
frame turns with it: for the slow hand motions of a calibration session (little linear
acceleration), ``du/dt ≈ u × ω``.  Both sides are computed from the samples (the gyro's
bias taken out as its median, both smoothed by the same centred moving average, which
delays neither) and cross-correlated as vectors (the sum of the three components'
products, normalised); the lag of the peak, refined by a parabola through the three best
lags, is the offset ``τ`` (at each lag ``u × ω`` is formed anew from ``u`` at the
accelerometer's sample and ``ω`` at the gyro's): the gyro's sample stamped ``t`` belongs to the accelerometer's
instant ``t - τ`` (``τ > 0``: the gyro's stamps are late).  Its standard error is the
scatter of the same estimate on eight stretches of the record (those whose peak
correlation measures one).

Raw counts work as well as physical units once the accelerometer's zero is taken out
(``acc_zero``; :func:`sphere_centre` of the samples for a recording in counts, whose zero
is its mid-scale plus the bias).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import RecordingError

#: Largest offset searched [s]; a peak at the edge means the two cannot be aligned.
MAX_OFFSET_S = 0.25
#: Farthest offset [s] searched to tell two time bases apart (a match beyond MAX_OFFSET_S is refused).
FAR_S = 10.0
#: Smallest peak correlation that measures an offset (below: no motion both sensors see).
MIN_CORRELATION = 0.3
#: Samples of the centred moving average applied to both signals.
SMOOTH = 11
#: Stretches of the record whose scatter gives the standard error.
PIECES = 8
#: An offset is applied when it exceeds this many standard errors (else stated only).
SIGNIFICANT = 3.0


@dataclass(frozen=True)
class Offset:
    """The gyro's time offset against the accelerometer (module docstring)."""

    tau: float  #: offset [s]; > 0: the gyro's stamps are late
    se: float  #: standard error [s] (NaN when too few stretches moved)
    correlation: float  #: peak correlation of the two signals
    applied: bool  #: whether the gyro was shifted by it

    def note(self, what: str = "gyro") -> str:
        """One line for the ``read:`` notes."""
        se = f" ± {1e3 * self.se:.2g}" if np.isfinite(self.se) else ""
        how = ("applied: the gyro interpolated to the accelerometer's instants" if self.applied else
               "not applied (within its uncertainty)")
        return (f"{what} - accelerometer time offset {1e3 * self.tau:+.3g}{se} ms (cross-correlation of u x w with "
                f"du/dt, u = a/|a|, over the motions, peak {self.correlation:.2f}); {how}")


def _smooth(x: np.ndarray) -> np.ndarray:
    k = np.ones(SMOOTH) / SMOOTH
    return np.column_stack([np.convolve(x[:, j], k, mode="same") for j in range(x.shape[1])])


def motion_signals(t, acc, gyro, acc_zero=0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(du/dt, u, ω)`` of each sample, (n, 3) each, smoothed (module docstring)."""
    a = _smooth(np.asarray(acc, float) - acc_zero)
    u = a / np.linalg.norm(a, axis=1, keepdims=True)
    du = np.gradient(u, np.asarray(t, float), axis=0)
    w = np.asarray(gyro, float)
    return du, u, _smooth(w - np.median(w, axis=0))


def _peak(du: np.ndarray, u: np.ndarray, w: np.ndarray, max_lag: int) -> tuple[float, float]:
    """(lag [samples] at which ``u[i] × w[i + lag]`` best matches ``du[i]``, refined; the peak correlation)."""
    n = len(du)
    lags = np.arange(-max_lag, max_lag + 1)
    c = np.full(lags.size, -1.0)
    for q, L in enumerate(lags):
        if abs(L) > n - 11:  # too little overlap (and a negative stop would wrap)
            continue
        i = slice(max(0, -L), n - max(0, L))  # du[i], u[i] against w[i + L]
        a = du[i]
        b = np.cross(u[i], w[max(0, L):n + min(0, L)])
        den = np.sqrt(np.sum(a * a) * np.sum(b * b))
        if den > 0:
            c[q] = float(np.sum(a * b) / den)
    k = int(np.argmax(c))
    frac = 0.0
    if 0 < k < lags.size - 1:
        den = c[k - 1] - 2 * c[k] + c[k + 1]
        frac = 0.5 * (c[k - 1] - c[k + 1]) / den if den < 0 else 0.0
    return float(lags[k] + frac), float(c[k])


def _far_match(du, w, h: float) -> tuple[int, float]:
    """(lag [samples], correlation) of the best match of ``|ω|`` with ``|du/dt|`` (frame-free
    magnitudes) over ±:data:`FAR_S` or a quarter of the record, by FFT."""
    x = np.linalg.norm(du, axis=1)
    y = np.linalg.norm(w, axis=1)
    x, y = x - x.mean(), y - y.mean()
    n = len(x)
    m = 1 << int(2 * n - 1).bit_length()
    c = np.fft.irfft(np.conj(np.fft.rfft(x, m)) * np.fft.rfft(y, m), m)  # c[L] = sum x[i] y[i + L]
    max_lag = min(int(FAR_S / h), n // 4)
    lags = np.r_[0:max_lag + 1, -max_lag:0]
    vals = c[lags]
    den = np.sqrt(np.sum(x * x) * np.sum(y * y))
    k = int(np.argmax(vals))
    return int(lags[k]), float(vals[k] / den) if den > 0 else 0.0


def estimate_offset(t, acc, gyro, *, source: str = "", acc_zero=0.0) -> Offset | None:
    """The gyro's time offset against the accelerometer, or None when no motion measures it.

    Raises
    ------
    RecordingError
        The motions match best beyond ±:data:`MAX_OFFSET_S` (the magnitudes ``|ω|`` and
        ``|du/dt|``, searched to ±:data:`FAR_S`): the two time bases cannot be aligned (one line).
    """
    t = np.asarray(t, float)
    h = float(np.median(np.diff(t)))
    max_lag = min(int(round(MAX_OFFSET_S / h)), len(t) // 4)  # a short record: a shorter search
    if max_lag < 2:
        return None
    du, u, w = motion_signals(t, acc, gyro, acc_zero)
    lag, corr = _peak(du, u, w, max_lag)
    if corr < MIN_CORRELATION or abs(lag) >= max_lag - 0.5:
        far, far_corr = _far_match(du, w, h)
        if abs(far) * h > MAX_OFFSET_S and far_corr >= MIN_CORRELATION:
            raise RecordingError(f"{source}: the gyro and the accelerometer cannot be aligned: their motions match "
                                 f"best {far * h:+.3g} s apart (correlation of |w| with |du/dt| {far_corr:.2f}), beyond "
                                 f"the ±{MAX_OFFSET_S:g} s a logger's delay explains; give a gyro stamped by the "
                                 "accelerometer's clock (--gyro FILE)")
        if corr < MIN_CORRELATION:
            return None
    pieces = []
    for idx in np.array_split(np.arange(len(t)), PIECES):
        p_lag, p_corr = _peak(du[idx], u[idx], w[idx], max_lag)
        if p_corr >= MIN_CORRELATION:
            pieces.append(p_lag)
    se = float(np.std(pieces, ddof=1) / np.sqrt(len(pieces)) * h) if len(pieces) >= 3 else float("nan")
    tau = lag * h
    return Offset(tau, se, corr, bool(np.isfinite(se) and abs(tau) > SIGNIFICANT * se))


def sphere_centre(acc) -> np.ndarray:
    """Centre of the sphere through the samples (least squares, linear in the centre): the zero of
    an accelerometer in counts, to within its scale factors' differences."""
    a = np.asarray(acc, float)[:: max(1, len(acc) // 20000)]
    A = np.column_stack([2 * a, np.ones(len(a))])
    sol, *_ = np.linalg.lstsq(A, np.sum(a * a, axis=1), rcond=None)
    return sol[:3]


def shift_gyro(t, gyro, tau: float) -> np.ndarray:
    """The gyro at the accelerometer's instants ``t``: its samples (stamped ``t``) read at ``t + τ``
    by linear interpolation (the ends hold their value)."""
    t = np.asarray(t, float)
    g = np.asarray(gyro, float)
    return np.column_stack([np.interp(t + tau, t, g[:, j]) for j in range(g.shape[1])])


__all__ = ["MAX_OFFSET_S", "Offset", "estimate_offset", "motion_signals", "shift_gyro", "sphere_centre"]
