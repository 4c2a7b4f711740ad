"""A gyroscope recorded in a file of its own (IMU-TK's ``xsens_gyro.mat``, ``gyro_data.txt``),
joined to the accelerometer's recording (``read(..., gyro=FILE)``, ``--gyro FILE``).

The file is a table like the accelerometer's: headerless ``t x y z`` (IMU-TK's ASCII
layout) or ``x y z``, or a header naming the gyro columns (``t,gx,gy,gz``, ``time,x,y,z``
...).  Its unit comes from the header, ``gyro_unit=`` or the values
(:func:`accelcal.formats.inference.resolve_gyro_unit`).  The gyro must be sampled with
the accelerometer: the same number of rows and, when the file has a time column, the same
times within half a sample (:func:`accelcal.gyro.rests.check_time_base`); a file that
does not match is refused in one line, never resampled behind the user's back.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..gyro.errors import GyroInputError
from ..gyro.rests import check_time_base, sample_interval
from ..recording import Recording, checked_recording
from .clock import clocked_time
from .inference import resolve_gyro_unit, time_seconds
from .parsing import parse_numbers
from .sync import estimate_offset, shift_gyro, sphere_centre
from .columns import ACC_ROLES, GYRO_ROLES, map_columns
from .table import _split_table, numeric_columns, table_origin
from .text import load_text


def read_gyro_table(path, *, gyro_unit: str | None = None, time_unit: str | None = None, clock: str = "auto"):
    """``(t or None, gyro (n, 3) in rad/s or counts, unit, notes)`` of a gyro file (module docstring)."""
    path = Path(path)
    text, notes = load_text(path)
    tab = _split_table(text, path)
    roles, units = map_columns(tab.names, tab.k, {}, path, required=())
    triad = GYRO_ROLES if all(r in roles for r in GYRO_ROLES) else ACC_ROLES  # named gx.. or plain x, y, z
    if not all(r in roles for r in triad):
        found = ", ".join(n.strip() for n in tab.names)[:150] if tab.names is not None else f"{tab.k} columns"
        raise RecordingError(f"{path}: no gyro columns (found: {found}); a gyro file is t x y z (IMU-TK's layout) "
                             "or names its columns gx, gy, gz")
    def column(role):
        return tab.column(roles[role])

    floats = numeric_columns(tab)
    if floats is not None and all(np.all(np.isfinite(floats[roles[r]])) for r in triad):
        raw = np.column_stack([floats[roles[r]] for r in triad])
    else:  # column by column: names the first bad value and its line
        raw = np.column_stack([parse_numbers(column(r), tab.dc, path, r, tab.names, roles[r], tab.lines)
                               for r in triad])
    t = None
    if "t" in roles:
        tcol = floats[roles["t"]] if floats is not None and np.all(np.isfinite(floats[roles["t"]])) else None
        t, _ = time_seconds(column("t"), None, time_unit, units.get("t"), tab.names, roles, tab.dc, path, tab.lines,
                            tab.preamble, parsed=tcol)
    # a file of its own: checked as every recording is, while its lines can still be named
    checked_recording(Recording(np.arange(len(raw)) if t is None else t, None, None, str(path), gyro=raw,
                                origin=table_origin(tab.names, {**roles, **dict(zip(GYRO_ROLES, map(roles.get, triad)))},
                                                    tab.lines, "line", timed=t is not None)))
    gyro, unit, note = resolve_gyro_unit(raw, units, gyro_unit, path)
    if t is not None:
        t, _ = clocked_time(t, None, counter_name="", mode=clock, timed_by_rate=False,
                            where=lambda i: f"line {tab.lines[i]}", path=path)  # on the clock, as the accelerometer
    return t, gyro, unit, [*notes, f"gyro from {path.name}: {note}"]


def attach_gyro(rec, path, *, gyro_unit: str | None = None, time_unit: str | None = None, clock: str = "auto"):
    """``rec`` with the gyro of the file ``path`` (module docstring): both on their clocks
    (:mod:`.clock`), their time offset measured from the motions (:mod:`.sync`), stated, and
    applied when it exceeds its uncertainty.

    Raises
    ------
    RecordingError
        The recording has gyro columns of its own, the file has no gyro columns, or its
        time base does not match the accelerometer's (:class:`accelcal.gyro.errors.GyroInputError`).
    """

    if rec.gyro is not None:
        raise RecordingError(f"{rec.source} has gyro columns of its own and --gyro {path} gives another gyro: "
                             "drop --gyro, or pass --no-gyro to calibrate the accelerometer alone")
    t, gyro, unit, notes = read_gyro_table(path, gyro_unit=gyro_unit, time_unit=time_unit, clock=clock)
    if t is None and len(gyro) != rec.n:
        raise GyroInputError(f"{path} has {len(gyro)} gyro samples, the accelerometer {rec.n}: their time bases do "
                             "not match; give a gyro file sampled with the accelerometer (--gyro FILE)")
    if t is not None:
        check_time_base(rec.t, t, sample_interval(rec.t).h)
    zero = sphere_centre(rec.acc) if rec.unit != "m/s^2" else 0.0
    offset = estimate_offset(rec.t, rec.acc, gyro, source=str(path), acc_zero=zero)
    if offset is None:
        notes.append("gyro - accelerometer time offset not measured: no motion both of them see")
    else:
        notes.append(offset.note(f"gyro from {Path(path).name}"))
        if offset.applied:
            gyro = shift_gyro(rec.t, gyro, offset.tau)
    return replace(rec, gyro=gyro, gyro_unit=unit, notes=rec.notes + tuple(notes))


__all__ = ["attach_gyro", "read_gyro_table"]
