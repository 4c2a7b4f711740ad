"""Reading the files people have: one entry point, :func:`read`, for every format.

Formats (``format=``; ``'auto'`` detects them from the first lines):

``csv``
    Any delimited text table (:func:`read_table`): comma, semicolon, tab, ``|`` or
    whitespace, decimal point or decimal comma, ``#``/``%``/``//`` comment lines,
    metadata lines above the header, gzip-compressed or not.  Columns are found by their
    usual names (``t``, ``time``, ``timestamp``, ``acc_x``, ``accX``, ``AX``, ``Accel. X``,
    ``linear_acceleration.x`` ...; :data:`ALIASES`) or given with ``columns=``.  A
    headerless table of 4 numbers per row is IMU-TK's layout (t, x, y, z).
``imutk``
    IMU-TK ASCII (``xsens_acc.mat``; :func:`accelcal.formats.imutk.read_imutk_ascii`).
``mpu6050``
    tomisuarez2/ImuCalibration's logger (``Fs,100`` lines, then ``ax,ay,az,gx,gy,gz``).
``imucal``
    an imucal session (``n_samples, gyr_*, acc_*``; the rate is not in the file:
    ``rate=`` or imucal's 204.8 Hz).
``imucal-annotated``
    imucal's annotated session (a ``part`` column; its static parts become known
    static intervals).
``block-log``
    a serial-monitor log of poses as blocks (FastAhrs FXOS8700; every block is a known
    static interval).

Units.  Acceleration comes out in m/s² or raw counts (:mod:`accelcal.units`): a unit in
the header (``acc_x [g]``, ``ax_mg``), ``unit=`` (which wins), or, failing both, the
magnitude of the data (median ``|a|`` near 1 → g, near 9.8 → m/s², ...), stated in
:attr:`~accelcal.recording.Recording.notes`.  Time comes out in seconds from the first
sample: its unit from ``time_unit=``, the header (``time_ms``), or the values (epoch
magnitudes; integer steps → the unit that makes the rate nearest 100 Hz), ISO 8601
date-times parsed, or ``rate=`` (time from the sample index).  Every guess is a note.

Every refusal is a :class:`~accelcal.errors.RecordingError` with one line that names the
file, the cause and the option that fixes it.
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..recording import Recording, intervals_from_labels
from ..units import acceleration_unit, time_unit
from .block_log import read_block_log
from .imucal import read_imucal_session
from .imucal_annotated import read_imucal_annotated
from .imutk import read_imutk_ascii
from .inference import convert_acc, with_inferred_unit
from .intervals import read_intervals
from .mpu6050 import read_mpu6050_csv
from .table import read_table
from .text import is_comment, load_text

FORMATS = ("auto", "csv", "imutk", "mpu6050", "imucal", "imucal-annotated", "block-log")


def read(path, *, format: str = "auto", columns=None, unit: str | None = None, time_unit: str | None = None,
         rate: float | None = None, intervals=None) -> Recording:
    """Read an accelerometer recording in any supported format.

    Parameters
    ----------
    path : str or Path
        The file (gzip-compressed or not).
    format : str
        One of :data:`FORMATS`; ``'auto'`` detects it (:func:`detect_format`).
    columns : str or dict, optional
        Which column is which: ``'t=time,ax=AccX,ay=AccY,az=AccZ[,temp=T]'`` or a dict;
        names or 1-based column numbers (:func:`parse_columns`).
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
        A file of known static intervals (:func:`read_intervals`).

    Returns
    -------
    Recording
        In m/s² or counts (``unit`` set), time in seconds, notes saying what was assumed.
    """
    path = Path(path)
    if format not in FORMATS:
        raise RecordingError(f"unknown format {format!r}; known: {', '.join(FORMATS)}")
    if unit is not None and acceleration_unit(unit) is None:
        raise RecordingError(f"unknown acceleration unit {unit!r}; use one of g, mg, m/s2, counts")
    if time_unit is not None and globals()["time_unit"](time_unit) is None:
        raise RecordingError(f"unknown time unit {time_unit!r}; use one of s, ms, us, ns")
    if rate is not None and not (np.isfinite(rate) and rate > 0):
        raise RecordingError(f"--rate must be a positive number of Hz, got {rate!r}")
    text, notes = load_text(path)
    fmt = detect_format(text) if format == "auto" else format
    if format == "auto" and fmt != "csv":
        notes.append(f"format: {fmt} (detected; pass --format to choose another)")
    if fmt == "csv":
        rec = read_table(path, text=text, columns=columns, unit=unit, time_unit=time_unit, rate=rate)
    else:
        if columns is not None:
            raise RecordingError(f"{path}: --columns applies to the csv format, not to {fmt} "
                                 "(pass --format csv to read it as a plain table)")
        rec = _read_known_format(path, fmt, text, rate)
        rec = _with_unit(rec, unit, path)
        if time_unit is not None:
            notes.append(f"--time-unit ignored: the {fmt} format defines its time")
    rec = replace(rec, notes=tuple(notes) + rec.notes)
    if intervals is not None:
        rec = read_intervals(intervals, rec)
    return rec


def _read_known_format(path: Path, fmt: str, text: str, rate):
    kw = {} if rate is None else {"rate_hz": rate}
    if fmt == "imutk":
        rec = read_imutk_ascii(path, text=text)
    elif fmt == "mpu6050":
        rec = read_mpu6050_csv(path, text=text)
    elif fmt == "imucal":
        rec = read_imucal_session(path, text=text, **kw)
    elif fmt == "imucal-annotated":
        rec, parts = read_imucal_annotated(path, text=text, **kw)
        static = np.array([p if not p.endswith("_rot") else "" for p in parts])
        iv, labels = intervals_from_labels(static)
        rec = replace(rec, intervals=iv, labels=labels,
                      notes=rec.notes + ("imucal annotated session: its static parts (not *_rot) are the known "
                                         "static intervals",))
    else:
        rec = read_block_log(path, text=text)
    if rate is not None and fmt in ("imutk", "mpu6050", "block-log"):
        rec = replace(rec, t=np.arange(rec.n) / rate, notes=rec.notes + (f"t = sample index / {rate:g} Hz (--rate)",))
    return rec


def _with_unit(rec: Recording, unit: str | None, path) -> Recording:
    """Apply ``unit=`` to a format reader's recording (converting g, mg to m/s²)."""
    if unit is None:
        return rec if rec.unit is not None else with_inferred_unit(rec)
    u = acceleration_unit(unit)
    if rec.unit is not None and rec.unit != ("counts" if u == "counts" else "m/s^2"):
        raise RecordingError(f"{path}: --unit {unit} contradicts the format, whose values are in {rec.unit}")
    acc, note = convert_acc(rec.acc, u, "--unit")
    return replace(rec, acc=acc, unit="counts" if u == "counts" else "m/s^2", notes=rec.notes + (note,))


def detect_format(text: str) -> str:
    """The format of a recording from its first lines (:data:`FORMATS` without ``'auto'``)."""
    head = text[:8192]
    if re.search(r">>>\s*Gathering data for", head, re.IGNORECASE):
        return "block-log"
    lines = [ln.strip() for ln in head.splitlines() if ln.strip() and not is_comment(ln)]
    if not lines:
        return "csv"
    if lines[0].replace(" ", "").lower().startswith("fs,") and len(lines) > 4 \
            and lines[4].replace(" ", "").lower().startswith("ax,ay,az,gx,gy,gz"):
        return "mpu6050"
    header = {c.strip().lower() for c in lines[0].split(",")}
    if {"n_samples", "acc_x", "acc_y", "acc_z", "gyr_x"} <= header:
        return "imucal"
    if {"part", "samples", "acc_x", "acc_y", "acc_z"} <= header:
        return "imucal-annotated"
    return "csv"
