"""The inertial recording every reader returns: :class:`Recording`.

A recording is time [s], specific force (n, 3) in one unit (m/s² or raw counts), an
optional temperature and angular rate, and what the file said about it: known static
intervals, notes on what a reader assumed, the units.  Readers of the file formats are in
:mod:`accelcal.formats`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .errors import RecordingError

#: Fewest samples a recording may have: below this nothing (rest, noise) can be estimated.
MIN_ROWS = 10


#: What a reader's sample is called in a count ("only 3 messages"), by the unit that numbers it.
_COUNT_NOUNS = {"line": "data rows", "message": "messages", "sample": "samples", "row": "rows"}
#: The default names of the fields :func:`checked_recording` checks.
_FIELD_NAMES = {"t": "time", "acc": "specific force", "gyro": "angular rate"}


@dataclass(frozen=True)
class Origin:
    """Where a reader found the samples of a recording: what the one-line messages of
    :func:`checked_recording` need to name the place a user can open, and the fix.

    The checks every recording must pass are made once, on every reader's output; only the
    reader knows that sample 7 is line 12 of a table or message 7 of topic ``/imu``, so it
    says so here.

    Attributes
    ----------
    unit : str
        What numbers a sample in the file: ``'line'`` (a text file, 1-based), ``'message'``
        (a log, 0-based as its tools count), ``'sample'`` (nothing better).
    first : int
        The number of sample 0 (the line of the first data row).
    numbers : sequence of int, or None
        Each sample's number when it is not ``first + k`` (comment lines skipped, rows
        sorted by a counter); None otherwise.
    label : str
        What in the file holds the samples (``'topic /imu'``, ``'sensor_accel instance 0'``);
        ``''``: the whole file.
    names : tuple of (field, name)
        What the file calls the checked fields ``t``, ``acc``, ``gyro``: one name
        (``('acc', 'linear_acceleration')``) or one per column (``('acc', ("column 'ax'",
        "column 'ay'", "column 'az'"))``); a field not named is called by what it is.
    fix : str
        What to do about a recording too short in this file (``'choose another topic with
        --topic'``); ``''``: the general hint.
    time_fix : str
        What to do about time that does not increase in this file (a log's sensor stamps:
        ``'use the bag's record time (--time-source log)'``); ``''``: the general hints.
    """

    unit: str = "sample"
    first: int = 0
    numbers: Sequence[int] | None = None
    label: str = ""
    names: tuple = ()
    fix: str = ""
    time_fix: str = ""

    def place(self, k: int) -> str:
        """Where sample ``k`` is in the file (``'line 12'``, ``'message 7'``)."""
        return f"{self.unit} {int(self.numbers[k]) if self.numbers is not None else self.first + k}"

    def name(self, field: str, column: int | None = None) -> str:
        """What the file calls ``field`` (``t``, ``acc``, ``gyro``), or its ``column``."""
        named = dict(self.names).get(field)
        if isinstance(named, tuple):
            named = named[column] if column is not None else ", ".join(named)
        return _FIELD_NAMES[field] + (f" ({named})" if named else "")

    def count(self, n: int) -> str:
        """``n`` samples counted as the file counts them (``'only 3 messages'``, ``'no messages'``)."""
        return f"{'only ' + str(n) if n else 'no'} {_COUNT_NOUNS.get(self.unit, self.unit + 's')}"


#: The origin of a recording whose reader says nothing about where its samples are.
BY_INDEX = Origin()


@dataclass(frozen=True)
class Recording:
    """One recording of an accelerometer (and, when the file has one, a gyroscope).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s], strictly increasing.
    acc : ndarray, shape (n, 3), or None
        Specific force in the file's unit (m/s² or raw counts); None for a gyro-only
        recording (a rate table's rotations: then ``gyro`` is required and ``unit`` None).
    temp : ndarray, shape (n,) or None
        Temperature [°C] if recorded.
    source : str
        Where the data came from (usually the file path).
    intervals : ndarray of int, shape (k, 2), or None
        Known static intervals ``[start, stop)`` (sample indices, sorted, disjoint), when
        the file says where the sensor rests (a block log, a section list, a ``pose``
        column).  :func:`accelcal.static.detect_static_recording` then uses them instead
        of detecting rests.
    labels : tuple of str, or None
        One name per known interval (``x_p``, ``block03``, ...).
    notes : tuple of str
        What a reader assumed that the user should know (time made from a sample index,
        unit taken from a header...): the CLI prints them.
    unit : {'m/s^2', 'counts'} or None
        Unit of ``acc`` when the file or the user said it (data in g or mg are converted
        to m/s² when read, :mod:`accelcal.units`); None when unknown.
    time_column : tuple (str, ndarray of str), or None
        The file's time column as written (name, values), so that a corrected copy can
        keep it (``accelcal apply``); None when the file has none.
    gyro : ndarray, shape (n, 3), or None
        Angular rate at the same instants as ``acc``, in ``gyro_unit``; None when the
        file has no gyroscope (or the reader does not read it).
    gyro_unit : {'rad/s', 'counts'} or None
        Unit of ``gyro`` when known (data in deg/s are converted to rad/s when read); None
        with a gyro: not stated, the values as written, for the motions of a calibration
        session to decide (:mod:`accelcal.gyro.unit_evidence`; a static record cannot:
        :func:`accelcal.formats.units_evidence.require_gyro_unit`).
    mag : ndarray, shape (n, 3), or None
        Magnetic field at the same instants as ``acc``, in ``mag_unit``; None when the file
        has no magnetometer (or the reader does not read it).
    mag_unit : {'uT', 'counts'} or None
        Unit of ``mag`` (gauss, tesla... are converted to µT when read).
    rotations : dict or None
        Known rotations of a Ferraris session (imucal's ``x_rot``, ``y_rot``, ``z_rot``
        sections): ``{label: (start, stop)}``, sample ranges; None when the file does not
        mark them.  The gyro's Ferraris calibration (:mod:`accelcal.gyro.ferraris`) uses them
        with the known static intervals.
    device_id : str or None
        The sensor's identity as the log names it (PX4's ``device_id``), so that a calibration
        applied to another unit can be warned; None when the file names none.
    precalibrated : str or None
        What these values are, when the file says someone calibrated them already (a PX4
        ``sensor_combined``); ``accelcal apply`` refuses to correct them a second time unless told.
    runs : ndarray of int, shape (k, 2), or None
        Separately recorded runs joined into one recording (``[start, stop)``, sorted,
        covering every sample; several variables of one ``.mat`` file): each rests on its
        own, so each has its own bias, and no motion spans two.  None: one run.
    origin : Origin or None
        Where the reader found the samples (the line, message or topic), for the messages
        of :func:`checked_recording`; None: samples are named by their index.
    """

    t: np.ndarray
    acc: np.ndarray
    temp: np.ndarray | None
    source: str
    intervals: np.ndarray | None = None
    labels: tuple[str, ...] | None = None
    notes: tuple[str, ...] = ()
    unit: str | None = None
    time_column: tuple | None = None
    gyro: np.ndarray | None = None
    gyro_unit: str | None = None
    rotations: dict | None = None
    device_id: str | None = None
    precalibrated: str | None = None
    runs: np.ndarray | None = None
    mag: np.ndarray | None = None
    mag_unit: str | None = None
    origin: Origin | None = None

    def __post_init__(self):
        t = _frozen_float(self.t)
        if self.acc is None and (self.gyro is None or self.unit is not None):
            raise RecordingError(f"{self.source}: a recording without accelerometer needs gyroscope data "
                                 "(and no acceleration unit)")
        acc = None if self.acc is None else _frozen_float(self.acc)
        temp = None if self.temp is None else _frozen_float(self.temp)
        if t.ndim != 1 or (acc is not None and acc.shape != (t.size, 3)) or (temp is not None and
                                                                              temp.shape != t.shape):
            raise RecordingError(
                f"{self.source}: inconsistent shapes t{t.shape}, acc{None if acc is None else acc.shape}"
                + ("" if temp is None else f", temp{temp.shape}"))
        gyro = _check_gyro(self.gyro, self.gyro_unit, t.size, self.source)
        intervals, labels = _check_intervals(self.intervals, self.labels, t.size, self.source)
        mag = _check_mag(self.mag, self.mag_unit, t.size, self.source)
        object.__setattr__(self, "mag", mag)
        for a in (t, acc, temp, intervals, gyro, mag):
            if a is not None:
                a.setflags(write=False)  # frozen means frozen: no in-place edits of shared data
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "acc", acc)
        object.__setattr__(self, "temp", temp)
        object.__setattr__(self, "gyro", gyro)
        object.__setattr__(self, "intervals", intervals)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "notes", tuple(self.notes))
        object.__setattr__(self, "rotations", _check_rotations(self.rotations, t.size, self.source))
        object.__setattr__(self, "runs", _check_runs(self.runs, t.size, self.source))
        if self.origin is not None and self.origin.numbers is not None and len(self.origin.numbers) != t.size:
            raise RecordingError(f"{self.source}: the origin places {len(self.origin.numbers)} samples, the recording "
                                 f"has {t.size}")
        if self.unit not in (None, "m/s^2", "counts"):
            raise RecordingError(f"{self.source}: unit {self.unit!r}; a Recording holds m/s^2 or counts "
                                 "(convert g and mg when reading)")

    @property
    def n(self) -> int:
        """Number of samples."""
        return self.t.size

    @property
    def rate(self) -> float:
        """Sampling rate [Hz] from the median time step."""
        return 1.0 / float(np.median(np.diff(self.t)))


def checked_recording(rec: Recording) -> Recording:
    """``rec`` if it holds what every reader's output must (else one :class:`RecordingError` line).

    The invariants of a recording that the estimators rely on, checked once where every
    reader's output passes (:func:`accelcal.formats.read`), not in each reader: at least
    :data:`MIN_ROWS` samples, finite time, specific force and angular rate, time strictly
    increasing.  A temperature column with non-finite values is dropped, with a note.  The
    message names the place in the file from the reader's :class:`Origin` (the line, the
    message of a topic) and the fix.
    """
    origin = rec.origin or BY_INDEX
    where = f"{rec.source}: {origin.label}: " if origin.label else f"{rec.source}: "
    if rec.n < MIN_ROWS:
        fix = origin.fix or "an empty or truncated file?"
        raise RecordingError(f"{where}{origin.count(rec.n)}; need at least {MIN_ROWS} ({fix})")
    for field in ("t", "acc", "gyro"):
        values = getattr(rec, field)
        if values is not None and not np.all(np.isfinite(values)):
            bad = ~np.isfinite(values.reshape(rec.n, -1))
            k = int(np.flatnonzero(bad.any(axis=1))[0])
            j = int(np.flatnonzero(bad[k])[0]) if values.ndim == 2 else None
            raise RecordingError(
                f"{where}{origin.name(field, j)}: non-finite value {values.reshape(rec.n, -1)[k, j or 0]} at "
                f"{origin.place(k)} ({int(bad.any(axis=1).sum())} such {origin.unit}(s)); remove or repair it")
    _check_increasing(rec.t, where, origin)
    if rec.temp is not None and not np.all(np.isfinite(rec.temp)):
        return replace(rec, temp=None, notes=rec.notes + ("temperature column has non-finite values: not used",))
    return rec


def _check_increasing(t: np.ndarray, where: str, origin: Origin) -> None:
    """Time strictly increasing, else one line: where it repeats or goes back, and the fix for each."""
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size == 0:
        return
    k = int(bad[0]) + 1
    if steps[k - 1] == 0:
        what, fix = "repeats", "time stamps coarser than the sampling? pass --rate HZ to time the samples by their index"
    else:
        what, fix = "goes back", ("samples out of order or two recordings joined: sort or split the file, or pass "
                                  "--rate HZ to time the samples by their index")
    raise RecordingError(f"{where}{origin.name('t')} {what} at {origin.place(k)} ({t[k]:.9g} s after "
                         f"{t[k - 1]:.9g} s; {bad.size} such step(s)); {origin.time_fix or fix}")


def _check_gyro(gyro, unit: str | None, n: int, source: str):
    """The angular rate as an (n, 3) float array (or None), its unit one a Recording holds."""
    if gyro is None:
        if unit is not None:
            raise RecordingError(f"{source}: a gyroscope unit ({unit!r}) without gyroscope data")
        return None
    gyro = _frozen_float(gyro)
    if gyro.shape != (n, 3):
        raise RecordingError(f"{source}: gyroscope data of shape {gyro.shape}, expected ({n}, 3) like the "
                             "accelerometer")
    if unit not in (None, "rad/s", "counts"):
        raise RecordingError(f"{source}: gyroscope unit {unit!r}; a Recording holds rad/s or counts "
                             "(convert deg/s when reading)")
    return gyro


def _check_runs(runs, n: int, source: str):
    """Runs as a (k, 2) int array of consecutive ranges covering ``[0, n)`` (or None)."""
    if runs is None:
        return None
    r = np.array(runs, dtype=np.int64).reshape(-1, 2)
    if len(r) == 0 or r[0, 0] != 0 or r[-1, 1] != n or np.any(r[1:, 0] != r[:-1, 1]) or np.any(r[:, 1] <= r[:, 0]):
        raise RecordingError(f"{source}: runs {r.tolist()} are not consecutive ranges covering the {n} samples")
    r.setflags(write=False)
    return r


def handed_over(a):
    """``a`` made read-only, so that a :class:`Recording` keeps it instead of copying it: for
    the float arrays a reader has just made and shares with no one (a 10⁶-row table's time,
    acceleration and rate are 56 MB, a fifth of the reading's peak memory).  Anything else
    (None, a view, another dtype) is returned as it is, and copied by the Recording."""
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.base is None:
        a.setflags(write=False)
    return a


def _frozen_float(a) -> np.ndarray:
    """``a`` as a float array of its own: a copy, unless ``a`` is one already (a float array
    that owns its data and is read-only: another Recording's, passed on by ``replace``),
    which is shared (a replace of a 10⁶-sample recording copied 56 MB)."""
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.base is None and not a.flags.writeable:
        return a
    return np.array(a, dtype=float)


def _check_mag(mag, unit: str | None, n: int, source: str):
    """The field as an (n, 3) float array (or None), in a unit a Recording holds."""
    if mag is None:
        return None
    mag = _frozen_float(mag)
    if mag.shape != (n, 3):
        raise RecordingError(f"{source}: magnetometer data of shape {mag.shape}, expected ({n}, 3) like the "
                             "accelerometer")
    if unit not in (None, "uT", "counts"):
        raise RecordingError(f"{source}: magnetometer unit {unit!r}; a Recording holds uT or counts")
    return mag


def _check_rotations(rotations, n: int, source: str):
    """Known rotations as ``{label: (start, stop)}`` of int ranges inside ``[0, n)`` (or None)."""
    if rotations is None:
        return None
    out = {}
    for name, (a, b) in dict(rotations).items():
        a, b = int(a), int(b)
        if not 0 <= a < b <= n:
            raise RecordingError(f"{source}: rotation {name!r} (samples {a}-{b}) is not a range inside the "
                                 f"recording's {n} samples")
        out[str(name)] = (a, b)
    return out or None


def _check_intervals(intervals, labels, n: int, source: str):
    """Known static intervals as a sorted, disjoint (k, 2) int array inside ``[0, n)``, with labels."""
    if intervals is None:
        if labels is not None:
            raise RecordingError(f"{source}: interval labels without intervals")
        return None, None
    iv = np.array(intervals, dtype=np.int64).reshape(-1, 2)
    if len(iv) == 0:
        raise RecordingError(f"{source}: the list of known static intervals is empty")
    if np.any(iv[:, 0] < 0) or np.any(iv[:, 1] > n) or np.any(iv[:, 1] - iv[:, 0] < 2):
        k = int(np.flatnonzero((iv[:, 0] < 0) | (iv[:, 1] > n) | (iv[:, 1] - iv[:, 0] < 2))[0])
        raise RecordingError(f"{source}: known static interval {k} (samples {iv[k, 0]}-{iv[k, 1]}) is not a range "
                             f"of at least 2 samples inside the recording's {n}")
    if np.any(np.diff(iv[:, 0]) <= 0) or np.any(iv[1:, 0] < iv[:-1, 1]):
        raise RecordingError(f"{source}: known static intervals overlap or are not in time order")
    labels = tuple(f"pose{k:02d}" for k in range(len(iv))) if labels is None else tuple(str(x) for x in labels)
    if len(labels) != len(iv):
        raise RecordingError(f"{source}: {len(labels)} labels for {len(iv)} known static intervals")
    return iv, labels


def intervals_from_labels(labels) -> tuple[np.ndarray | None, tuple[str, ...] | None]:
    """Known static intervals from a per-sample label column: each run of one non-empty label.

    Parameters
    ----------
    labels : array_like of str, shape (n,)
        ``''`` (or ``'-'``) where the sensor is not in a known static pose.

    Returns
    -------
    intervals : ndarray of int, shape (k, 2), or None if no sample is labelled
    labels : tuple of str, or None
    """
    lab = np.char.strip(np.asarray(labels, dtype=str))
    lab = np.where(lab == "-", "", lab)
    change = np.flatnonzero(lab[1:] != lab[:-1]) + 1
    starts = np.concatenate([[0], change])
    stops = np.concatenate([change, [lab.size]])
    keep = lab[starts] != ""
    if not keep.any():
        return None, None
    return np.column_stack([starts[keep], stops[keep]]), tuple(lab[starts[keep]])


def labels_from_intervals(intervals, labels, n: int) -> np.ndarray:
    """The per-sample label column of known static intervals (inverse of :func:`intervals_from_labels`)."""
    out = np.full(n, "", dtype=object)
    prev_stop, prev_label = -1, None
    for (a, b), name in zip(intervals, labels):
        if not name or name == "-" or name != name.strip() or (a == prev_stop and name == prev_label):
            raise RecordingError(f"interval label {name!r} cannot be written as a pose column "
                                 "(empty, padded, or equal to the label of the interval it touches)")
        out[a:b] = name
        prev_stop, prev_label = b, name
    return out
