"""Static-interval detection in raw accelerometer recordings (IMU-TK style).

Tedaldi, Pretto & Menegatti (ICRA 2014): the sensor first rests for a while; the
noise level learned there sets a threshold on a moving-window variance, and the
stretches where the variance stays below it are the static poses.

Algorithm (all windows centred, length ``window``, variances via cumulative sums)

1. ``v[i]`` = sum over the three axes of the variance of the window centred on
   sample ``i`` (the trace of the window covariance, i.e. the total noise power;
   IMU-TK uses the norm of the per-axis variances, which behaves the same).
2. Initial rest.  With ``init_duration=None`` it is found from the data: the first
   window seeds a threshold, the initial rest is the first run of windows below
   ``threshold_factor`` × that seed.  With ``init_duration`` given it is
   ``[0, init_duration)``.  Either way it must look like a rest (see
   :func:`_check_initial_rest`), else :class:`RecordingError`.
3. ``vref`` = trace of the covariance of the initial rest; a window centre is static
   when ``v < threshold_factor * vref``.
4. A run of static centres ``[a, b)`` means every sample of ``[a - h, b + h)`` lies in
   a quiet window (``h`` = half window); that span, minus ``trim`` at each end that
   borders motion, is the pose, kept if it lasts at least ``min_duration``.

Defaults (identical for the three recordings in ``shared/data``; no per-file tuning)

* ``window = 1.0`` s — IMU-TK's 101 samples at 100 Hz.  The MPU-6050 poses last only
  2–3 s, so a 2 s window would lose them.
* ``threshold_factor = 6`` — the middle of IMU-TK's search range 2…10.  The
  hand-placed MPU-6050 poses are 1.5–3 × noisier than its initial rest (the hand or
  the surface still moves a little): with factor 4 one of them breaks in two, with
  6–10 each is one run (10 poses).  Motion between poses is 10²–10⁵ × the noise, so
  6 is far from it.  On the Xsens data factors 4–10 give the same 38 poses; at 3 and
  below, two brief taps (≈ 0.2 s, window variance ≈ 3.4 × the rest) split two poses.
  The imucal session's initial rest is ≈ 3 × noisier than its later rests, so with a
  factor ≤ 3 the "later parts are quieter" check (step 2) rejects it.
* ``min_duration = 1.0`` s — IMU-TK keeps intervals of at least 100 samples (1 s).
  The initial rest only needs one window to serve as noise reference.
* ``trim = 0.25`` s — cut from each end that borders motion, where the sensor is
  still settling: without it pose means move by up to 10 standard errors (imucal,
  MPU-6050) against a 0.5 s trim; with 0.25 s by at most 1.4.
* ``init_duration = None`` (automatic) — the initial rests differ too much to fix
  one duration: Xsens ≈ 52 s, MPU-6050 ≈ 37 s, imucal Ferraris session only ≈ 1.3 s
  (it is bumped at 1.5 s, then rests again in the same orientation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import AccelcalError, RecordingError

DEFAULT_WINDOW = 1.0
DEFAULT_THRESHOLD_FACTOR = 6.0
DEFAULT_MIN_DURATION = 1.0
DEFAULT_TRIM = 0.25
#: Largest drift of the initial rest's block means, in per-sample noise std, that is
#: still a rest.  A slow rotation gives ≈ 3.5 (B - 1) over B blocks; the real initial
#: rests drift by 0.9 (Xsens, 51 blocks), 0.5 (MPU-6050), 0.3 (imucal).
MAX_INIT_DRIFT = 3.0
#: Largest drift of the quietest stretch's 4 block means [per-sample noise std] when it
#: replaces a missing initial rest (:func:`_quietest_stretch`).  Stricter than
#: ``MAX_INIT_DRIFT``: the stretch is short, so a rest drifts by little, and a stretch
#: chosen for its low variance could otherwise be part of a slow motion.
MAX_QUIET_DRIFT = 1.5


@dataclass(frozen=True)
class StaticPoses:
    """Static poses found in a recording (all arrays have one row per pose, in time order).

    Attributes
    ----------
    means : ndarray, shape (n_poses, 3)
        Mean acceleration of each pose, input units.
    t_start, t_end, t_mid : ndarray, shape (n_poses,)
        Time of the first and last sample of each pose and their midpoint [s].
    n_samples : ndarray of int, shape (n_poses,)
        Samples averaged in each pose.
    noise_std : ndarray, shape (n_poses, 3)
        Per-sample standard deviation of each axis within the pose.
    mean_std : ndarray, shape (n_poses, 3)
        Standard error of each pose mean, ``noise_std / sqrt(n_eff)`` with the effective
        sample size from the autocorrelation (Geyer's initial positive sequence).  This
        is the per-pose noise the estimators use.
    temp : ndarray, shape (n_poses,), or None
        Mean temperature of each pose if the recording has one.
    intervals : ndarray of int, shape (n_poses, 2)
        Sample index range ``[start, stop)`` of each pose.
    init_rest : tuple of int
        Sample range ``[start, stop)`` whose noise set the threshold (the first known
        interval when the intervals were given).
    reference : {'initial_rest', 'quietest_stretch', 'known_intervals'}
        Where the noise reference came from: the recording's initial rest, its quietest
        stretch (the recording does not start at rest), or no detection at all (the
        recording's known static intervals were used as they are).
    reference_note : str
        Why the initial rest was not used (empty otherwise): the CLI prints it.
    """

    means: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    t_mid: np.ndarray
    n_samples: np.ndarray
    noise_std: np.ndarray
    mean_std: np.ndarray
    temp: np.ndarray | None
    intervals: np.ndarray
    init_rest: tuple[int, int]
    reference: str = "initial_rest"
    reference_note: str = ""

    def __len__(self) -> int:
        return len(self.means)


def detect_static(t, acc, *, init_duration: float | None = None, window: float = DEFAULT_WINDOW,
                  threshold_factor: float = DEFAULT_THRESHOLD_FACTOR,
                  min_duration: float = DEFAULT_MIN_DURATION, trim: float = DEFAULT_TRIM,
                  temp=None, noise_reference: str = "auto") -> StaticPoses:
    """Find the static poses of a raw recording.

    Parameters
    ----------
    t : array_like, shape (n,)
        Time [s], strictly increasing (sampling rate from the median step).
    acc : array_like, shape (n, 3)
        Acceleration in any one unit.
    init_duration : float, optional
        Length [s] of the initial rest.  None: found from the data (module docstring).
    window : float
        Length [s] of the moving variance window.
    threshold_factor : float
        A window is static if its variance is below this multiple of the initial rest's.
    min_duration : float
        Shortest pose [s] kept, after trimming.
    trim : float
        Time [s] cut from each end of a pose that borders motion.
    temp : array_like, shape (n,), optional
        Temperature, averaged per pose.
    noise_reference : {'auto', 'initial', 'quietest'}
        Where the noise level comes from.  ``'initial'``: the initial rest, which must
        pass the checks of :func:`_check_initial_rest` (IMU-TK's protocol).
        ``'quietest'``: the quietest stretch of the recording (:func:`_quietest_stretch`).
        ``'auto'`` (default): the initial rest, or, if the recording does not start at
        rest and ``init_duration`` is not given, the quietest stretch, saying why in
        :attr:`StaticPoses.reference_note`.

    Returns
    -------
    StaticPoses
        The initial rest is normally the first pose.

    Raises
    ------
    RecordingError
        Non-finite values, time not strictly increasing, a recording shorter than three
        windows, an initial segment that is not at rest (the sensor never rests, or
        moves at the start), or no static pose at all.
    """
    t, acc, temp = _validate(t, acc, temp)
    n = t.size
    fs = 1.0 / float(np.median(np.diff(t)))
    w = _window_samples(window, threshold_factor, min_duration, trim, fs, n)
    h = w // 2
    v = _rolling_variance_trace(acc, w)
    m = int(round(trim * fs))
    n_min = max(int(np.ceil(min_duration * fs)), 2)
    init, vref, reference, note = _noise_reference(t, acc, v, noise_reference, init_duration, window,
                                                   threshold_factor, w, m, fs)
    spans = _spans(_runs(v < threshold_factor * vref), h, m, n)
    spans = spans[spans[:, 1] - spans[:, 0] >= n_min]
    if len(spans) == 0:
        raise RecordingError("no static interval found: the sensor never rests long enough")
    return _pose_statistics(t, acc, temp, spans, init, reference, note)



def _window_samples(window: float, threshold_factor: float, min_duration: float, trim: float, fs: float,
                    n: int) -> int:
    """The variance window in samples (odd, so that it is centred on a sample); the settings and
    a recording too short for them refused in one line."""
    if not (window > 0 and threshold_factor > 1 and min_duration >= 0 and trim >= 0):
        raise AccelcalError("need window > 0, threshold_factor > 1, min_duration >= 0 and trim >= 0")
    if window * fs < 3:
        raise RecordingError(f"the {window:g} s variance window holds {window * fs:.2g} samples at {fs:.4g} Hz; it "
                             "needs at least 3: give a longer --window, or check the time unit (--time-unit)")
    w = max(3, int(round(window * fs)) | 1)
    if n < 3 * w:
        raise RecordingError(f"recording too short: {n} samples ({n / fs:.2f} s); "
                             f"need at least 3 windows ({3 * w} samples)")
    return w


def _noise_reference(t, acc, v, noise_reference: str, init_duration, window: float, threshold_factor: float,
                     w: int, m: int, fs: float):
    """The stretch whose variance is the noise reference, that variance, which stretch it is
    (``initial_rest`` or ``quietest_stretch``) and a note when the initial rest was not usable."""
    if noise_reference not in ("auto", "initial", "quietest"):
        raise AccelcalError(f"noise_reference must be 'auto', 'initial' or 'quietest', got {noise_reference!r}")
    if noise_reference == "quietest":
        init, vref = _quietest_stretch(acc, v, w, fs, "")
        return init, vref, "quietest_stretch", ""
    try:
        init = _initial_segment(v, init_duration, window, threshold_factor, w, w // 2, m, t.size, fs)
        return init, _check_initial_rest(acc, v, init, w, threshold_factor, fs), "initial_rest", ""
    except RecordingError as e:
        if noise_reference == "initial" or init_duration is not None:
            raise
        note = str(e)
        init, vref = _quietest_stretch(acc, v, w, fs, note)
        note = (f"{note}; noise level taken from the quietest {(init[1] - init[0]) / fs:.1f} s stretch "
                f"(t = {t[init[0]]:.1f}-{t[init[1] - 1]:.1f} s)")
        return init, vref, "quietest_stretch", note


def _initial_segment(v, init_duration, window, k, w, h, m, n, fs) -> tuple[int, int]:
    """The initial rest: found from the data (first run below k × the first window's variance) or given."""
    if init_duration is None:
        seed = v[h]  # variance of the first window; v[0] == seed, so the first run starts at 0
        if seed <= 0:
            raise RecordingError("the first window has zero variance: the sensor output is constant (stuck?)")
        return tuple(_spans(_runs(v < k * seed)[:1], h, m, n)[0])
    n0 = int(round(init_duration * fs))
    if not w <= n0 <= n:
        raise RecordingError(f"init_duration {init_duration:g} s must cover one window ({window:g} s) "
                             f"and fit in the recording ({n / fs:.1f} s)")
    return (0, n0)


def static_poses_from_intervals(t, acc, intervals, *, temp=None) -> StaticPoses:
    """Pose statistics of known static intervals (no detection).

    Parameters
    ----------
    t, acc, temp
        As for :func:`detect_static`.
    intervals : array_like of int, shape (k, 2)
        ``[start, stop)`` sample ranges, sorted and disjoint, at least 2 samples each
        (:attr:`accelcal.recording.Recording.intervals`).

    Returns
    -------
    StaticPoses
        ``reference='known_intervals'``; the noise statistics of each pose come from its
        own samples, as for detected poses.
    """
    t, acc, temp = _validate(t, acc, temp)
    spans = np.asarray(intervals, dtype=np.int64).reshape(-1, 2)
    if len(spans) == 0 or np.any(spans[:, 0] < 0) or np.any(spans[:, 1] > t.size) \
            or np.any(spans[:, 1] - spans[:, 0] < 2) or np.any(spans[1:, 0] < spans[:-1, 1]):
        raise RecordingError("known static intervals must be sorted, disjoint sample ranges of at least "
                             f"2 samples inside the recording's {t.size}")
    return _pose_statistics(t, acc, temp, spans, tuple(int(x) for x in spans[0]), "known_intervals", "")


def detect_static_recording(rec, **kw) -> StaticPoses:
    """The static poses of a :class:`~accelcal.recording.Recording` (uses its temperature).

    Its known static intervals (:attr:`~accelcal.recording.Recording.intervals`: a block
    log's blocks, a section list, a ``pose`` column) when it carries them
    (:func:`static_poses_from_intervals`; the detection settings ``kw`` are then unused),
    else :func:`detect_static` with ``kw``.
    """
    if getattr(rec, "intervals", None) is not None:
        return static_poses_from_intervals(rec.t, rec.acc, rec.intervals, temp=rec.temp)
    return detect_static(rec.t, rec.acc, temp=rec.temp, **kw)


# --------------------------------------------------------------------------- helpers


def _validate(t, acc, temp):
    t = np.asarray(t, dtype=float)
    acc = np.asarray(acc, dtype=float)
    if t.ndim != 1 or acc.shape != (t.size, 3):
        raise RecordingError(f"need t of shape (n,) and acc of shape (n, 3); got {t.shape} and {acc.shape}")
    if temp is not None:
        temp = np.asarray(temp, dtype=float)
        if temp.shape != t.shape:
            raise RecordingError(f"temp has shape {temp.shape}, expected {t.shape}")
    for name, a in (("t", t), ("acc", acc), ("temp", temp)):
        if a is not None and not np.all(np.isfinite(a)):
            raise RecordingError(f"non-finite value in {name} (first at sample "
                                 f"{int(np.flatnonzero(~np.isfinite(a).reshape(len(a), -1).all(1))[0])})")
    if t.size < 2 or np.any(np.diff(t) <= 0):
        i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1 if t.size >= 2 else 0
        raise RecordingError(f"time must be strictly increasing with at least 2 samples (fails at sample {i})")
    return t, acc, temp


def _rolling_variance_trace(acc: np.ndarray, w: int) -> np.ndarray:
    """Trace of the covariance of each centred window of ``w`` samples; edges copy the nearest full window.

    Cumulative sums make this O(n).  The data are centred on their first sample
    first, so that raw counts around 32768 do not cost digits in the sums of squares.
    """
    x = acc - acc[0]
    c1 = np.concatenate([np.zeros((1, 3)), np.cumsum(x, axis=0)])
    c2 = np.concatenate([np.zeros((1, 3)), np.cumsum(x * x, axis=0)])
    s1 = c1[w:] - c1[:-w]
    s2 = c2[w:] - c2[:-w]
    var = np.maximum((s2 - s1 * s1 / w) / (w - 1), 0.0).sum(axis=1)  # clip round-off below zero
    h = w // 2
    return np.concatenate([np.full(h, var[0]), var, np.full(acc.shape[0] - h - var.size, var[-1])])


def _runs(mask: np.ndarray) -> np.ndarray:
    """``[start, stop)`` of each run of True in ``mask``, shape (k, 2)."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return np.column_stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1)])


def _spans(runs: np.ndarray, h: int, m: int, n: int) -> np.ndarray:
    """Samples covered by the quiet windows of each run of centres, minus ``m`` at ends that border motion."""
    start = runs[:, 0] - h
    stop = runs[:, 1] + h
    start = np.where(start > 0, start + m, 0)   # the recording's own start borders no motion
    stop = np.where(stop < n, stop - m, n)
    # Two quiet runs closer than a window (a motion so brief that the windows only partly
    # holding it stay quiet) would give poses that share samples: cut both at the middle
    # of the loud centres between them, ``m`` either side, so that poses stay disjoint.
    clash = np.flatnonzero(stop[:-1] > start[1:])
    mid = (runs[clash, 1] + runs[clash + 1, 0]) // 2
    stop[clash], start[clash + 1] = mid - m, mid + m
    return np.column_stack([start, np.maximum(stop, start)])


def _check_initial_rest(acc, v, init, w, k, fs) -> float:
    """Check that the initial segment is a rest and return the trace of its covariance.

    Three symptoms of a segment that is not at rest, each fatal:

    * shorter than one window: too short to learn a noise level from;
    * its mean drifts: split into blocks of about one window, the block means spread
      by more than ``MAX_INIT_DRIFT`` within-block noise std on some axis (a slow
      rotation; a rest drifts by a small fraction of the noise);
    * it is not the quiet reference: the windows of the rest of the recording go
      below ``1/k`` of its variance (the sensor shook at the start, then rested), or
      one of its own blocks exceeds ``k`` × their median (motion inside it).
    """
    a, b = init
    if b - a < w:  # the noise level must rest on at least as many samples as each window
        raise RecordingError(f"the recording does not start at rest: initial rest only {(b - a) / fs:.2f} s, "
                             f"need at least one window ({w / fs:.2f} s)")
    seg = acc[a:b]
    blocks = np.array_split(seg, min(max((b - a) // w, 2), 64))
    means = np.array([blk.mean(axis=0) for blk in blocks])
    bvars = np.array([blk.var(axis=0, ddof=1) for blk in blocks])
    within = np.sqrt(bvars.mean(axis=0))
    drift = (means.max(axis=0) - means.min(axis=0)) / np.where(within > 0, within, np.inf)
    where = f"the initial segment (0-{b / fs:.1f} s) is not at rest"
    if np.any(drift > MAX_INIT_DRIFT):
        raise RecordingError(f"{where}: its mean drifts by {drift.max():.1f} noise std "
                             "(the sensor never rests, or moves at the start)")
    vtr = bvars.sum(axis=1)
    vref = float(seg.var(axis=0, ddof=1).sum())
    if vref <= 0:
        raise RecordingError(f"{where}: zero variance, the sensor output is constant (stuck?)")
    if vtr.max() > k * np.median(vtr):
        raise RecordingError(f"{where}: part of it is {vtr.max() / np.median(vtr):.0f}x noisier than the rest of it")
    rest = np.concatenate([v[:a], v[b:]])
    if rest.size and rest.min() * k < vref:
        raise RecordingError(f"{where}: later parts of the recording are {vref / rest.min():.0f}x quieter "
                             "(the sensor moved or vibrated at the start)")
    return vref


def _quietest_stretch(acc, v, w, fs, why: str) -> tuple[tuple[int, int], float]:
    """The quietest stretch of ``2w + 1`` samples and the trace of its covariance.

    The stretch whose loudest window (of the ``w + 2`` centred windows inside it) is the
    quietest of the recording.  Being the minimum over the recording, its variance is
    biased low (by about 15 % for a 2 s stretch among a few dozen independent ones): the
    threshold is that much stricter, which keeps poses, not motion.  It must look like a
    rest: split into 4 blocks, the block means may spread by at most
    ``MAX_QUIET_DRIFT`` per-sample noise std on every axis (white noise: ≈ 0.3; the
    quietest stretches of the real recordings: 0.1-0.55; a random walk of the same
    window variance: ≥ 2), and its variance must not be zero.
    """
    n = acc.shape[0]
    L = 2 * w + 1
    if n < L:
        raise RecordingError(f"recording too short for a noise reference: {n} samples, need {L}")
    h = w // 2
    centres = np.lib.stride_tricks.sliding_window_view(v[h:n - h], L - w + 1)
    j = int(np.argmin(centres.max(axis=1)))
    seg = acc[j:j + L]
    vref = float(seg.var(axis=0, ddof=1).sum())
    lead = f"{why}; " if why else ""
    if vref <= 0:
        raise RecordingError(f"{lead}the quietest stretch has zero variance: the sensor output is constant (stuck?)")
    blocks = np.array_split(seg, 4)
    means = np.array([b.mean(axis=0) for b in blocks])
    within = np.sqrt(np.mean([b.var(axis=0, ddof=1) for b in blocks], axis=0))
    drift = float(np.max((means.max(axis=0) - means.min(axis=0)) / np.where(within > 0, within, np.inf)))
    if drift > MAX_QUIET_DRIFT:
        raise RecordingError(f"{lead}its quietest {L / fs:.1f} s stretch is not at rest either (its mean drifts by "
                             f"{drift:.1f} noise std): the sensor never holds still; record at least one still "
                             f"stretch of {L / fs:.1f} s or give the rests with --intervals")
    return (j, j + L), vref


def integrated_autocorr_time(x: np.ndarray) -> np.ndarray:
    """Integrated autocorrelation time of each column of ``x``, at least 1.

    Geyer's initial positive sequence: sum the pairs ``ρ(2j) + ρ(2j+1)`` while positive,
    ``τ = 2 Σ - 1``.  It needs no lag cut-off, and truncating at the first
    non-positive pair stops before the noisy tail of the estimate.  The variance of the
    mean of ``n`` correlated samples is ``τ σ² / n``.

    Parameters
    ----------
    x : numpy.ndarray, shape (n, k)
        Samples of ``k`` series (e.g. the three axes of one rest).

    Returns
    -------
    numpy.ndarray, shape (k,)
        τ of each column, in samples, between 1 and ``n``.
    """
    n = x.shape[0]
    xc = x - x.mean(axis=0)
    f = np.fft.rfft(xc, n=2 * n, axis=0)  # zero-padded: linear, not circular, correlation
    acov = np.fft.irfft(f * np.conj(f), axis=0)[:n]
    tau = np.ones(x.shape[1])
    for j in range(x.shape[1]):
        if acov[0, j] <= 0:
            continue
        rho = acov[:, j] / acov[0, j]
        pairs = rho[: 2 * (n // 2)].reshape(-1, 2).sum(axis=1)
        neg = np.flatnonzero(pairs <= 0)
        pairs = pairs[: neg[0]] if neg.size else pairs
        tau[j] = max(1.0, 2.0 * pairs.sum() - 1.0)
    return np.minimum(tau, n)


#: Lags whose autocovariances :func:`_segment_statistics` sums directly (Geyer's sequence of a
#: rest of white noise ends within the first few pairs; longer ones take the FFT route).
DIRECT_LAGS = 16


def _segment_statistics(segs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, standard deviation (ddof 1) and :func:`integrated_autocorr_time` of each segment
    (each (k, 3)), all segments of one length at once.

    The autocovariances of the first :data:`DIRECT_LAGS` lags are summed directly, pair of
    lags by pair and only as long as Geyer's sequence of a column goes on (it ends within
    two or three pairs on most rests), instead of two FFTs per pose; a column whose
    sequence runs past them is done by the FFT route.  Same estimator; the
    autocovariances agree to rounding.
    """
    means, std, tau = (np.empty((len(segs), 3)) for _ in range(3))
    groups: dict[int, list[int]] = {}
    for i, s in enumerate(segs):
        groups.setdefault(len(s), []).append(i)
    for n, idx in groups.items():
        X = np.stack([segs[i] for i in idx])
        # one mean and one pass of deviations for the means, the stds and the autocovariances
        # (the operations of ``X.mean``/``X.std(ddof=1)`` in their order: the same bits)
        mu = X.mean(axis=1, keepdims=True)
        D = X - mu
        means[idx] = mu[:, 0, :]
        std[idx] = np.sqrt(np.square(D).sum(axis=1) / (n - 1))
        C = D.transpose(0, 2, 1).reshape(-1, n)  # one row per column
        tau[idx] = _geyer(_leading_autocovariances(C, min(DIRECT_LAGS, 2 * (n // 2))), n).reshape(-1, 3)
        for i in np.asarray(idx)[np.isnan(tau[idx]).any(axis=1)]:  # sequence longer than the direct lags
            tau[i] = integrated_autocorr_time(segs[i])
    return means, std, tau


def _leading_autocovariances(C: np.ndarray, K: int) -> np.ndarray:
    """``Σ_t C[c, t] C[c, t + k]`` for lags ``k < K`` (``K`` even), (c, K); a row is left NaN
    from the pair of lags after its first non-positive autocorrelation pair (Geyer stops there)."""
    c, n = C.shape
    acov = np.full((c, K), np.nan)
    rows, Ca = np.arange(c), C
    for k in range(0, K, 2):
        for lag in (k, k + 1):
            acov[rows, lag] = np.einsum("ct,ct->c", Ca[:, :n - lag], Ca[:, lag:])
        a0 = acov[rows, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            go = (a0 > 0) & (acov[rows, k] / a0 + acov[rows, k + 1] / a0 > 0)
        rows, Ca = rows[go], Ca[go]
        if not rows.size:
            break
    return acov


def _geyer(acov: np.ndarray, n: int) -> np.ndarray:
    """Geyer's τ (c,) from the leading autocovariances (c, K) of columns of ``n`` samples
    (:func:`_leading_autocovariances`), as :func:`integrated_autocorr_time` sums them; NaN
    where all ``K/2`` pairs are positive and the full sequence is longer."""
    K = acov.shape[1]
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = acov / acov[:, :1]
    pairs = rho[:, 0::2] + rho[:, 1::2]
    nonpos = pairs <= 0  # NaN (not computed: after the end) is not
    end = np.where(nonpos.any(axis=1), np.argmax(nonpos, axis=1), K // 2)  # pairs summed: [0, end)
    total = np.sum(np.where(np.arange(K // 2)[None, :] < end[:, None], pairs, 0.0), axis=1)
    tau = np.maximum(1.0, 2.0 * total - 1.0)
    tau[(end == K // 2) & (K < 2 * (n // 2))] = np.nan
    tau[~(acov[:, 0] > 0)] = 1.0
    return np.minimum(tau, n)


def _pose_statistics(t, acc, temp, spans, init, reference="initial_rest", note="") -> StaticPoses:
    means, noise_std, tau = _segment_statistics([acc[a:b] for a, b in spans])
    mean_std = noise_std * np.sqrt(tau / (spans[:, 1] - spans[:, 0])[:, None])
    t_start, t_end = t[spans[:, 0]], t[spans[:, 1] - 1]
    ptemp = None if temp is None else np.array([temp[a:b].mean() for a, b in spans])
    return StaticPoses(means=means, t_start=t_start, t_end=t_end, t_mid=0.5 * (t_start + t_end),
                       n_samples=(spans[:, 1] - spans[:, 0]).astype(int), noise_std=noise_std,
                       mean_std=mean_std, temp=ptemp, intervals=spans.astype(int),
                       init_rest=(int(init[0]), int(init[1])), reference=reference, reference_note=note)
