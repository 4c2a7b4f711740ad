"""Reading and writing accelerometer recordings (raw time series).

The canonical format of the CLI is a CSV file with a header row and the columns
``t`` [s], ``ax``, ``ay``, ``az`` (one consistent unit: m/s² or raw counts) and an
optional ``temp`` [°C]; other columns are ignored.  Readers for the three public
recordings in ``shared/data`` return the same :class:`Recording`, in the units stored
in the file; :func:`nominal_conversion` gives their nominal counts → m/s² conversion
where one is documented.

Every problem with a file raises :class:`~accelcal.errors.RecordingError` with a
one-line message that names the file, and where relevant the column and line.
Parsing is strict on purpose: a calibration silently fed a half-written or
mis-labelled file is worse than one that refuses to run.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .atomic import atomic_output
from .errors import RecordingError

#: Fewest samples a recording may have: below this nothing (rest, noise) can be estimated.
MIN_ROWS = 10
#: Columns of the canonical CSV.
REQUIRED_COLUMNS = ("t", "ax", "ay", "az")
OPTIONAL_COLUMNS = ("temp",)
#: Sampling rate of the imucal example sessions (imucal's examples and tests use it).
IMUCAL_RATE_HZ = 204.8
#: Spellings that pandas parses as NaN: reported as non-finite, not as non-numeric.
_NAN_SPELLINGS = {"nan", "+nan", "-nan"}


@dataclass(frozen=True)
class Recording:
    """One accelerometer recording.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s], strictly increasing.
    acc : ndarray, shape (n, 3)
        Specific force in the file's unit (m/s² or raw counts).
    temp : ndarray, shape (n,) or None
        Temperature [°C] if recorded.
    source : str
        Where the data came from (usually the file path).
    """

    t: np.ndarray
    acc: np.ndarray
    temp: np.ndarray | None
    source: str

    def __post_init__(self):
        t = np.array(self.t, dtype=float)
        acc = np.array(self.acc, dtype=float)
        temp = None if self.temp is None else np.array(self.temp, dtype=float)
        if t.ndim != 1 or acc.shape != (t.size, 3) or (temp is not None and temp.shape != t.shape):
            raise RecordingError(
                f"{self.source}: inconsistent shapes t{t.shape}, acc{acc.shape}"
                + ("" if temp is None else f", temp{temp.shape}"))
        for a in (t, acc, temp):
            if a is not None:
                a.setflags(write=False)  # frozen means frozen: no in-place edits of shared data
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "acc", acc)
        object.__setattr__(self, "temp", temp)

    @property
    def n(self) -> int:
        """Number of samples."""
        return self.t.size

    @property
    def rate(self) -> float:
        """Sampling rate [Hz] from the median time step."""
        return 1.0 / float(np.median(np.diff(self.t)))


@dataclass(frozen=True)
class NominalConversion:
    """Nominal conversion of a format's raw values to m/s²: ``(raw - offset) / counts_per_unit``.

    Attributes
    ----------
    offset : ndarray, shape (3,)
        Raw value of zero specific force (nominal bias), file units.
    counts_per_unit : ndarray, shape (3,)
        File units per m/s² (1 if the file is already in m/s²).
    g_local : float or None
        Local gravity [m/s²] the data's authors used, if documented.
    note : str
        Where the numbers come from.
    """

    offset: np.ndarray
    counts_per_unit: np.ndarray
    g_local: float | None
    note: str

    def to_si(self, acc) -> np.ndarray:
        """Apply the nominal conversion to raw values ``acc`` (..., 3)."""
        return (np.asarray(acc, dtype=float) - self.offset) / self.counts_per_unit


_G0 = 9.80665  # standard gravity: "counts per g" datasheet figures refer to it
_NOMINAL = {
    "imutk_xsens": ((32768.0,) * 3, (415.0, 413.0, 415.0), 9.81744,
                    "IMU-TK example: bias 32768, g = 9.81744; sensitivities from imu_tk_matlab calibrate.m"),
    "mpu6050": ((0.0,) * 3, (16384.0 / _G0,) * 3, None,
                "MPU-6050 datasheet, ±2 g range: 16384 counts per g"),
    "imucal_session": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s²"),
}


def nominal_conversion(kind: str) -> NominalConversion | None:
    """Nominal raw → m/s² conversion of a public format, or None where none is documented.

    Parameters
    ----------
    kind : {'imutk_xsens', 'mpu6050', 'imucal_session', 'imucal_annotated'}
        The format.  ``'imucal_annotated'`` (raw counts of an unnamed sensor) returns None.
    """
    if kind == "imucal_annotated":
        return None
    if kind not in _NOMINAL:
        raise RecordingError(f"unknown recording format {kind!r}; known: {', '.join([*_NOMINAL, 'imucal_annotated'])}")
    offset, cpu, g, note = _NOMINAL[kind]
    return NominalConversion(np.array(offset), np.array(cpu), g, note)


# --------------------------------------------------------------------------- parsing


def _read_table(path, what: str, **kw) -> pd.DataFrame:
    """Read a delimited text file as strings; every failure becomes a one-line RecordingError."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    if path.stat().st_size == 0:
        raise RecordingError(f"{path}: empty file (expected {what})")
    try:
        # dtype=str + na_filter=False: nothing is coerced behind our back; empty fields
        # (short or blank lines) stay '' and are reported by _to_float with their line.
        return pd.read_csv(path, dtype=str, na_filter=False, skip_blank_lines=False, **kw)
    except pd.errors.EmptyDataError:
        raise RecordingError(f"{path}: no data (expected {what})") from None
    except pd.errors.ParserError as e:
        msg = " ".join(str(e).split()).replace("Error tokenizing data. C error: ", "")
        raise RecordingError(f"{path}: malformed {what}: {msg}") from None
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text file (undecodable bytes), expected {what}") from None


def _drop_trailing_blank(df: pd.DataFrame) -> pd.DataFrame:
    """Drop blank lines at the end of the file (harmless); blank lines inside stay errors."""
    blank = (df == "").all(axis=1).to_numpy()
    n = len(df)
    while n and blank[n - 1]:
        n -= 1
    return df.iloc[:n]


def _to_float(df: pd.DataFrame, col, path, first_line: int, name: str | None = None) -> np.ndarray:
    """Strictly convert one string column: non-numeric and non-finite values are errors.

    ``first_line`` is the 1-based file line of the first data row, so that messages
    point at the line a user can open.
    """
    name = col if name is None else name
    s = df[col].str.strip()
    x = pd.to_numeric(s, errors="coerce").to_numpy(dtype=float)
    bad = np.isnan(x) & ~s.str.lower().isin(_NAN_SPELLINGS).to_numpy()
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        val = s.iloc[i]
        what = "missing value (short or blank line)" if val == "" else f"non-numeric value {val[:20]!r}"
        raise RecordingError(f"{path}: column {name!r}: {what} at line {first_line + i}"
                             f" ({int(bad.sum())} bad value(s) in this column)")
    nonfinite = ~np.isfinite(x)
    if nonfinite.any():
        i = int(np.flatnonzero(nonfinite)[0])
        raise RecordingError(f"{path}: column {name!r}: non-finite value {s.iloc[i]!r} at line {first_line + i}")
    return x


def _check_time(t: np.ndarray, path, first_line: int) -> None:
    """Enough rows and strictly increasing time."""
    if t.size < MIN_ROWS:
        raise RecordingError(f"{path}: only {t.size} data rows; need at least {MIN_ROWS}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise RecordingError(f"{path}: time not strictly increasing at line {first_line + i}"
                             f" (t = {t[i]:g} after {t[i - 1]:g})")


# --------------------------------------------------------------------------- canonical CSV


def read_recording(path) -> Recording:
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
        Missing/empty file, no header or missing columns, non-numeric or non-finite
        values, fewer than ``MIN_ROWS`` rows, time not strictly increasing.
    """
    what = "a CSV with header t,ax,ay,az[,temp]"
    df = _drop_trailing_blank(_read_table(path, what))
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
    cols = {c: _to_float(df, c, path, first_line=2) for c in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS) if c in df}
    _check_time(cols["t"], path, first_line=2)
    return Recording(cols["t"], np.column_stack([cols["ax"], cols["ay"], cols["az"]]), cols.get("temp"), str(path))


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def write_recording(path, rec: Recording) -> None:
    """Write ``rec`` as canonical CSV, atomically (temp file in the same folder, then rename).

    Floats are written with the shortest repr that round-trips, so
    ``read_recording(write_recording(p, rec))`` reproduces ``rec`` exactly.
    """
    path = Path(path)
    data = {"t": rec.t, "ax": rec.acc[:, 0], "ay": rec.acc[:, 1], "az": rec.acc[:, 2]}
    if rec.temp is not None:
        data["temp"] = rec.temp
    with atomic_output(path) as tmp, open(tmp, "w", newline="") as f:
        pd.DataFrame(data).to_csv(f, index=False)
        f.flush()
        os.fsync(f.fileno())


# --------------------------------------------------------------------------- public formats


def read_imutk_ascii(path) -> Recording:
    """Read an IMU-TK ASCII file (e.g. ``xsens_acc.mat``): whitespace-separated time, x, y, z.

    Values are returned as stored (raw counts for the Xsens example; see
    ``nominal_conversion('imutk_xsens')``).
    """
    df = _drop_trailing_blank(_read_table(path, "4 whitespace-separated columns (t x y z)",
                                          sep=r"\s+", header=None))
    if df.shape[1] != 4:
        raise RecordingError(f"{path}: {df.shape[1]} columns, expected 4 (t x y z) in an IMU-TK ASCII file")
    t, x, y, z = (_to_float(df, i, path, first_line=1, name=n) for i, n in enumerate(("t", "x", "y", "z")))
    _check_time(t, path, first_line=1)
    return Recording(t, np.column_stack([x, y, z]), None, str(path))


def read_imucal_session(csv_path, rate_hz: float = IMUCAL_RATE_HZ) -> Recording:
    """Read an imucal Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s²).

    ``n_samples`` is the sample counter (0, 1, 2, ... in the example: checked to be
    integer and strictly increasing), so ``t = n_samples / rate_hz``.  The gyro
    columns are validated but not returned.
    """
    cols = ("n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z")
    df = _drop_trailing_blank(_read_table(csv_path, "an imucal session CSV"))
    _require(df, cols, csv_path)
    # Gyro columns are checked too: a damaged gyro field means a damaged file.
    v = {c: _to_float(df, c, csv_path, first_line=2) for c in cols}
    _check_counter(v["n_samples"], "n_samples", csv_path, first_line=2)
    t = v["n_samples"] / rate_hz
    _check_time(t, csv_path, first_line=2)
    return Recording(t, np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]]), None, str(csv_path))


def read_imucal_section_list(json_path) -> dict[str, tuple[int, int]]:
    """Read an imucal section list: ``{name: (start, end)}``, half-open sample ranges.

    imucal slices with ``data.iloc[start:end]``, so ``end`` is exclusive.
    """
    path = Path(json_path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        raw = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise RecordingError(f"{path}: not valid JSON ({' '.join(str(e).split())})") from None
    if not isinstance(raw, dict) or not raw:
        raise RecordingError(f"{path}: expected a JSON object of sections {{name: {{start, end}}}}")
    out = {}
    for name, sec in raw.items():
        try:
            start, end = sec["start"], sec["end"]
        except (TypeError, KeyError):
            raise RecordingError(f"{path}: section {name!r} lacks integer 'start' and 'end'") from None
        if not (isinstance(start, int) and isinstance(end, int)) or isinstance(start, bool) \
                or isinstance(end, bool) or not 0 <= start < end:
            raise RecordingError(f"{path}: section {name!r} has invalid range start={start!r}, end={end!r}")
        out[str(name)] = (start, end)
    return out


def read_imucal_annotated(csv_path, rate_hz: float = IMUCAL_RATE_HZ) -> tuple[Recording, np.ndarray]:
    """Read imucal's annotated session (``part, samples, acc_*, gyr_*``, raw counts).

    The file is grouped by section, not in time order; rows are sorted by the
    ``samples`` counter, which must be unique integers.  ``t = samples / rate_hz``.

    Returns
    -------
    rec : Recording
        Time-ordered acceleration in raw counts (no documented nominal scale).
    parts : ndarray of str, shape (n,)
        Section label of each sample (``x_p``, ..., ``z_rot``), in time order.
    """
    cols = ("part", "samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
    df = _drop_trailing_blank(_read_table(csv_path, "an imucal annotated session CSV"))
    _require(df, cols, csv_path)
    v = {c: _to_float(df, c, csv_path, first_line=2) for c in cols[1:]}
    s = v["samples"]
    order = np.argsort(s, kind="stable")
    _check_counter(s[order], "samples", csv_path, first_line=None)
    parts = df["part"].str.strip().to_numpy(dtype=str)[order]
    if (parts == "").any():
        raise RecordingError(f"{csv_path}: empty 'part' label at line {2 + int(np.flatnonzero(parts == '')[0])}")
    acc = np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]])[order]
    t = s[order] / rate_hz
    _check_time(t, csv_path, first_line=2)
    return Recording(t, acc, None, str(csv_path)), parts


def read_mpu6050_csv(path) -> Recording:
    """Read the MPU-6050 calibration CSV of tomisuarez2/ImuCalibration.

    Layout: four ``key,value`` lines (``Fs,100``, ``Logging Type,0``,
    ``Initialization time,36.5``, ``Waiting time,3``), a header ``ax,ay,az,gx,gy,gz``
    and raw int16 counts.  ``t = row / Fs``.  See ``nominal_conversion('mpu6050')``.
    """
    path = Path(path)
    meta = _read_table(path, "an MPU-6050 CSV (Fs line, 3 metadata lines, header ax,ay,az,...)",
                       header=None, nrows=4, names=["key", "value"])
    if len(meta) < 4 or meta.iloc[0, 0].strip() != "Fs":
        raise RecordingError(f"{path}: expected 4 metadata lines starting with 'Fs,<rate>'")
    try:
        fs = float(meta.iloc[0, 1])
    except ValueError:
        fs = float("nan")
    if not np.isfinite(fs) or fs <= 0:
        raise RecordingError(f"{path}: invalid sampling rate Fs={meta.iloc[0, 1]!r}")
    df = _drop_trailing_blank(_read_table(path, "an MPU-6050 CSV", skiprows=4))
    cols = ("ax", "ay", "az", "gx", "gy", "gz")
    _require(df, cols, path)
    if len(df) == 0:
        raise RecordingError(f"{path}: header but no data rows")
    v = {c: _to_float(df, c, path, first_line=6) for c in cols}  # gyro checked: catches truncation
    acc = np.column_stack([v["ax"], v["ay"], v["az"]])
    t = np.arange(len(df)) / fs
    _check_time(t, path, first_line=6)
    return Recording(t, acc, None, str(path))


def _require(df: pd.DataFrame, cols, path) -> None:
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing)} (found: {', '.join(df.columns)[:120]})")


def _check_counter(s: np.ndarray, name: str, path, first_line: int | None) -> None:
    """A sample counter must hold integers, strictly increasing (after sorting if first_line is None)."""
    if np.any(s != np.round(s)):
        raise RecordingError(f"{path}: column {name!r} holds non-integer sample numbers")
    d = np.diff(s)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        where = f"line {first_line + i}" if first_line is not None else f"sample {int(s[i])}"
        raise RecordingError(f"{path}: column {name!r} not strictly increasing (repeated at {where})")
