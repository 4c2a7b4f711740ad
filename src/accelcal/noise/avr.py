"""What allan_variance_ros would read from the same record, and why it differs from the IEEE fit.

allan_variance_ros (ori-drs/allan_variance_ros, commit 1d54b60) is what many ROS users
run before Kalibr.  Its reading, from its source:

* ``src/AllanVarianceComputor.cpp`` (``allanVariance``, lines 136-229): τ = 0.1 s ·
  ``period`` for ``period`` = 1 … 9999 (0.1 s to 999.9 s, a *linear* grid: nine in ten of
  its τ lie above 100 s); bins of ``int(τ · measure_rate)`` samples, *not* overlapping
  (``overlap_ = 0``, "Disable overlap"), the Allan variance of consecutive bin means; the
  gyroscope in deg/s (``* 180 / M_PI``, line 167).
* ``scripts/analysis.py``: white noise: a line of slope −½ fitted in log–log
  (``curve_fit`` with the slope bounded to [m, m + 0.001]) to the τ < 10 s
  (``white_noise_break_point``, lines 123-129), read at τ = 1 s; random walk: a line of
  slope +½ fitted to *all* τ (lines 132-134), read at τ = 3 s; "bias instability": the
  minimum Allan deviation (lines 136-138, no 0.664 factor); the worst axis goes to
  ``imu.yaml`` (gyro converted back to rad, line 243), the printout quotes deg/√h
  (``* 60``, line 248) and deg/h (``* 3600``, line 252).

:func:`avr_reading` computes those numbers on the data (the same grid, bins and fits;
the slope fixed at its bound m).  Where the record is shorter than 2 · 999.9 s the longest
τ cannot be averaged twice: allan_variance_ros writes NaN there and its analysis stops;
here they are left out, and the note says so.

Why the random walk differs: a +½ line through every τ, read at 3 s, measures the level
of the whole Allan-deviation curve weighted towards its long-τ end, wherever the record's
long τ are white noise or bias instability; the IEEE fit takes the random walk from the τ
where it carries the curve (and gives an upper bound when it never does).
"""

from __future__ import annotations

import math

import numpy as np

from .terms import exported_term

#: allan_variance_ros's τ grid: 0.1 s · (1 … 9999).
AVR_TAUS = 0.1 * np.arange(1, 10000)
#: Its white-noise fit uses the τ below this [s].
AVR_WHITE_TAU_MAX = 10.0
#: A reading this many times apart (either way) from the IEEE value earns a summary line.
DIFFER_FACTOR = 2.0
SOURCE = "ori-drs/allan_variance_ros@1d54b60"


def avr_adev(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """(τ, ADEV (k, d)) on allan_variance_ros's grid and non-overlapping bins, the τ with ≥ 2 bin means only.

    The short bins (many means each) one by one, the long ones (a few means each, nine in
    ten of the grid) all at once: a loop over 9999 τ took 0.4 s of 10⁶ samples.  τ whose
    bins truncate to the same size share one computation."""
    x = np.asarray(x, dtype=float)
    x = x[:, None] if x.ndim == 1 else x
    n = len(x)
    c = np.empty((n + 1, x.shape[1]))
    c[0] = 0.0
    np.cumsum(x, axis=0, out=c[1:])  # in place: no second copy of the record
    bins = (AVR_TAUS * fs).astype(int)  # the C++ truncates τ · rate to an int
    ok = bins >= 1
    taus, bins = AVR_TAUS[ok], bins[ok]
    m = np.maximum(-(-(n - bins) // bins), 0)  # bin means per τ: len(range(0, n - bin, bin))
    last = np.flatnonzero(m < 2)  # for (j = 0; j < size - bin; j += bin): stops at the first τ without two
    stop = int(last[0]) if last.size else len(bins)
    taus, bins = taus[:stop], bins[:stop]
    sizes, which = np.unique(bins, return_inverse=True)
    counts = m[:stop][np.searchsorted(bins, sizes)]
    avar = np.empty((len(sizes), x.shape[1]))
    few = counts < _AVR_BATCH_BELOW
    for i in np.flatnonzero(~few):
        b = int(sizes[i])
        means = np.diff(c[0:(counts[i] + 1) * b:b], axis=0) / b
        avar[i] = np.sum(np.diff(means, axis=0) ** 2, axis=0) / (2 * (counts[i] - 1))
    if few.any():
        avar[few] = _avr_batch(c, sizes[few], counts[few])
    return taus, np.sqrt(avar[which]).reshape(len(taus), x.shape[1])


#: Bin sizes with fewer means than this are computed together (:func:`_avr_batch`).
_AVR_BATCH_BELOW = 2000


def _avr_batch(c: np.ndarray, sizes: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The Allan variances (k, d) of bin sizes ``sizes`` with ``counts`` means each, from the
    cumulative sums ``c``: every bin edge in one index array, the squared differences of
    consecutive means summed per size (in order, as the loop sums them), one column at a time
    (temporaries of one column: a 10⁶-sample triad's peak memory was 50 MB higher)."""
    seg = np.repeat(np.arange(len(sizes)), counts + 1)  # bin edges j · size, j = 0 … count, of each size
    first = np.concatenate(([0], np.cumsum(counts + 1)[:-1]))
    edges = (np.arange(len(seg)) - first[seg]) * sizes[seg]
    width = sizes[seg[1:]].astype(float)
    inside = seg[2:] == seg[:-2]  # both means of a difference from one size (the others are dropped)
    which = seg[2:][inside]
    sums = np.empty((len(sizes), c.shape[1]))
    for j in range(c.shape[1]):
        d = np.diff(np.diff(c[edges, j]) / width)
        d *= d
        sums[:, j] = np.bincount(which, weights=d[inside], minlength=len(sizes))
    return sums / (2 * (counts - 1))[:, None]


def avr_reading(x, fs: float) -> dict:
    """allan_variance_ros's white noise N, random walk K and minimum ADEV per axis (module docstring)."""
    taus, adev = avr_adev(x, fs)
    if len(taus) < 2:
        return {"noise_density": [math.nan] * 3, "random_walk": [math.nan] * 3, "min_adev": [math.nan] * 3,
                "complete": False, "tau_max_s": float(taus[-1]) if len(taus) else 0.0}
    with np.errstate(divide="ignore"):
        lg = np.log(adev)
    lt = np.log(taus)[:, None]
    short = taus < AVR_WHITE_TAU_MAX
    white = np.exp(np.mean(lg[short] + 0.5 * lt[short], axis=0)) if short.any() else np.full(adev.shape[1], np.nan)
    walk = np.exp(np.mean(lg - 0.5 * lt, axis=0) + 0.5 * math.log(3.0))
    return {"noise_density": white.tolist(), "random_walk": walk.tolist(), "min_adev": adev.min(axis=0).tolist(),
            "complete": bool(taus[-1] >= AVR_TAUS[-1]), "tau_max_s": float(taus[-1])}


#: Why allan_variance_ros's noise density differs from the IEEE fit's.
_WHY_WHITE = ("it fits a -1/2 slope to the tau < 10 s of its own grid and reads it at 1 s, where quantization, the "
              "sensor's filter or the bias instability still bend the curve; the IEEE fit separates them")


def avr_lines(sensor: str, unit: str, reading: dict, ours_n: list, ours_k: list) -> list[str]:
    """Summary lines where allan_variance_ros's worst-axis value is more than DIFFER_FACTOR apart from ours."""
    out = []
    # allan_variance_ros's imu.yaml fields, each with the term the exports give it (its unit) and why they differ
    for key, ours, name, why in (("noise_density", ours_n, "noise density", _WHY_WHITE),
                                 ("random_walk", ours_k, "random walk", _why_walk(reading))):
        u = exported_term(key).unit_of(unit)
        theirs, mine = max(reading[key]), max(ours)
        if not (math.isfinite(theirs) and mine > 0):
            continue
        r = theirs / mine
        if 1 / DIFFER_FACTOR <= r <= DIFFER_FACTOR:
            continue
        out.append(f"{sensor}: allan_variance_ros would write {name} {theirs:.3g} {u} to imu.yaml, {r:.2g}x this "
                   f"report's {mine:.3g}: {why}")
    return out


def _why_walk(reading: dict) -> str:
    cut = "" if reading["complete"] else (
        f"; on this record it stops at tau = {reading['tau_max_s']:.4g} s (its analysis.py fails on records shorter "
        "than 2 x 999.9 s, NaN at the longest tau)")
    return ("it fits a +1/2 slope to every tau from 0.1 s to 999.9 s on a linear grid (nine in ten above 100 s) "
            "and reads it at 3 s: the level of the whole curve's long end, not the random walk, which the IEEE "
            "fit takes where it carries the curve" + cut)


def units_line(sensor: str, reading: dict) -> str:
    """How allan_variance_ros prints the same record (its units), for a user comparing printouts."""
    if sensor == "gyroscope":
        deg = 180 / math.pi
        return ("allan_variance_ros would print angle random walk " + ", ".join(
            f"{60 * deg * v:.3g}" for v in reading["noise_density"]) + " deg/sqrt(h) and 'bias instability' (the "
            "minimum ADEV, no 0.664 factor) " + ", ".join(f"{3600 * deg * v:.3g}" for v in reading["min_adev"])
            + " deg/h (x, y, z)")
    return ("allan_variance_ros would print velocity random walk " + ", ".join(
        f"{60 * v:.3g}" for v in reading["noise_density"]) + " m/s/sqrt(h) and 'bias instability' (the minimum "
        "ADEV) " + ", ".join(f"{v:.3g}" for v in reading["min_adev"]) + " m/s^2 (x, y, z)")


__all__ = ["AVR_TAUS", "DIFFER_FACTOR", "SOURCE", "avr_adev", "avr_lines", "avr_reading", "units_line"]
