"""The sensor's clock, read from the data: sample numbers, rate, jitter, drift and gaps.

A sensor samples on its own oscillator; what a file records as time is often something
else: the host's receive time (a serial or BLE link batches samples and delivers them
late by a varying amount), a logger's clock.  1 / median step is then wrong (SNU's host
stamps jitter 5-15.5 ms about 10 ms: 97.6 Hz for a 100.0 Hz sensor; a BLE link that
delivers at its 11.25 ms connection interval: 89 Hz for 100.05 Hz), and a step longer
than 1.5 steps is no proof of a missing sample.

What decides is the sample number ``k`` of each row:

* from a **sample counter** when the file has one (``INDEX``, ``seq``, ``counter``,
  ``sample``, ``n_samples``, ``header.seq`` ...: :data:`COUNTER_NAMES`): ``k`` is the
  counter, unwrapped at its modulus when it wraps (the time stamps confirm the number of
  samples across the wrap); a counter that restarts is refused in one line;
* else from the **time stamps**: ``k`` is the row index, plus the samples missing in a
  gap.  A gap is a step that shifts every later stamp by whole sample periods (a level
  shift of the stamps about the clock, measured by the medians of the stamps on either
  side); a late sample followed by an early one (host jitter, batching) shifts nothing.

The clock is then the robust straight line ``t = a + h k`` through the stamps (least
squares, stamps further than 5 robust σ from the line left out, repeated): its rate
``1 / h``; the quadratic through the same stamps gives its drift (the change of rate from
the first to the last sample, in ppm) and the stamps' jitter about it (robust σ).  The
recording's times are the clock's: even steps (up to the drift), gaps exactly where
samples are missing.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..errors import RecordingError
from ..recording import MIN_ROWS

#: Column names (lower case, separators removed) of sample counters.
COUNTER_NAMES = frozenset({
    "index", "idx", "seq", "seqno", "seqnum", "sequence", "sequencenumber", "counter", "cnt", "samplecounter",
    "samplecount", "sample", "samples", "sampleindex", "samplenumber", "sampleno", "samplenr", "nsamples",
    "nsample", "headerseq", "fieldheaderseq", "framecounter", "imucounter", "sensorcounter", "datacounter"})
#: Stamps further than this many robust σ from the clock line are left out of its fit.
OUTLIER_SIGMA = 5.0
#: Largest number of residuals a median of :func:`fit_clock` is taken over (a regular subsample beyond).
MEDIAN_SAMPLES = 20_000
#: The quadratic (drift) times are used when its coefficient exceeds this many standard errors.
DRIFT_SIGNIFICANT = 5.0
#: Samples on either side of a candidate gap whose median stamps measure its level shift.
SHIFT_WINDOW = 50
#: Stamps within this fraction of a period of the clock are the clock (kept as written: the
#: digits a file was written with read back exactly).
STAMPS_ON_CLOCK = 1e-4
#: Samples per block of :func:`_wander`, and the wander (in periods) beyond which stamps without
#: a counter are no constant-rate clock (PX4's sensor_combined: 8 periods; SNU's host stamps: 0.2).
WANDER_BLOCK = 50
WANDER_PERIODS = 0.5
#: Fewest stamps on either side of a candidate gap that can decide it (none nearer the ends).
MIN_SIDE = 10
#: A step longer than this many periods is a candidate gap (decided by its level shift).
CANDIDATE_STEP = 1.2
#: Smallest modulus taken for a wrapping counter (a counter of one byte wraps at 256).
MIN_MODULUS = 16


def is_counter_name(name: str) -> bool:
    """Whether a column name names a sample counter (:data:`COUNTER_NAMES`)."""
    return re.sub(r"[^a-z0-9]", "", str(name).lower()) in COUNTER_NAMES


@dataclass(frozen=True)
class Clock:
    """The sensor's clock of a recording (module docstring)."""

    t: np.ndarray  #: the clock's time of each row [s] (a quadratic in ``k``: the rate may drift)
    k: np.ndarray  #: sample number of each row (int64, 0 at the first row)
    rate: float  #: 1 / h [Hz]
    jitter: float  #: robust σ of the stamps about the clock [s]
    drift_ppm: float  #: change of the rate from the first to the last sample [ppm]
    missing: int  #: samples missing (in gaps)
    gaps: int  #: number of gaps
    wraps: int  #: times the counter wrapped
    source: str  #: what numbered the samples ("counter 'seq'", "the time stamps")
    stamp_rate: float  #: 1 / median step of the stamps [Hz] (what a naive reading says)

    def as_dict(self) -> dict:
        """The clock's numbers, JSON-ready."""
        return {"rate_hz": self.rate, "jitter_s": self.jitter, "drift_ppm": self.drift_ppm,
                "missing_samples": self.missing, "gaps": self.gaps, "counter_wraps": self.wraps,
                "numbered_by": self.source, "median_step_rate_hz": self.stamp_rate}

    def note(self) -> str:
        """One line for the ``read:`` notes: rate, jitter, drift, gaps."""
        gaps = (f"{self.gaps} gap(s), {self.missing} sample(s) missing" if self.gaps else "no sample missing")
        wraps = f"; the counter wrapped {self.wraps} time(s), unwrapped" if self.wraps else ""
        naive = (f" (1 / median step would say {self.stamp_rate:.4g} Hz)"
                 if abs(self.stamp_rate / self.rate - 1) > 5e-4 else "")
        return (f"clock: {self.rate:.6g} Hz fitted to the time stamps against {self.source}{naive}; jitter "
                f"{1e3 * self.jitter:.3g} ms, drift {self.drift_ppm:+.3g} ppm over the record; {gaps}{wraps}; "
                "times are the clock's (--clock stamps keeps the stamps)")


def estimate_clock(stamps, counter=None, *, counter_name: str = "counter", where=None, path="") -> Clock:
    """The clock of a recording from its time stamps [s] and, if any, its sample counter.

    Parameters
    ----------
    stamps : array_like, shape (n,)
        Time stamps [s], strictly increasing.
    counter : array_like of int, shape (n,), optional
        The file's sample counter.
    counter_name : str
        The counter's column name, for notes and errors.
    where : callable, optional
        ``where(i)`` names row ``i`` in errors ("line 12"); default "row i".
    path : str
        The file, for errors.

    Raises
    ------
    RecordingError
        A counter that restarts or repeats (one line naming the row and ``--clock stamps``).
    """
    s = np.asarray(stamps, float)
    where = where or (lambda i: f"row {i + 1}")
    if counter is not None:
        k, wraps = counter_numbers(counter, s, counter_name, where, path)
        source = f"counter {counter_name!r}"
    else:
        k, wraps, source = stamp_numbers(s), 0, "the row index (no counter)"
    try:
        times, h, jitter, drift = fit_clock(s, k)
    except np.linalg.LinAlgError:  # the kept stamps share one sample number: no line through them
        raise RecordingError(f"{path}: the time stamps against {source} fit no clock (the stamps that agree "
                             "sit at one sample); check the file's time column, or pass --clock stamps to keep "
                             "the stamps as they are") from None
    steps = np.diff(k)
    gaps = int(np.sum(steps > 1))
    ds = np.diff(s)
    return Clock(times, k, 1.0 / h, jitter, drift, int(np.sum(steps - 1)), gaps, wraps, source,
                 1.0 / float(np.median(ds[ds > 0], overwrite_input=True)) if np.any(ds > 0) else float("nan"))


def fit_clock(stamps, k) -> tuple[np.ndarray, float, float, float]:
    """``(times, h, jitter, drift_ppm)`` of the clock through ``stamps`` against sample numbers ``k``.

    ``h``: the slope of the robust line ``stamps ≈ a + h k`` (the mean period); ``drift``
    from the quadratic through the same stamps; ``times`` and ``jitter`` (robust σ of the
    stamps about them) from the quadratic when its curvature exceeds
    :data:`DRIFT_SIGNIFICANT` standard errors (a clock whose rate drifts, the IMU-TK fork's
    data2: 131 ppm, is followed and its drift not counted as jitter), else from the line.
    """
    s = np.asarray(stamps, float)
    k = np.asarray(k, np.int64)
    last = float(k[-1] - k[0])
    mid = 0.5 * last
    x = (k - k[0]).astype(float)
    x -= mid  # centred: the slope and the intercept are fitted apart
    every = max(1, len(s) // MEDIAN_SAMPLES)  # a long record's outliers are judged on a regular subsample
    xs, ss = x[::every], s[::every]
    keep = np.ones(len(ss), bool)
    for _ in range(5):
        h, a = _polyfit(xs[keep], ss[keep], 1, mid)
        rs = ss - (a + h * xs)
        dev = np.abs(rs - np.median(rs[keep]))
        sigma = 1.4826 * float(np.median(dev[keep]))
        new = dev <= max(OUTLIER_SIGMA * sigma, 1e-9 * abs(h))
        if np.count_nonzero(new) < 3 or np.ptp(xs[new]) == 0:  # a line needs distinct sample numbers
            break
        changed = int(np.count_nonzero(new != keep))
        keep = new
        if changed <= 1e-3 * len(ss):  # the line moves no more than a thousandth of the stamps would move it
            break
    r = s - (a + h * x)
    r -= np.median(r[::every])
    keep = np.abs(r, out=r) <= max(OUTLIER_SIGMA * sigma, 1e-9 * abs(h))
    del r  # each temporary the record's size is a fifth of the reading's memory
    xk, sk = (x, s) if keep.all() else (x[keep], s[keep])  # no copies of a record without outliers
    if len(xk) < 3 or np.ptp(xk) == 0:  # too few to judge: the line through all
        keep, xk, sk = np.ones(len(s), bool), x, s
    sums = _PowerSums(xk, sk, mid)  # the line's and the quadratic's sums, each taken once
    if every > 1:
        h, a = sums.fit(1)
    times, drift = None, 0.0  # the line's times made last: not beside the quadratic's sums
    if len(xk) > 10 and last > 0 and np.ptp(xk) > 0.5 * mid:  # a curvature needs the stamps' span
        c = sums.fit(2)
        del sums
        quadratic = np.polyval(c, x)
        r = (s[::every] - quadratic[::every])[keep[::every]]
        s2 = 1.4826 * float(np.median(np.abs(r - np.median(r))))
        drift = float(2.0 * c[0] * last / h * 1e6)  # period at the end vs the start, relative
        xk = xk[::every] / max(mid, 1.0)  # the curvature's standard error from the subsample, scaled
        m = [float(np.sum(xk ** p)) * every for p in range(5)]  # moments: X^T X of (x^2, x, 1)
        xtx = np.array([[m[4], m[3], m[2]], [m[3], m[2], m[1]], [m[2], m[1], m[0]]])
        se_c = s2 * float(np.sqrt(np.linalg.inv(xtx)[0, 0])) / max(mid, 1.0) ** 2
        if abs(c[0]) > DRIFT_SIGNIFICANT * se_c:  # a drift the stamps show: follow it
            times, sigma = quadratic, s2
        del quadratic
    if times is None:
        times = a + h * x
    return times, float(h), sigma, drift


def _polyfit(x, y, deg: int, scale: float) -> np.ndarray:
    """``np.polyfit(x, y, deg)`` by the normal equations of ``x / scale`` (:class:`_PowerSums`)."""
    return _PowerSums(x, y, scale).fit(deg)


class _PowerSums:
    """``np.polyfit(x, y, deg)`` for degrees 1 and 2 by the normal equations of ``z = x / scale``
    (in [-1, 1]: well conditioned for degree 2), in a few passes over the data instead of a
    least-squares solve of the whole Vandermonde matrix (1 M stamps: 0.03 s instead of 0.6 s);
    each sum taken once, so the line and the quadratic through the same points share theirs."""

    def __init__(self, x, y, scale: float):
        self.scale = max(float(scale), 1.0)
        self.z, self.y = x / self.scale, y
        self._z2 = None
        self._sums: dict[str, float] = {}

    def _sum(self, key: str) -> float:
        # sums of products, not np.dot: a BLAS call per product waits for its threads on a
        # busy machine; each power's sum once (z^i z^j depends on i + j only), 1 * q summed as q
        if key not in self._sums:
            self._sums[key] = float(np.sum(self._term(key)))
        return self._sums[key]

    def _term(self, key: str) -> np.ndarray:
        z, y = self.z, self.y
        if key in ("z", "y", "zy"):
            return {"z": z, "y": y}[key] if key != "zy" else z * y
        if self._z2 is None:
            self._z2 = z * z
        z2 = self._z2
        return z2 if key == "z2" else z * z2 if key == "z3" else z2 * z2 if key == "z4" else z2 * y

    def fit(self, deg: int) -> np.ndarray:
        """The coefficients, highest power first (``np.polyfit``'s order), of degree 1 or 2."""
        moments = [float(len(self.z))] + [self._sum(k) for k in ("z", "z2", "z3", "z4")[:2 * deg]]
        A = np.array([[moments[i + j] for j in range(deg + 1)] for i in range(deg + 1)])
        b = np.array([self._sum(k) for k in ("y", "zy", "z2y")[:deg + 1]])
        coef = np.linalg.solve(A, b)  # lowest power first, in z
        return np.array([coef[j] / self.scale ** j for j in range(deg, -1, -1)])


def counter_numbers(counter, stamps, name: str, where, path) -> tuple[np.ndarray, int]:
    """Sample numbers (0 at the first row) of a counter, unwrapped at its modulus; and the wraps."""
    c = np.asarray(counter)
    if not np.all(np.isfinite(c)) or np.any(c != np.round(c)):
        raise RecordingError(f"{path}: counter {name!r} holds values that are not integers; name the right column "
                             "with --columns counter=NAME, or pass --clock stamps to ignore it")
    c = c.astype(np.int64)
    d = np.diff(c)
    up = d[d > 0]
    step = int(np.median(up)) if up.size else 1
    drops = np.flatnonzero(d <= 0)
    wraps = 0
    if drops.size:
        d = _unwrap(c, d, drops, step, stamps, name, where, path)
        wraps = int(drops.size)
    if np.any(d % step):
        i = int(np.flatnonzero(d % step)[0])
        raise RecordingError(f"{path}: counter {name!r} steps by {int(d[i])} at {where(i + 1)} where it counts in "
                             f"steps of {step}: not a sample counter; name the right column with --columns "
                             "counter=NAME, or pass --clock stamps")
    k = np.concatenate([[0], np.cumsum(d // step)])
    return k, wraps


def _unwrap(c, d, drops, step: int, stamps, name: str, where, path) -> np.ndarray:
    """The counter's steps with each wrap undone; a restart (or a repeat) is one line."""
    i = int(drops[0])
    if d[i] == 0:
        raise RecordingError(f"{path}: counter {name!r} repeats the value {int(c[i])} at {where(i + 1)} "
                             f"({drops.size} such step(s)): rows duplicated or the counter is not per sample; drop "
                             "the duplicates, or pass --clock stamps to ignore the counter")
    ok = d > 0
    h = float(np.median(np.diff(stamps)[ok] / d[ok])) if (stamps is not None and ok.any()) else float("nan")
    hi = int(c.max())
    # a counter wraps at a power of two (a byte, a 16- or 32-bit word) or of ten (a decimal display);
    # a drop at any other value is a restart, however well the numbers line up
    moduli = sorted({1 << max(hi.bit_length(), 4), 10 ** len(str(hi))} | (
        {hi + 1} if (hi + 1) & hi == 0 or str(hi + 1).rstrip("0") == "1" else set()))
    for m in moduli:
        if m < MIN_MODULUS:
            continue
        steps = d[drops] + m
        if np.isfinite(h):  # the stamps say how many samples passed across each wrap
            elapsed = np.diff(stamps)[drops] / h
            fits = np.abs(steps - elapsed) <= np.maximum(3.0 * step, 0.5 * elapsed)
        else:  # no stamps: a wrap goes on by a step or two, a restart jumps back
            fits = steps <= 3 * step
        if np.all(steps > 0) and np.all(fits):
            out = d.copy()
            out[drops] = steps
            return out
    j = int(drops[0])
    raise RecordingError(f"{path}: counter {name!r} restarts at {where(j + 1)} (from {int(c[j])} to {int(c[j + 1])}, "
                         f"not a wrap at {' or '.join(str(m) for m in moduli)}): the sensor was reset or two recordings "
                         "were joined; split the file there, or pass --clock stamps to time the samples by their "
                         "stamps alone")


def looks_like_counter(values) -> bool:
    """Whether a column found by its name counts samples: integers that go up at (nearly) every row
    (a pose number or a packet count repeats; a wrap or a restart is a rare drop)."""
    v = np.asarray(values, float)
    if v.size < 3 or not np.all(np.isfinite(v)) or np.any(v != np.round(v)):
        return False
    d = np.diff(v)
    return bool(np.mean(d > 0) >= 0.99)


def stamp_numbers(stamps) -> np.ndarray:
    """Sample numbers from time stamps alone: the row index plus the samples missing in gaps.

    A step longer than :data:`CANDIDATE_STEP` periods is a gap of ``m`` samples when the
    stamps after it sit ``m`` periods later about the clock than those before it (the
    medians of :data:`SHIFT_WINDOW` stamps on either side); the candidates are decided
    greedily, the largest shift first, so two candidates never claim one shift.
    """
    s = np.asarray(stamps, float)
    n = len(s)
    k = np.arange(n, dtype=np.int64)
    if n < 4:
        return k
    dt = np.diff(s)
    h = h0 = float(np.median(dt))  # the median step: the period, whatever gaps the fit below has not counted
    cand = np.flatnonzero(dt > CANDIDATE_STEP * h)
    if cand.size == 0:
        return k
    # the period from steps over SHIFT_WINDOW rows (median: the few that span a gap do not count,
    # and the jitter of one stamp is divided by the window), not a fit that the gaps would tilt
    lag = max(1, min(SHIFT_WINDOW, n // 4))  # most pairs this far apart span no gap
    h = float(np.median((s[lag:] - s[:-lag]) / lag))
    r = s - h * k
    r -= np.median(r)  # residual about the clock; a gap of m samples raises all later ones by m h
    extra = np.zeros(n - 1, np.int64)
    cap = np.maximum(np.round(dt[cand] / h).astype(np.int64) - 1, 1)  # a gap is no longer than its step
    shifts = _level_shifts(r, cand, h)
    open_ = np.ones(cand.size, bool)
    while True:
        m = np.minimum(np.round(shifts / h).astype(np.int64), cap)
        ok = open_ & (m >= 1)
        if not ok.any():
            break
        j = _best_split(r, cand, ok, int(np.argmax(np.where(ok, shifts, -np.inf))))
        i = int(cand[j])
        extra[i] += m[j]
        r[i + 1:] -= m[j] * h
        open_[j] = False
        near = np.flatnonzero(open_ & (np.abs(cand - i) < SHIFT_WINDOW))  # only their windows saw the shift
        shifts[near] = [_level_shift(r, int(cand[q])) for q in near]
    # next to the ends no level can be measured: there a step far beyond the jitter is a gap
    dr = np.diff(r)  # steps about the clock: free of the trend the uncounted gaps leave in r
    sigma = 1.4826 * float(np.median(np.abs(dr - np.median(dr))))
    edge = open_ & ((cand + 1 < MIN_SIDE) | (n - cand - 1 < MIN_SIDE))
    edge &= dt[cand] > h0 + max(0.5 * h0, 10.0 * sigma)
    extra[cand[edge]] += np.round(dt[cand[edge]] / h0).astype(np.int64) - 1
    return np.concatenate([[0], np.cumsum(1 + extra)])


def _best_split(r, cand, ok, j: int) -> int:
    """Of the candidates near ``cand[j]`` that see a shift, the one where a step of the level
    fits the residuals best (least absolute deviation about the two medians): jitter near a
    gap makes neighbouring steps long too, and their windows see the same shift."""
    near = np.flatnonzero(ok & (np.abs(cand - cand[j]) < SHIFT_WINDOW))
    if near.size == 1:
        return j
    lo, hi = max(0, int(cand[near].min()) + 1 - SHIFT_WINDOW), min(len(r), int(cand[near].max()) + 1 + SHIFT_WINDOW)
    seg = r[lo:hi]

    def cost(i):
        a, b = seg[:i + 1 - lo], seg[i + 1 - lo:]
        return float(np.sum(np.abs(a - np.median(a))) + np.sum(np.abs(b - np.median(b))))

    return int(near[np.argmin([cost(int(cand[q])) for q in near])])


def _level_shifts(r, cand, h: float) -> np.ndarray:
    """:func:`_level_shift` of every candidate: those with full windows at once (a gathered
    (k, SHIFT_WINDOW) block each side), the few near the ends one by one.  The medians are
    taken only where the windows' means already differ by a quarter period (their difference
    by cumulative sums, for all at once): elsewhere no gap can be (host jitter makes a fifth
    of the steps candidates)."""
    n = len(r)
    cs = np.concatenate([[0.0], np.cumsum(r)])
    W = SHIFT_WINDOW
    inside = (cand + 1 >= W) & (cand + 1 + W <= n)
    c = cand[inside]
    out = np.zeros(cand.size)
    out[inside] = (cs[c + 1 + W] - cs[c + 1]) / W - (cs[c + 1] - cs[c + 1 - W]) / W  # the means' shift
    full = inside & (out > 0.25 * h)
    off = np.arange(SHIFT_WINDOW)
    for lo in range(0, int(full.sum()), 50_000):  # blocks: bounded memory
        c = cand[full][lo:lo + 50_000]
        after = np.median(r[c[:, None] + 1 + off], axis=1)
        before = np.median(r[c[:, None] + 1 - SHIFT_WINDOW + off], axis=1)
        out[np.flatnonzero(full)[lo:lo + 50_000]] = after - before
    for q in np.flatnonzero(~inside):
        out[q] = _level_shift(r, int(cand[q]))
    return out


def _level_shift(r, i: int) -> float:
    """Median of the residuals after step ``i`` minus the median before it (windows of SHIFT_WINDOW)."""
    lo, hi = max(0, i + 1 - SHIFT_WINDOW), min(len(r), i + 1 + SHIFT_WINDOW)
    if min(hi - i - 1, i + 1 - lo) < MIN_SIDE:
        return 0.0  # too few stamps on one side to tell a gap from a late stamp
    return float(np.median(r[i + 1:hi]) - np.median(r[lo:i + 1]))


#: Values of ``clock=`` (``--clock``): the clock fitted to the data, or the stamps as they are.
CLOCK_MODES = ("auto", "stamps")


def clocked_time(t, counter, *, counter_name: str, mode: str, timed_by_rate: bool, where, path):
    """The recording's times and the notes on its clock (the table reader's route).

    ``t``: times [s] from the time column, or from the sample index and a rate
    (``timed_by_rate``); ``counter``: the counter column's values (or None).  Stamps no
    clock can be fitted to (too few, not finite, going back, or repeating without a
    counter that numbers the samples) are returned as they are, for the check every
    recording passes to refuse with the line (:func:`accelcal.recording.checked_recording`).
    """
    if mode not in CLOCK_MODES:
        raise RecordingError(f"--clock must be {' or '.join(CLOCK_MODES)}, got {mode!r}")
    if mode == "stamps" or not _fits_a_clock(t, counter):
        return t, ["clock: the time stamps as they are (--clock stamps)"] if mode == "stamps" else []
    if timed_by_rate:
        if counter is None:
            return t, []
        k, wraps = counter_numbers(counter, None, counter_name, where, path)
        period = float(t[1] - t[0])
        gaps = int(np.sum(np.diff(k) > 1))
        return k * period, [f"clock: samples numbered by counter {counter_name!r} at {1 / period:.6g} Hz: "
                            + (f"{gaps} gap(s), {int(k[-1] + 1 - len(k))} sample(s) missing" if gaps else
                               "no sample missing") + (f"; the counter wrapped {wraps} time(s), unwrapped" if wraps
                                                       else "")]
    c = estimate_clock(t, counter, counter_name=counter_name, where=where, path=path)
    if np.max(np.abs(c.t - t)) <= STAMPS_ON_CLOCK * (1.0 / c.rate):
        return t, [c.note().replace("times are the clock's", "the stamps are on it (kept)")]
    wander = _wander(t - c.t)
    if counter is None and wander > WANDER_PERIODS / c.rate:
        return t, [f"clock: the stamps follow no constant rate (their medians over {WANDER_BLOCK} samples wander "
                   f"{1e3 * wander:.3g} ms from the best one, {c.rate:.6g} Hz): kept as they are"]
    return c.t, [c.note()]


def _fits_a_clock(t, counter) -> bool:
    """Whether stamps ``t`` can be fitted a clock: enough of them, finite, never going back,
    repeating only where a counter numbers the samples (a batch received at once)."""
    if len(t) < MIN_ROWS or not np.all(np.isfinite(t)):
        return False
    steps = np.diff(t)
    return bool(np.all(steps > 0) if counter is None else np.all(steps >= 0))


def _wander(r) -> float:
    """Largest |median| of the residuals over blocks of :data:`WANDER_BLOCK` samples: how far the
    stamps stray from the clock for longer than jitter lasts."""
    m = len(r) // WANDER_BLOCK
    if m == 0:
        return 0.0
    blocks = np.asarray(r[:m * WANDER_BLOCK]).reshape(m, WANDER_BLOCK)
    return float(np.max(np.abs(np.median(blocks, axis=1))))


__all__ = ["CLOCK_MODES", "COUNTER_NAMES", "Clock", "clocked_time", "counter_numbers", "estimate_clock", "fit_clock",
           "is_counter_name", "looks_like_counter", "stamp_numbers"]
