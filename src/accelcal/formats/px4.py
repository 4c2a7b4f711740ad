"""PX4 ULog flight logs: the IMU read through ``pyulog`` (the ``px4`` extra).

Which topic.  PX4 logs the IMU twice:

* ``sensor_accel`` / ``sensor_gyro`` (one instance per physical sensor): the driver's
  output in m/s² and rad/s, rotated to the board frame but *not* calibrated (since
  PX4 1.10; older versions logged calibrated ``x, y, z`` beside ``x_raw``, which the
  notes then say).  What a calibration must start from.
* ``sensor_combined``: the autopilot's own output, already calibrated with its
  ``CAL_ACC*`` / ``CAL_GYRO*`` parameters and averaged over the IMU integration
  interval.  Calibrating it again fits what is left of the autopilot's calibration.

The raw topics are read when they are logged with at least
:data:`~accelcal.recording.MIN_ROWS` samples (PX4's default logger profile samples
them at about 1 Hz, which is too few); otherwise ``sensor_combined`` is read and the
notes say that it is calibrated already.  ``topic`` forces one of them; several raw
instances (several IMUs) are listed in one line and chosen with ``instance``.

Time: ``time_source='header'`` (default) is ``timestamp_sample``, when the sensor
sampled; ``'log'`` is ``timestamp``, when the sample was published.  ``sensor_combined``
has one stamp, its gyro's (the accelerometer's offset ``accelerometer_timestamp_relative``
is noted when it is not zero).  The gyro instance's samples are interpolated to the
accelerometer's sample times when the two differ, and then shifted by their time offset
measured from the motions (:mod:`accelcal.formats.sync`; stated, applied when beyond its
uncertainty); the recorded microseconds are kept as the time column
(``timestamp_sample_us`` or ``timestamp_us``).
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np

from ..errors import LogFormatError, TopicError
from ..recording import MIN_ROWS
from .logs import (Progress, check_time_source, choose, clock_note, make_recording, microseconds, require_extra,
                   stamps_to_time, topic_origin)
from .px4_mag import MAG_TOPICS, add_magnetometer
from .sync import estimate_offset, shift_gyro

ULOG_MAGIC = b"ULog\x01\x12\x35"
TOPICS = ("sensor_accel", "sensor_gyro", "sensor_combined")
#: What the recording's ``precalibrated`` says of sensor_combined, and of the x, y, z of PX4 before 1.10.
COMBINED_CALIBRATED = "PX4 sensor_combined (already calibrated by the autopilot: CAL_ACC*/CAL_GYRO* applied)"
OLD_ACCEL_CALIBRATED = "PX4 sensor_accel x, y, z (calibrated by the autopilot in this PX4 version)"
#: File size above which the read announces itself (pyulog parses in one call).
_ANNOUNCE_BYTES = 64 * 2**20


def sniff(path, head: bytes) -> bool:
    """True for a ULog file (its 7-byte magic)."""
    return head.startswith(ULOG_MAGIC)


def read(path, *, topic: str | None = None, time_source: str = "header", instance: int | None = None,
         progress=None, mag_instance: int | None = None):
    """Read the accelerometer, gyroscope and magnetometer of a PX4 ULog file.

    Parameters
    ----------
    path : path-like
        The ``.ulg`` file.
    topic : {'sensor_accel', 'sensor_combined'}, optional
        Default: the raw ``sensor_accel`` (with ``sensor_gyro``) when logged with enough
        samples, else ``sensor_combined`` (module docstring).
    time_source : {'header', 'log'}
        ``timestamp_sample`` (default) or ``timestamp``.
    instance : int, optional
        The raw sensor instance (``multi_id``); needed when several are logged.
    progress : None, False or callable
        See :class:`accelcal.formats.logs.Progress`.
    mag_instance : int, optional
        The ``sensor_mag`` instance; needed when several are logged (:mod:`.px4_mag`).

    Returns
    -------
    Recording
        ``acc`` [m/s²], ``gyro`` [rad/s] (None when not logged), ``temp`` [°C] from the
        raw accelerometer where logged, ``mag`` [µT] from ``sensor_mag`` where logged.
    """
    check_time_source(time_source)
    path = Path(path)
    require_extra("px4", path)
    import pyulog

    ulog = _parse(pyulog, path, progress)
    data = {(d.name, d.multi_id): d for d in ulog.data_list}
    for d in data.values():
        _require(path, d, ("timestamp",))
    notes = []
    topic, inst = _choose(path, data, topic, instance, notes)
    if topic == "sensor_combined":
        rec = _combined(path, data[("sensor_combined", 0)], time_source, notes)
    else:
        rec = _raw(path, data, inst, ulog, time_source, notes)
    return add_magnetometer(rec, path, data, ulog.initial_parameters, time_source, mag_instance)


def _choose(path, data: dict, topic: str | None, instance: int | None, notes: list) -> tuple[str, int | None]:
    """The IMU topic (the raw sensor_accel when logged with enough samples) and its instance."""
    raw = {i: len(d.data["timestamp"]) for (name, i), d in data.items() if name == "sensor_accel"}
    usable = {i: n for i, n in raw.items() if n >= MIN_ROWS}
    everything = {name: f"{len(d.data['timestamp'])} samples" for (name, _), d in data.items()}
    if topic is None:
        topic = "sensor_accel" if usable else "sensor_combined"
    if topic not in ("sensor_accel", "sensor_combined"):
        raise TopicError(f"{path}: --topic {topic}: a PX4 log's IMU is read from sensor_accel (raw, with sensor_gyro) "
                         "or sensor_combined (calibrated by the autopilot)")
    if topic == "sensor_combined":
        if ("sensor_combined", 0) not in data:
            raise TopicError(f"{path}: no sensor_combined and no raw sensor_accel with at least {MIN_ROWS} samples in "
                             f"this log (topics: {', '.join(sorted(everything)) or 'none'})")
        if raw and not usable:
            notes.append(f"sensor_accel is logged with only {max(raw.values())} samples (the logger's profile samples "
                         "it slowly): reading sensor_combined instead")
        if instance not in (None, 0):
            raise TopicError(f"{path}: sensor_combined has one instance; --instance chooses a raw sensor_accel")
        return topic, None
    if not usable:
        raise TopicError(f"{path}: no sensor_accel with at least {MIN_ROWS} samples (logged: "
                         + (", ".join(f"instance {i}: {n}" for i, n in raw.items()) or "none")
                         + "); read sensor_combined (--topic sensor_combined), calibrated by the autopilot")
    rates = {i: _rate(data[("sensor_accel", i)]) for i in usable}
    cands = {str(i): f"{n} samples at {rates[i]:.4g} Hz" for i, n in usable.items()}
    return topic, int(choose(path, cands, None if instance is None else str(instance), cands,
                             kind="sensor_accel instance", option="--instance"))


def _parse(pyulog, path: Path, progress):
    if not path.is_file():
        raise LogFormatError(f"{path}: no such file")
    size = path.stat().st_size
    if size > _ANNOUNCE_BYTES and progress is not False:
        Progress(f"{path} ({size / 2**20:.0f} MB, pyulog)", None, progress, unit="bytes")(0)
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter):  # pyulog prints its warnings; they become our one line
            ulog = pyulog.ULog(str(path), message_name_filter_list=[*TOPICS, *MAG_TOPICS])
    except Exception as e:  # pyulog raises ULogException, struct.error, IndexError... on damaged files
        why = " ".join(str(e).split())[:120] or type(e).__name__
        raise LogFormatError(f"{path}: not a readable ULog file ({why}); the log is damaged or truncated in its "
                             "header: download it from the vehicle again") from None
    if ulog.file_corruption:
        said = " ".join(chatter.getvalue().split())[:100]
        raise LogFormatError(f"{path}: the ULog is corrupted (pyulog skipped damaged bytes{': ' + said if said else ''}"
                             "); its samples cannot be trusted: download the log from the vehicle again")
    return ulog


def _require(path, d, fields) -> None:
    """The fields a topic must have; a damaged definition (or an unknown PX4 version) is one line."""
    missing = [f for f in fields if f not in d.data]
    if missing:
        raise LogFormatError(f"{path}: {d.name} instance {d.multi_id} lacks the field(s) {', '.join(missing)} (a "
                             f"damaged ULog, or a PX4 version this reader does not know; it has "
                             f"{', '.join(list(d.data)[:8])})")


def _rate(d) -> float:
    ts = d.data.get("timestamp_sample", d.data["timestamp"])
    step = np.median(np.diff(ts.astype(np.int64))) if len(ts) > 1 else 0
    return 1e6 / step if step > 0 else float("nan")


def _stamps(path, d, time_source: str, topic: str, notes: list):
    """(sensor stamps, log stamps) in µs, int64; the chosen one first in the notes."""
    label = f"{d.name} instance {d.multi_id}"
    log = microseconds(d.data["timestamp"], path, f"{label}: timestamp")
    sample = microseconds(d.data["timestamp_sample"], path, f"{label}: timestamp_sample") \
        if "timestamp_sample" in d.data else None
    if sample is None and time_source == "header":
        notes.append(f"{topic} has no timestamp_sample in this PX4 version: its publication time is used")
    return (sample if sample is not None else log), log


def _raw(path, data, inst: int, ulog, time_source: str, notes: list):
    acc_d = data[("sensor_accel", inst)]
    _require(path, acc_d, ("x", "y", "z"))
    sample, log = _stamps(path, acc_d, time_source, "sensor_accel", notes)
    chosen = sample if time_source == "header" else log
    name = "timestamp_sample_us" if time_source == "header" and "timestamp_sample" in acc_d.data else "timestamp_us"
    t = stamps_to_time(chosen * 1000)
    acc = np.column_stack([acc_d.data[k].astype(np.float64) for k in ("x", "y", "z")])
    temp = acc_d.data["temperature"].astype(np.float64) if "temperature" in acc_d.data else None
    old = "x_raw" in acc_d.data
    notes.insert(0, f"PX4 ULog, sensor_accel instance {inst} (device id {_device(acc_d)}): {len(acc)} samples at "
                    f"{_rate(acc_d):.4g} Hz, m/s^2" + (
                        "; in this PX4 version x, y, z are already calibrated (x_raw holds the counts)" if old else
                        ", the driver's output before the autopilot's calibration"))
    gyro = _gyro(path, data, inst, time_source, chosen, notes)
    if gyro is not None and any("interpolated to the accelerometer" in n for n in notes) and np.all(
            np.isfinite(acc)) and np.all(np.diff(t) > 0):  # else checked_recording refuses the accelerometer's
        gyro = _aligned(path, t, acc, gyro, notes)
    note = clock_note(sample * 1000, log * 1000, "sample times", "publication times")
    if note and "timestamp_sample" in acc_d.data:
        notes.append(f"warning: {note}")
    cal = _calibration_parameters(ulog, _device(acc_d))
    if cal:
        notes.append(f"the autopilot's own calibration of accelerometer {inst} is in the log's parameters: {cal}")
    device = _device(acc_d)
    origin = topic_origin(f"sensor_accel instance {inst}", time=name[:-3], acc=("x", "y", "z"),
                          gyro=tuple(f"sensor_gyro {a}" for a in "xyz"),
                          time_fix="the log's stamps are not in order (a damaged log?)")
    return make_recording(path, t=t, acc=acc, gyro=gyro, notes=notes, time_name=name, time_values=chosen, temp=temp,
                          device_id=None if device == "?" else device,
                          precalibrated=OLD_ACCEL_CALIBRATED if old else None, origin=origin)


def _gyro(path, data, inst: int, time_source: str, at_us: np.ndarray, notes: list):
    d = data.get(("sensor_gyro", inst))
    if d is None or len(d.data["timestamp"]) < MIN_ROWS:
        notes.append(f"no sensor_gyro instance {inst} with at least {MIN_ROWS} samples: the recording has no gyro")
        return None
    _require(path, d, ("x", "y", "z"))
    sample, log = _stamps(path, d, time_source, "sensor_gyro", [])
    ts = sample if time_source == "header" else log
    w = np.column_stack([d.data[k].astype(np.float64) for k in ("x", "y", "z")])
    # a topic of its own, resampled to the accelerometer's times: checked here, where its messages can be named
    # (checked_recording sees the resampled values only)
    bad = ~np.all(np.isfinite(w), axis=1)
    if bad.any():
        raise LogFormatError(f"{path}: topic sensor_gyro: non-finite angular rate in message "
                             f"{int(np.flatnonzero(bad)[0])} ({int(bad.sum())} such messages)")
    if np.any(np.diff(ts) <= 0):
        raise LogFormatError(f"{path}: sensor_gyro instance {inst}: time stamps not in order (a damaged log?)")
    if len(ts) == len(at_us) and np.array_equal(ts, at_us):
        notes.append(f"sensor_gyro instance {inst} (device id {_device(d)}), rad/s, sampled with the accelerometer")
        return w
    outside = int(np.sum((at_us < ts[0]) | (at_us > ts[-1])))
    notes.append(f"sensor_gyro instance {inst} (device id {_device(d)}, {len(ts)} samples at {_rate(d):.4g} Hz), "
                 "rad/s, linearly interpolated to the accelerometer's sample times"
                 + (f" ({outside} samples outside the gyro's span hold its first/last value)" if outside else ""))
    x = (ts - ts[0]).astype(np.float64)
    xi = (at_us - ts[0]).astype(np.float64)
    return np.column_stack([np.interp(xi, x, w[:, k]) for k in range(3)])


def _aligned(path, t, acc, gyro, notes: list):
    """The gyro of its own topic shifted by its time offset against the accelerometer, measured from the
    motions (:mod:`.sync`; a flight's linear accelerations may leave it unmeasured: said so)."""
    offset = estimate_offset(t, acc, gyro, source=str(path))
    if offset is None:
        notes.append("sensor_gyro - sensor_accel time offset not measured: no motion both of them see")
        return gyro
    notes.append(offset.note("sensor_gyro"))
    return shift_gyro(t, gyro, offset.tau) if offset.applied else gyro


def _combined(path, d, time_source: str, notes: list):
    _require(path, d, [f"{k}[{i}]" for k in ("accelerometer_m_s2", "gyro_rad") for i in range(3)])
    ts = microseconds(d.data["timestamp"], path, "sensor_combined: timestamp")
    t = stamps_to_time(ts * 1000)
    acc = np.column_stack([d.data[f"accelerometer_m_s2[{k}]"].astype(np.float64) for k in range(3)])
    gyro = np.column_stack([d.data[f"gyro_rad[{k}]"].astype(np.float64) for k in range(3)])
    notes.insert(0, f"PX4 ULog, sensor_combined: {len(acc)} samples at {_rate(d):.4g} Hz; already calibrated by the "
                    "autopilot (CAL_ACC*/CAL_GYRO* applied) and averaged over its integration interval: a calibration "
                    "fitted to it corrects what the autopilot's calibration left")
    rel = d.data.get("accelerometer_timestamp_relative")
    if rel is not None and np.any((rel != 0) & (rel != 0x7FFFFFFF)):
        notes.append(f"the accelerometer is stamped {np.median(rel):.0f} us (median) after the gyro; t is the gyro's")
    if time_source == "log":
        notes.append("sensor_combined has one time stamp (timestamp): used for --time-source log too")
    origin = topic_origin("sensor_combined", time="timestamp", time_fix="the log's stamps are not in order",
                          acc=tuple(f"accelerometer_m_s2[{k}]" for k in range(3)),
                          gyro=tuple(f"gyro_rad[{k}]" for k in range(3)))
    return make_recording(path, t=t, acc=acc, gyro=gyro, notes=notes, time_name="timestamp_us", time_values=ts,
                          precalibrated=COMBINED_CALIBRATED, origin=origin)


def _device(d) -> str:
    ids = d.data.get("device_id")
    return "?" if ids is None or not len(ids) else str(int(ids[0]))


def _calibration_parameters(ulog, device: str) -> str:
    """The CAL_ACC<n>_* offsets and scales of the slot whose CAL_ACC<n>_ID is this device, as text."""
    p = ulog.initial_parameters
    slot = next((n for n in range(8) if str(p.get(f"CAL_ACC{n}_ID", "")) == device), None)
    if slot is None:
        return ""
    keys = [f"CAL_ACC{slot}_{a}{k}" for k in ("OFF", "SCALE") for a in "XYZ"]
    return ", ".join(f"{k}={p[k]:.6g}" for k in keys if k in p)


__all__ = ["TOPICS", "read", "sniff"]
