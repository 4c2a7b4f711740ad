"""The canonical recording CSV of the CLI and the workflow: read strictly, written exactly.

A CSV file with a header row and the columns ``t`` [s], ``ax``, ``ay``, ``az`` (one
consistent unit: m/s² or raw counts), an optional ``temp`` [°C] and an optional ``pose``
(the label of the known static pose of each sample); other columns are ignored.

Every problem with a file raises :class:`~accelcal.errors.RecordingError` with a
one-line message that names the file, and where relevant the column and line.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from ..atomic import atomic_output
from ..errors import RecordingError
from ..recording import Origin, Recording, intervals_from_labels, labels_from_intervals
from .parsing import columns_named, drop_trailing_blank, read_delimited, to_float

#: Columns of the canonical CSV.
REQUIRED_COLUMNS = ("t", "ax", "ay", "az")
OPTIONAL_COLUMNS = ("temp",)
#: Optional column of the canonical CSV naming the known static pose of each sample
#: (empty where the sensor is not in a known pose).
POSE_COLUMN = "pose"


def read_canonical(path) -> Recording:
    """Read the canonical recording CSV of the CLI.

    Parameters
    ----------
    path : str or Path
        CSV with a header row and columns ``t``, ``ax``, ``ay``, ``az`` and optional
        ``temp``; other columns are ignored.

    Returns
    -------
    Recording

    Raises
    ------
    RecordingError
        Missing/empty file, no header or missing columns, non-numeric values; fewer
        than ``MIN_ROWS`` rows, non-finite values or time not strictly increasing are
        refused by :func:`accelcal.recording.checked_recording`, with the line.
    """
    what = "a CSV with header t,ax,ay,az[,temp]"
    df = drop_trailing_blank(read_delimited(path, what))
    df.columns = [str(c).strip() for c in df.columns]
    with open(path, newline="") as f:  # pandas renames duplicates ('ax', 'ax.1'): look at the raw header
        raw = [c.strip() for c in next(csv.reader(f))]
    dup = sorted({c for c in raw if raw.count(c) > 1})
    if dup:
        raise RecordingError(f"{path}: duplicate column(s) {', '.join(dup)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        looks_numeric = all(_is_number(c) for c in df.columns)
        hint = "no header row (first line is numeric)" if looks_numeric else \
            f"missing column(s) {', '.join(missing)} (found: {', '.join(df.columns)[:120]})"
        raise RecordingError(f"{path}: {hint}; expected header {','.join(REQUIRED_COLUMNS)}[,temp]")
    if len(df) == 0:
        raise RecordingError(f"{path}: header but no data rows")
    cols = {c: to_float(df, c, path, first_line=2) for c in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS) if c in df}
    intervals, labels = (intervals_from_labels(df[POSE_COLUMN].to_numpy(dtype=str)) if POSE_COLUMN in df
                         else (None, None))
    return Recording(cols["t"], np.column_stack([cols["ax"], cols["ay"], cols["az"]]), cols.get("temp"), str(path),
                     intervals=intervals, labels=labels,
                     origin=Origin("line", 2, names=columns_named(t="t", acc=("ax", "ay", "az"))))


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def write_canonical(path, rec: Recording) -> None:
    """Write ``rec`` as canonical CSV, atomically (temp file in the same folder, then rename).

    Floats are written with the shortest repr that round-trips, so
    ``read_canonical(write_canonical(p, rec))`` reproduces ``rec`` exactly.
    """
    path = Path(path)
    data = {"t": rec.t, "ax": rec.acc[:, 0], "ay": rec.acc[:, 1], "az": rec.acc[:, 2]}
    if rec.temp is not None:
        data["temp"] = rec.temp
    if rec.intervals is not None:
        data[POSE_COLUMN] = labels_from_intervals(rec.intervals, rec.labels, rec.n)
    with atomic_output(path) as tmp, open(tmp, "w", newline="") as f:
        import pandas as pd

        pd.DataFrame(data).to_csv(f, index=False)
        f.flush()
        os.fsync(f.fileno())
