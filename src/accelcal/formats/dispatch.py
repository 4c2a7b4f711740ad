"""Reading the files people have: one entry point, :func:`read`, for every format.

Two strictnesses, chosen by the caller:

* ``strict=False`` (the default, ``accelcal calibrate``): the file as people write it.
  The format is detected (:data:`~accelcal.formats.registry.FORMATS`, in its order) or
  named; a table's delimiter, header, columns, units and time are found
  (:mod:`accelcal.formats.table`, :mod:`accelcal.formats.inference`); gzip and
  Windows-1252 are undone.  Every guess is stated in
  :attr:`~accelcal.recording.Recording.notes`.
* ``strict=True`` (the workflow, reading back what it wrote): the canonical CSV
  (:mod:`accelcal.formats.canonical`) exactly as :func:`write_recording` writes it,
  nothing guessed, no option.

Every refusal is a :class:`~accelcal.errors.RecordingError` with one line that names the
file, the cause and the option that fixes it.

This module imports only the standard library; a format's reader is imported when a file
of that format is read.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from ..errors import RecordingError
from ..units import acceleration_unit, angular_rate_unit
from ..units import time_unit as time_unit_name
from .registry import (BINARY_HEAD_BYTES, FALLBACK, FORMATS, KEEP_OPTIONS, LOG_OPTIONS, MAG_LOG_OPTIONS, OPTION_FLAGS,
                       TEXT_HEAD_CHARS, TIME_SOURCES,
                       Format, format_named)
from .text import load_text

#: Values of ``clock=`` (:data:`accelcal.formats.clock.CLOCK_MODES`; repeated here: this module
#: imports no numerical library).
CLOCK_MODES = ("auto", "stamps")


def read(path, *, strict: bool = False, format: str = "auto", columns=None, unit: str | None = None,
         time_unit: str | None = None, rate: float | None = None, intervals=None, gyro=None,
         gyro_unit: str | None = None, topic: str | None = None, instance: int | None = None,
         time_source: str | None = None, clock: str | None = None, variable: str | None = None,
         mag_unit: str | None = None, mag_topic: str | None = None, mag_instance: int | None = None,
         time_column: bool = True):
    """Read an accelerometer recording (and its gyroscope, when the file or ``gyro`` has one).

    Parameters
    ----------
    path : str or Path
        The file (gzip-compressed or not, for text formats).
    strict : bool
        False: detect the format and guess what the file does not say (stated in the
        notes).  True: the canonical CSV only (header ``t,ax,ay,az[,temp][,pose]``, as
        :func:`write_recording` writes it), nothing guessed; no other option may be given.
    format : str
        ``'auto'`` (detect it) or a name of :data:`~accelcal.formats.registry.FORMATS`.
    columns : str or dict, optional
        Which column is which: ``'t=time,ax=AccX,ay=AccY,az=AccZ[,temp=T]'`` or a dict;
        names or 1-based column numbers (:func:`accelcal.formats.columns.parse_columns`).
    unit : str, optional
        Unit of the acceleration values (``g``, ``mg``, ``m/s2``, ``counts``); overrides
        the header.
    time_unit : str, optional
        Unit of the time column (``s``, ``ms``, ``us``, ``ns``); overrides the header and
        the inference.
    rate : float, optional
        Sampling rate [Hz]: time from the sample index (for files without time, or whose
        time column is unusable).
    intervals : str or Path, optional
        A file of known static intervals (:func:`accelcal.formats.intervals.read_intervals`).
    gyro : str or Path, optional
        The gyroscope's own file, sampled with the accelerometer (IMU-TK's ``t x y z``
        layout or a table naming gx, gy, gz: :mod:`accelcal.formats.gyro_file`).
    gyro_unit : str, optional
        Unit of the gyro values (``rad/s``, ``deg/s``, ``counts``) of a table or of the
        ``gyro`` file; overrides the header.  Formats that define their gyro's unit ignore
        it (with a note).
    mag_unit : str, optional
        Unit of the magnetometer columns of a table (``uT``, ``T``, ``gauss``, ``mG``,
        ``counts``...); overrides the header.  ``mag_topic`` / ``mag_instance``: a log's (:mod:`.mag_logs`).
    topic : str, optional
        Logs: the IMU topic (ROS), ``sensor_accel`` or ``sensor_combined`` (PX4), the IMU
        message (DataFlash); default the only one (several: a one-line error listing them).
    instance : int, optional
        Logs: the sensor instance (PX4 ``multi_id``, DataFlash ``I``) when several are logged.
    time_source : {'header', 'log'}, optional
        Logs: the sensor's own stamps (``'header'``, the default) or the time the log
        recorded each message.
    variable : str, optional
        Files of named variables (MATLAB ``.mat``, R data): the variable that is the
        recording; several, comma-separated, are runs of one session recorded apart
        (:attr:`~accelcal.recording.Recording.runs`).  Default the only usable one.

    clock : {'auto', 'stamps'}, optional
        Tables: time the samples by the sensor's clock, fitted to the time stamps against
        the sample counter or the row index (``'auto'``, the default: rate, jitter, drift and
        gaps in the notes, :mod:`accelcal.formats.clock`), or by the stamps as they are.
    time_column : bool
        Keep the time column as written (:attr:`~accelcal.recording.Recording.time_column`,
        what ``accelcal apply`` writes back; default).  False: not kept, and a table's reader
        lets the file's text go as soon as its time is read.

    Returns
    -------
    Recording
        In m/s² or counts (``unit`` set; strict: as in the file, ``unit`` None), time in
        seconds, notes saying what was assumed.
    """
    from ..recording import checked_recording  # numpy: not loaded for the CLI's help (formats list)

    path = Path(path)
    options = {"columns": columns, "unit": unit, "time_unit": time_unit, "rate": rate, "gyro_unit": gyro_unit,
               "mag_unit": mag_unit, "topic": topic, "instance": instance, "time_source": time_source, "clock": clock,
               "variable": variable, "mag_topic": mag_topic, "mag_instance": mag_instance}
    if strict:
        return checked_recording(_without_time_column(
            _read_strict(path, format, {**options, "intervals": intervals, "gyro": gyro}), time_column))
    fmt = None if format == "auto" else format_named(format)
    _check_options(unit, time_unit, rate, gyro_unit, time_source)
    if clock is not None and clock not in CLOCK_MODES:
        raise RecordingError(f"--clock must be {' or '.join(CLOCK_MODES)}, got {clock!r}")
    fmt, text, notes = _format_and_text(path, fmt)
    held = [text]  # handed over to the reader, not kept here: it may let the text go early
    del text
    rec = _read_format(path, fmt, held, {**options, "time_column": None if time_column else False}, notes)
    rec = replace(_without_time_column(rec, time_column), notes=tuple(notes) + rec.notes)
    return checked_recording(_with_side_files(rec, intervals, gyro, gyro_unit, time_unit, clock))


def _without_time_column(rec, time_column: bool):
    """``rec`` without its time column as written unless ``time_column``."""
    return rec if time_column or rec.time_column is None else replace(rec, time_column=None)


def _format_and_text(path: Path, fmt: Format | None) -> tuple[Format, str | None, list[str]]:
    """The format (``fmt``, or detected: binary signatures first, then the text), the file's
    text for a text format, and the notes saying what was detected or undone."""
    notes: list[str] = []
    text = None
    if fmt is None:
        fmt = _sniff_binary(path)
        if fmt is not None:
            notes.append(_detected(fmt))
    if fmt is None or fmt.text:
        text, notes = load_text(path)
        if fmt is None:
            fmt = _sniff_text(path, text)
            if fmt.name != FALLBACK:
                notes.append(_detected(fmt))
    return fmt, text, notes


def _with_side_files(rec, intervals, gyro, gyro_unit, time_unit, clock):
    """``rec`` with the known static intervals and the gyroscope of their own files, if given."""
    if intervals is not None:
        from .intervals import read_intervals

        rec = read_intervals(intervals, rec)
    if gyro is not None:
        from .gyro_file import attach_gyro

        rec = attach_gyro(rec, gyro, gyro_unit=gyro_unit, time_unit=time_unit, clock=clock or "auto")
    return rec


def write_recording(path, rec, *, format: str = FALLBACK) -> None:
    """Write ``rec`` in ``format`` (the canonical CSV by default), atomically.

    ``read(path, strict=True)`` reads it back exactly.
    """
    fmt = format_named(format)
    writer = fmt.load_writer()
    if writer is None:
        raise RecordingError(f"no writer for the {fmt.name} format; "
                             f"formats with one: {', '.join(f.name for f in FORMATS.values() if f.writer)}")
    writer(path, rec)


def detect_format(path) -> str:
    """The name of the format :func:`read` would detect for ``path`` (``format='auto'``)."""
    path = Path(path)
    fmt = _sniff_binary(path)
    if fmt is None:
        text, _ = load_text(path)
        fmt = _sniff_text(path, text)
    return fmt.name


def _detected(fmt: Format) -> str:
    return f"format: {fmt.name} (detected; pass --format to choose another)"


def _check_options(unit, time_unit, rate, gyro_unit, time_source) -> None:
    if unit is not None and acceleration_unit(unit) is None:
        raise RecordingError(f"unknown acceleration unit {unit!r}; use one of g, mg, m/s2, counts")
    if gyro_unit is not None and angular_rate_unit(gyro_unit) is None:
        raise RecordingError(f"unknown gyro unit {gyro_unit!r}; use one of rad/s, deg/s, counts")
    if time_unit is not None and time_unit_name(time_unit) is None:
        raise RecordingError(f"unknown time unit {time_unit!r}; use one of s, ms, us, ns")
    if rate is not None and not (math.isfinite(rate) and rate > 0):
        raise RecordingError(f"--rate must be a positive number of Hz, got {rate!r}")
    if time_source not in (None, *TIME_SOURCES):
        raise RecordingError(f"--time-source must be {' or '.join(TIME_SOURCES)}, got {time_source!r}")


def _read_strict(path: Path, format: str, options: dict):
    fmt = format_named(FALLBACK if format == "auto" else format)
    given = [name for name, value in options.items() if value is not None]
    if given:
        raise RecordingError(f"{path}: strict reading takes the file as it is; {', '.join(given)} "
                             "apply to strict=False")
    reader = fmt.load_strict_reader()
    if reader is None:
        raise RecordingError(f"the {fmt.name} format has no strict reader; strict=True reads "
                             f"{', '.join(f.name for f in FORMATS.values() if f.strict_reader)}")
    fmt.check_extra(path)
    return reader(path)


def _sniff_binary(path: Path) -> Format | None:
    """The first binary format that recognises ``path`` from its first bytes, or None."""
    binary = [f for f in FORMATS.values() if not f.text and f.sniff is not None]
    if not binary:
        return None
    head = b""
    if path.is_file():
        with open(path, "rb") as fh:
            head = fh.read(BINARY_HEAD_BYTES)
    return next((f for f in binary if f.load_sniff()(path, head)), None)


def _sniff_text(path: Path, text: str) -> Format:
    """The first text format that recognises the text's head, else the fallback (a table)."""
    head = text[:TEXT_HEAD_CHARS]
    found = (f for f in FORMATS.values() if f.text and f.sniff is not None and f.load_sniff()(path, head))
    return next(found, FORMATS[FALLBACK])


def _read_format(path: Path, fmt: Format, held: list, options: dict, notes: list[str]):
    """Run ``fmt``'s reader with the options it takes; apply the others (see
    :data:`~accelcal.formats.registry.READING_OPTIONS`); notes on the file go to ``notes``.
    ``held``: ``[the text]`` (None for a binary format), emptied here or by the reader: the
    reader holds the only reference to the text, so that it may let it go before it returns."""
    for option in ("columns", "variable", *LOG_OPTIONS, *MAG_LOG_OPTIONS):
        if options[option] is not None and option not in fmt.options:
            takers = [f.name for f in FORMATS.values() if option in f.options]
            fix = {"columns": f"pass --format {FALLBACK} to read it as a plain table",
                   "variable": "a file of one table has no variables to choose from"}.get(
                option, "a file of one sensor and one clock has no choice to make")
            raise RecordingError(f"{path}: {OPTION_FLAGS[option]} applies to the {_either(takers)} format"
                                 f"{'s' if len(takers) > 1 else ''}, not to {fmt.name} ({fix})")
    reader = fmt.load_reader(path)
    own = {k: v for k, v in options.items() if k in fmt.options and v is not None}
    if fmt.text:  # a reader that may let the text go takes it handed over (a ** call's dict would hold it)
        rec = reader(path, text=held if KEEP_OPTIONS[0] in fmt.options else held.pop(), **own)
    else:
        rec = reader(path, **own)
    rate = options["rate"]
    if rate is not None and "rate" not in fmt.options:
        import numpy as np

        rec = replace(rec, t=np.arange(rec.n) / rate, notes=rec.notes + (f"t = sample index / {rate:g} Hz (--rate)",))
    if "unit" not in fmt.options:
        rec = _with_unit(rec, options["unit"], path)
    if options["time_unit"] is not None and "time_unit" not in fmt.options:
        notes.append(f"--time-unit ignored: the {fmt.name} format defines its time")
    if options["clock"] is not None and "clock" not in fmt.options:
        notes.append(f"--clock ignored: the {fmt.name} format times its samples itself")
    if options["gyro_unit"] is not None and "gyro_unit" not in fmt.options and rec.gyro is not None:
        from .units_evidence import override_gyro_unit

        rec, note = override_gyro_unit(rec, options["gyro_unit"], fmt.name)
        notes.append(note)
    if options["mag_unit"] is not None and "mag_unit" not in fmt.options and rec.mag is not None:
        notes.append(f"--mag-unit ignored: the {fmt.name} format defines its magnetometer's unit")
    return rec


def _either(names: list[str]) -> str:
    """``a``, ``a or b``, ``a, b or c``."""
    return " or ".join(names) if len(names) < 3 else f"{', '.join(names[:-1])} or {names[-1]}"


def _with_unit(rec, unit: str | None, path):
    """Apply ``unit=`` to a format reader's recording (converting g, mg to m/s²)."""
    from .inference import convert_acc, with_inferred_unit

    if rec.acc is None:  # a gyro-only recording
        if unit is not None:
            raise RecordingError(f"{path}: --unit {unit} given, but the recording has no accelerometer (gyro only)")
        return rec
    if unit is None:
        return rec if rec.unit is not None else with_inferred_unit(rec)
    u = acceleration_unit(unit)
    if rec.unit is not None and rec.unit != ("counts" if u == "counts" else "m/s^2"):
        raise RecordingError(f"{path}: --unit {unit} contradicts the format, whose values are in {rec.unit}")
    acc, note = convert_acc(rec.acc, u, "--unit")
    return replace(rec, acc=acc, unit="counts" if u == "counts" else "m/s^2", notes=rec.notes + (note,))


__all__ = ["detect_format", "read", "write_recording"]
