"""What the files of numerical environments share (MATLAB ``.mat``: :mod:`.mat`, R data:
:mod:`.rda`): named variables, one of which is the recording.

A file holds variables; the readers turn each numeric one into a :class:`Variable`: a
matrix of one row per sample and one column per quantity, with the column names when the
file has them (an R matrix's ``dimnames``, a data frame's names, a MATLAB struct's
fields) and the sampling rate when the file states it (the ``freq`` attribute of an R
``imu`` object).  Its columns are then found as a table's (:func:`.table.read_matrix`):
by their names, or, unnamed, as in a headerless table (3 columns: ax, ay, az; 4: t, ax,
ay, az; else ``--columns``), which a note states.

The variable is the only usable one, or named (``variable='NAME'``, ``--variable``); a
file with several usable ones and no choice is refused in one line listing them.  Several
names (``'x_rotation,y_rotation,z_rotation'``) are runs of one session recorded apart:
they are read alike, joined one after another (:data:`RUN_GAP_S` apart: their times are
not related, and the gap keeps a motion from spanning two of them) and marked as
:attr:`~accelcal.recording.Recording.runs`, so that each run rests, and has its bias, on
its own.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import RecordingError
from ..recording import MIN_ROWS, Recording, checked_recording
from .table import read_matrix

#: Time [s] put between runs joined from several variables (their own times are not related).
RUN_GAP_S = 1.0
#: Most columns a variable may have to be taken for a recording (more: a wide data matrix).
MAX_COLUMNS = 64


@dataclass(frozen=True)
class Variable:
    """One numeric variable of a file, as a recording's matrix (module docstring)."""

    name: str
    block: np.ndarray  #: (n, k) float
    names: tuple[str, ...] | None = None  #: column names, or None (numbered)
    rate: float | None = None  #: sampling rate the file states [Hz]
    rate_from: str = ""  #: where the file states it


def describe(shape, kind: str) -> str:
    """``'4001x3 double'``: a variable's shape and kind, for the listings."""
    return "x".join(str(int(d)) for d in shape) + f" {kind}"


def usable(shape) -> bool:
    """A matrix of at least :data:`~accelcal.recording.MIN_ROWS` rows (samples) and 3 to
    :data:`MAX_COLUMNS` columns (quantities)."""
    return len(shape) == 2 and shape[0] >= MIN_ROWS and 3 <= shape[1] <= MAX_COLUMNS


def choose(path, found: dict[str, str], variable: str | None, kind: str) -> list[str]:
    """The names of the variables to read.

    Parameters
    ----------
    found : dict
        Every variable of the file -> its description; the usable ones are those whose
        description does not start with ``'('`` (the readers put why a variable is not
        usable in parentheses).
    variable : str or None
        ``--variable``: one name, or several separated by commas (runs of one session).
    kind : str
        What the file is ("MATLAB file"), for messages.
    """
    ok = [k for k, v in found.items() if not v.startswith("(")]
    listing = ", ".join(f"{k} ({v.strip('()')})" for k, v in found.items())[:300] or "none"
    if variable is None:
        if len(ok) == 1:
            return ok
        if not ok:
            raise RecordingError(f"{path}: no variable of this {kind} is a recording (found: {listing}); a recording is "
                                 f"a numeric matrix of one row per sample (at least {MIN_ROWS}) and one column per "
                                 "quantity: save one (e.g. [t, gx, gy, gz]) and read it again")
        raise RecordingError(f"{path}: {len(ok)} variables could be the recording: {', '.join(ok)}; choose one with "
                             f"--variable NAME (several runs of one session: --variable {','.join(ok[:3])})")
    names = [v.strip() for v in str(variable).split(",") if v.strip()]
    if not names or len(set(names)) != len(names):
        raise RecordingError(f"--variable: one name or several distinct names separated by commas, got {variable!r}")
    for v in names:
        if v not in found:
            raise RecordingError(f"{path}: no variable {v!r} in this {kind} (found: {listing}); choose one with "
                                 "--variable NAME")
        if v not in ok:
            raise RecordingError(f"{path}: variable {v!r} is {found[v]}, not a recording (a numeric matrix of one "
                                 f"row per sample, at least {MIN_ROWS}); usable: {', '.join(ok) or 'none'}")
    return names


def read_variables(path, variables: list[Variable], *, columns=None, unit=None, time_unit=None, rate=None,
                   gyro_unit=None, kind: str = "variable") -> Recording:
    """The recording of the chosen variables: one, or several joined as runs (module docstring)."""

    recs = []
    for v in variables:
        notes = [f"{kind} {v.name} ({describe(v.block.shape, 'values')}"
                 + (")" if v.names is None else f"; columns {', '.join(v.names)[:120]})")]
        file_rate = None if rate is not None or v.rate is None else (v.rate, v.rate_from)
        try:
            rec = read_matrix(path, v.names, v.block, notes=notes, columns=columns, unit=unit, time_unit=time_unit,
                              rate=rate, gyro_unit=gyro_unit, file_rate=file_rate)
        except RecordingError as e:
            raise RecordingError(f"{e} ({kind} {v.name})" if len(variables) > 1 else str(e)) from None
        recs.append(replace(rec, origin=replace(rec.origin, label=f"{kind} {v.name}")))
    return recs[0] if len(recs) == 1 else join_runs(recs, [v.name for v in variables], path)


def join_runs(recs: list[Recording], names: list[str], path) -> Recording:
    """Recordings of one session recorded apart, as one with :attr:`~Recording.runs`; each run
    checked as every recording is (:func:`~accelcal.recording.checked_recording`) while its
    rows still name their variable."""
    recs = [checked_recording(r) for r in recs]
    first = recs[0]
    for name, r in zip(names[1:], recs[1:]):
        same = ((r.acc is None) == (first.acc is None) and (r.gyro is None) == (first.gyro is None)
                and r.unit == first.unit and r.gyro_unit == first.gyro_unit and (r.temp is None) == (first.temp is None))
        if not same:
            raise RecordingError(f"{path}: the runs {names[0]} and {name} do not hold the same quantities in the same "
                                 "units; read them one at a time (--variable NAME)")
    t, start, runs, pos = [], 0.0, [], 0
    for r in recs:
        t.append(r.t - r.t[0] + start)
        start = t[-1][-1] + RUN_GAP_S
        runs.append((pos, pos + r.n))
        pos += r.n

    def cat(field):
        parts = [getattr(r, field) for r in recs]
        return None if parts[0] is None else np.concatenate(parts)

    notes = list(dict.fromkeys([*first.notes, *(n for r in recs[1:] for n in r.notes)]))
    notes.append(f"{len(recs)} runs joined ({', '.join(names)}), each from t = 0, {RUN_GAP_S:g} s apart: "
                 "each rests and has its bias on its own")
    return replace(first, t=np.concatenate(t), acc=cat("acc"), temp=cat("temp"), gyro=cat("gyro"), notes=tuple(notes),
                   time_column=None, intervals=None, labels=None, rotations=None, runs=np.array(runs), origin=None)


__all__ = ["MAX_COLUMNS", "RUN_GAP_S", "Variable", "choose", "describe", "read_variables", "usable"]
