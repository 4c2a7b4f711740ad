"""What the log formats share (:mod:`.ros`, :mod:`.px4`, :mod:`.ardupilot`): topic choice, time
stamps, bounded buffers, progress.

A log holds many topics and two clocks.  The readers differ in how they decode
messages; they agree on everything here:

* the IMU topic is chosen automatically only when there is exactly one; several are
  listed in one line with the option that picks one;
* time: the sensor's own stamp (a ROS header stamp, PX4's ``timestamp_sample``) by
  default, the time the log recorded the message on request; when both exist and they
  disagree (a latency that jumps by more than two sample periods, or clocks more than a
  second apart) a note says so;
* samples are streamed into preallocated arrays (:class:`ColumnBuffer`), never into a
  list of message objects, so memory is the size of the output;
* a read that lasts longer than a couple of seconds reports its progress on stderr.

Each reader checks its optional extra through its registry entry
(:meth:`accelcal.formats.registry.Format.check_extra`: one line naming the ``pip install``
that fixes it) before importing it.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import LogFormatError, TopicError
from ..recording import Origin, Recording
from .clock import clocked_time
from .registry import TIME_SOURCES, format_named

#: Largest spread (1st to 99th percentile) of the latency log − sensor stamp, in sample
#: periods, that is not reported as a disagreement of the two clocks.
MAX_LATENCY_SPREAD_PERIODS = 2.0
#: Largest median latency [s] not reported (two clocks more than this apart: sim time,
#: a device clock that was never synchronised).
MAX_LATENCY_S = 1.0
#: Seconds a read may take before it reports progress.
PROGRESS_AFTER_S = 2.0
PROGRESS_EVERY_S = 5.0


def require_extra(format_name: str, path=None) -> None:
    """The optional extra of a log format, checked through its registry entry (one line if missing)."""
    format_named(format_name).check_extra(path)


def check_time_source(time_source: str) -> str:
    if time_source not in TIME_SOURCES:
        raise TopicError(f"time_source must be one of {', '.join(TIME_SOURCES)}, got {time_source!r}")
    return time_source


def choose(path, candidates: dict[str, str], given: str | None, everything: dict[str, str], *,
           kind: str, option: str) -> str:
    """The one IMU topic of a log: ``given`` if it is one, the only candidate, else a one-line error.

    Parameters
    ----------
    candidates : dict
        IMU topics -> a short description (type, message count).
    everything : dict
        Every topic -> its description, to list when the given one is not an IMU topic.
    kind : str
        What a candidate is ("sensor_msgs/Imu topic", "IMU instance").
    option : str
        The option that chooses (``--topic``, ``--instance``).
    """
    if given is not None:
        if given in candidates:
            return given
        if given in everything:
            raise TopicError(f"{path}: {given} is {everything[given]}, not a {kind}; "
                             f"{_listing(candidates, kind)}")
        raise TopicError(f"{path}: {given} is not in this log; {_listing(candidates, kind)}")
    if len(candidates) == 1:
        return next(iter(candidates))
    if not candidates:
        others = ", ".join(f"{k} ({v})" for k, v in list(everything.items())[:8]) or "none"
        raise TopicError(f"{path}: no {kind} in this log (topics: {others})")
    raise TopicError(f"{path}: {len(candidates)} {kind}s: "
                     + ", ".join(f"{k} ({v})" for k, v in candidates.items()) + f"; choose one with {option}")


def _listing(candidates: dict, kind: str) -> str:
    if not candidates:
        return f"this log has no {kind}"
    return f"{kind}s: " + ", ".join(f"{k} ({v})" for k, v in candidates.items())


class ColumnBuffer:
    """Rows of fixed width appended in blocks into one preallocated array (grown by doubling).

    ``capacity`` is the expected number of rows (the log's message count); a log that holds
    more grows the array, one that holds fewer is trimmed by :meth:`result`.
    """

    def __init__(self, capacity: int, width: int, dtype=np.float64):
        self._a = np.empty((max(int(capacity), 16), width), dtype=dtype)
        self.n = 0

    def extend(self, block: np.ndarray) -> None:
        k = len(block)
        if self.n + k > len(self._a):
            grown = np.empty((max(2 * len(self._a), self.n + k), self._a.shape[1]), dtype=self._a.dtype)
            grown[: self.n] = self._a[: self.n]
            self._a = grown
        self._a[self.n: self.n + k] = block
        self.n += k

    def result(self) -> np.ndarray:
        return self._a[: self.n]


class Progress:
    """Progress of a long read on stderr: silent for :data:`PROGRESS_AFTER_S`, then a line every few seconds.

    ``progress``: None (this default behaviour), False (silent) or a callable
    ``f(done, total)`` called instead of printing.
    """

    def __init__(self, what: str, total: int | None, progress=None, unit: str = "messages"):
        self.what, self.total, self.unit = what, total, unit
        self.callback: Callable | None = progress if callable(progress) else None
        self.silent = progress is False
        self.start = self.last = time.monotonic()
        self.printed = False

    def __call__(self, done: int) -> None:
        if self.callback is not None:
            self.callback(done, self.total)
            return
        if self.silent:
            return
        now = time.monotonic()
        if now - self.start < PROGRESS_AFTER_S or (self.printed and now - self.last < PROGRESS_EVERY_S):
            return
        share = f" ({100 * done / self.total:.0f} %)" if self.total else ""
        print(f"accelcal: reading {self.what}: {done:,} {self.unit}{share} ...", file=sys.stderr, flush=True)
        self.last, self.printed = now, True


#: Largest time stamp [µs] a log may hold: 2^53 µs (285 years), exact in float64, and in int64
#: nanoseconds.  A damaged log's stamps can be anything; beyond it they would wrap silently.
MAX_STAMP_US = 2**53


def microseconds(values, path, label: str) -> np.ndarray:
    """Time stamps [µs] as int64, each checked to lie in ``[0, MAX_STAMP_US]``; else one line."""
    v = np.asarray(values)
    bad = (v < 0) | (v > MAX_STAMP_US)
    if v.dtype.kind == "f":
        bad |= ~np.isfinite(v)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise LogFormatError(f"{path}: {label}: time stamp {v[i]!r} at message {i} is not a time ({int(bad.sum())} "
                             "such): the log is damaged; download or copy it again")
    return v.astype(np.int64)


def stamps_to_time(stamps_ns: np.ndarray) -> np.ndarray:
    """Seconds since the first of integer nanosecond stamps (exact differences in int64 first).  Stamps
    that do not increase are refused with every recording's (:func:`accelcal.recording.checked_recording`),
    with the message and the fix the reader's :class:`~accelcal.recording.Origin` gives."""
    return (stamps_ns - stamps_ns[0]) * 1e-9 if len(stamps_ns) else np.zeros(0)


def clock_note(sensor_ns: np.ndarray, log_ns: np.ndarray, sensor_name: str, log_name: str) -> str | None:
    """A note when the sensor stamps and the log times disagree (module docstring), else None."""
    lat = (log_ns - sensor_ns).astype(np.float64) * 1e-9
    if lat.size < 2:
        return None
    period = float(np.median(np.diff(sensor_ns))) * 1e-9
    lo, med, hi = np.percentile(lat, [1, 50, 99])
    if abs(med) <= MAX_LATENCY_S and hi - lo <= MAX_LATENCY_SPREAD_PERIODS * period:
        return None
    return (f"the {sensor_name} and the {log_name} disagree: latency {log_name} - {sensor_name} median "
            f"{1e3 * med:.4g} ms, 1-99 % spread {1e3 * (hi - lo):.3g} ms (sample period {1e3 * period:.3g} ms)")


def topic_origin(label: str, *, time: str, time_fix: str, acc: tuple, gyro: tuple, numbers=None) -> Origin:
    """Where an IMU topic's samples are (its messages, numbered from 0 as the log's tools count
    them), what the log calls its fields (``acc``, ``gyro``: the three of each), and the fixes,
    for the recording's check."""
    return Origin("message", numbers=numbers, label=label, names=(("t", time), ("acc", acc), ("gyro", gyro)),
                  fix="an empty or truncated topic: record the IMU again, or choose another", time_fix=time_fix)


def make_recording(path, *, t, acc, gyro, notes: Sequence[str], time_name: str, time_values, origin: Origin,
                   temp=None, device_id: str | None = None, precalibrated: str | None = None, counter=None,
                   counter_name: str = "counter") -> Recording:
    """The :class:`Recording` of an IMU topic: acc in m/s², gyro in rad/s, the recorded time column kept;
    timed by the sensor's clock fitted to the chosen stamps against ``counter`` (ROS 1's
    ``header.seq``) or the message index (:mod:`.clock`: stamps on it are kept as they are; a
    log's record time, which jitters, is replaced by it).  A sensor stamps each sample: stamps
    that repeat are refused (``origin``'s fix) even with a counter, which numbers gaps only."""
    t = np.asarray(t, float)
    if counter is not None and not np.all(np.diff(t) > 0):
        counter = None  # the stamps are left as they are, for checked_recording to refuse
    t, clock_notes = clocked_time(t, counter, counter_name=counter_name, mode="auto", timed_by_rate=False,
                                  where=lambda i: f"message {i}", path=path)
    notes = (*notes, *clock_notes)
    return Recording(t, acc, temp, str(path), notes=tuple(notes), unit="m/s^2", time_column=(time_name, time_values),
                     gyro=gyro, gyro_unit=None if gyro is None else "rad/s", device_id=device_id,
                     precalibrated=precalibrated, origin=origin)


__all__ = ["MAX_STAMP_US", "ColumnBuffer", "Progress", "microseconds", "TIME_SOURCES", "check_time_source", "choose",
           "clock_note", "require_extra", "make_recording", "stamps_to_time", "topic_origin"]
