"""Strict parsing of delimited text shared by the readers: every failure one RecordingError line.

Parsing is strict on purpose: a calibration silently fed a half-written or mis-labelled
file is worse than one that refuses to run.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np

from ..errors import RecordingError

#: Spellings that pandas parses as NaN: reported as non-finite, not as non-numeric.
NAN_SPELLINGS = {"nan", "+nan", "-nan"}
NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+([eE][+-]?\d+)?$")
#: Spellings of nan and inf that Python's float reads: numbers, refused in a recording with their line.
NON_FINITE = re.compile(r"^[+-]?(nan|inf|infinity)$", re.IGNORECASE)


def read_delimited(path, what: str, text: str | None = None, **kw):
    """Read a delimited text file as strings; every failure becomes a one-line RecordingError.

    ``text``: the file's content when already read (:func:`accelcal.formats.text.load_text`
    undoes gzip); ``path`` then only names the file in messages.
    """
    import pandas as pd  # here, not at import: the plain-table reader and the CLI's help do without it

    path = Path(path)
    if text is None:
        if not path.is_file():
            raise RecordingError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
        if path.stat().st_size == 0:
            raise RecordingError(f"{path}: empty file (expected {what})")
    elif not text:
        raise RecordingError(f"{path}: empty file (expected {what})")
    try:
        # dtype=str + na_filter=False: nothing is coerced behind our back; empty fields
        # (short or blank lines) stay '' and are reported by to_float with their line.
        return pd.read_csv(path if text is None else io.StringIO(text), dtype=str, na_filter=False,
                           skip_blank_lines=False, **kw)
    except pd.errors.EmptyDataError:
        raise RecordingError(f"{path}: no data (expected {what})") from None
    except pd.errors.ParserError as e:
        msg = " ".join(str(e).split()).replace("Error tokenizing data. C error: ", "")
        raise RecordingError(f"{path}: malformed {what}: {msg}") from None
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text file (undecodable bytes), expected {what}") from None


def drop_trailing_blank(df):
    """Drop blank lines at the end of the file (harmless); blank lines inside stay errors."""
    blank = (df == "").all(axis=1).to_numpy()
    n = len(df)
    while n and blank[n - 1]:
        n -= 1
    return df.iloc[:n]


def to_float(df, col, path, first_line: int, name: str | None = None) -> np.ndarray:
    """Strictly convert one string column: non-numeric values are errors.

    ``first_line`` is the 1-based file line of the first data row, so that messages
    point at the line a user can open.  ``nan`` and ``inf`` are numbers here: whether a
    recording may hold them is :func:`accelcal.recording.checked_recording`'s to say, with
    the line (the reader's :class:`~accelcal.recording.Origin`).
    """
    name = col if name is None else name
    s = df[col].str.strip()
    import pandas as pd

    x = pd.to_numeric(s, errors="coerce").to_numpy(dtype=float)
    bad = np.isnan(x) & ~s.str.lower().isin(NAN_SPELLINGS).to_numpy()
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        val = s.iloc[i]
        what = "missing value (short or blank line)" if val == "" else f"non-numeric value {val[:20]!r}"
        raise RecordingError(f"{path}: column {name!r}: {what} at line {first_line + i}"
                             f" ({int(bad.sum())} bad value(s) in this column)")
    return x


def columns_named(**fields) -> tuple:
    """An :class:`~accelcal.recording.Origin`'s ``names``: each field's columns as the file names them
    (``columns_named(t="t", acc=("ax", "ay", "az"))``)."""
    return tuple((f, f"column {c!r}" if isinstance(c, str) else tuple(f"column {x!r}" for x in c))
                 for f, c in fields.items())


def require_columns(df, cols, path) -> None:
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing)} (found: {', '.join(df.columns)[:120]})")


def check_counter(s: np.ndarray, name: str, path) -> None:
    """A sample counter must hold integers (a format's own structure: the time made from it is
    checked with every recording's, :func:`accelcal.recording.checked_recording`)."""
    if np.any(s != np.round(s)):
        raise RecordingError(f"{path}: column {name!r} holds non-integer sample numbers")


def split_fields(line: str, delim: str) -> list[str]:
    return line.split() if delim == " " else [f.strip() for f in line.split(delim)]


def norm_name(name: str) -> str:
    return re.sub(r"[\s_.\-:/]+", "", name.lower())


def parse_numbers(values, dc: bool, path, role: str, names, col: int, lines, finite: bool = False) -> np.ndarray:
    """Strict float conversion of one column; the first bad value is reported with its line.  ``nan``
    and ``inf`` are numbers (a recording's are refused by :func:`accelcal.recording.checked_recording`),
    unless ``finite``: a column whose nan would mean something else (a magnetometer's: no sample)."""
    s = np.char.strip(values.astype(str))
    if dc:
        s = np.char.replace(s, ",", ".")
    out = np.empty(s.size)
    bad = None
    try:
        out[:] = s.astype(float)
    except ValueError:
        for i, v in enumerate(s):
            try:
                out[i] = float(v)
            except ValueError:
                bad = i
                break
    label = f"{role} (column {names[col].strip()!r})" if names is not None else f"{role} (column {col + 1})"
    if bad is not None:
        v = s[bad]
        what = "empty field" if v == "" else f"non-numeric value {v[:20]!r}"
        raise RecordingError(f"{path}: {label}: {what} at line {lines[bad]}")
    nonfinite = ~np.isfinite(out) if finite else np.zeros(0, bool)
    if nonfinite.any():
        i = int(np.flatnonzero(nonfinite)[0])
        raise RecordingError(f"{path}: {label}: non-finite value {str(s[i])!r} at line {lines[i]}")
    return out
