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
import io
import re
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .atomic import atomic_output
from .errors import RecordingError

#: Fewest samples a recording may have: below this nothing (rest, noise) can be estimated.
MIN_ROWS = 10
#: Columns of the canonical CSV.
REQUIRED_COLUMNS = ("t", "ax", "ay", "az")
OPTIONAL_COLUMNS = ("temp",)
#: Optional column of the canonical CSV naming the known static pose of each sample
#: (empty where the sensor is not in a known pose).
POSE_COLUMN = "pose"
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

    def __post_init__(self):
        t = np.array(self.t, dtype=float)
        acc = np.array(self.acc, dtype=float)
        temp = None if self.temp is None else np.array(self.temp, dtype=float)
        if t.ndim != 1 or acc.shape != (t.size, 3) or (temp is not None and temp.shape != t.shape):
            raise RecordingError(
                f"{self.source}: inconsistent shapes t{t.shape}, acc{acc.shape}"
                + ("" if temp is None else f", temp{temp.shape}"))
        intervals, labels = _check_intervals(self.intervals, self.labels, t.size, self.source)
        for a in (t, acc, temp, intervals):
            if a is not None:
                a.setflags(write=False)  # frozen means frozen: no in-place edits of shared data
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "acc", acc)
        object.__setattr__(self, "temp", temp)
        object.__setattr__(self, "intervals", intervals)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "notes", tuple(self.notes))
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
    "imutk_fork": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s² (ROS IMU topic)"),
    "fxos8700": ((0.0,) * 3, (1.0,) * 3, None, "file already in m/s² (Adafruit sensor driver)"),
}


def nominal_conversion(kind: str) -> NominalConversion | None:
    """Nominal raw → m/s² conversion of a public format, or None where none is documented.

    Parameters
    ----------
    kind : {'imutk_xsens', 'mpu6050', 'imucal_session', 'imutk_fork', 'fxos8700', 'imucal_annotated'}
        The format.  ``'imucal_annotated'`` (raw counts of an unnamed sensor) returns None.
    """
    if kind == "imucal_annotated":
        return None
    if kind not in _NOMINAL:
        raise RecordingError(f"unknown recording format {kind!r}; known: {', '.join([*_NOMINAL, 'imucal_annotated'])}")
    offset, cpu, g, note = _NOMINAL[kind]
    return NominalConversion(np.array(offset), np.array(cpu), g, note)


# --------------------------------------------------------------------------- parsing


def _read_table(path, what: str, text: str | None = None, **kw):
    """Read a delimited text file as strings; every failure becomes a one-line RecordingError.

    ``text``: the file's content when already read (:func:`accelcal.readers.load_text`
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
        # (short or blank lines) stay '' and are reported by _to_float with their line.
        return pd.read_csv(path if text is None else io.StringIO(text), dtype=str, na_filter=False,
                           skip_blank_lines=False, **kw)
    except pd.errors.EmptyDataError:
        raise RecordingError(f"{path}: no data (expected {what})") from None
    except pd.errors.ParserError as e:
        msg = " ".join(str(e).split()).replace("Error tokenizing data. C error: ", "")
        raise RecordingError(f"{path}: malformed {what}: {msg}") from None
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text file (undecodable bytes), expected {what}") from None


def _drop_trailing_blank(df):
    """Drop blank lines at the end of the file (harmless); blank lines inside stay errors."""
    blank = (df == "").all(axis=1).to_numpy()
    n = len(df)
    while n and blank[n - 1]:
        n -= 1
    return df.iloc[:n]


def _to_float(df, col, path, first_line: int, name: str | None = None) -> np.ndarray:
    """Strictly convert one string column: non-numeric and non-finite values are errors.

    ``first_line`` is the 1-based file line of the first data row, so that messages
    point at the line a user can open.
    """
    name = col if name is None else name
    s = df[col].str.strip()
    import pandas as pd

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
    intervals, labels = intervals_from_labels(df[POSE_COLUMN].to_numpy(dtype=str)) if POSE_COLUMN in df else (None, None)
    return Recording(cols["t"], np.column_stack([cols["ax"], cols["ay"], cols["az"]]), cols.get("temp"), str(path),
                     intervals=intervals, labels=labels)


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


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


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


def write_recording(path, rec: Recording) -> None:
    """Write ``rec`` as canonical CSV, atomically (temp file in the same folder, then rename).

    Floats are written with the shortest repr that round-trips, so
    ``read_recording(write_recording(p, rec))`` reproduces ``rec`` exactly.
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


# --------------------------------------------------------------------------- public formats


def read_imutk_ascii(path, text: str | None = None) -> Recording:
    """Read an IMU-TK ASCII file (e.g. ``xsens_acc.mat``): whitespace-separated time, x, y, z.

    Values are returned as stored (raw counts for the Xsens example; see
    ``nominal_conversion('imutk_xsens')``).
    """
    df = _drop_trailing_blank(_read_table(path, "4 whitespace-separated columns (t x y z)", text,
                                          sep=r"\s+", header=None))
    if df.shape[1] != 4:
        raise RecordingError(f"{path}: {df.shape[1]} columns, expected 4 (t x y z) in an IMU-TK ASCII file")
    t, x, y, z = (_to_float(df, i, path, first_line=1, name=n) for i, n in enumerate(("t", "x", "y", "z")))
    _check_time(t, path, first_line=1)
    return Recording(t, np.column_stack([x, y, z]), None, str(path))


def read_imucal_session(csv_path, rate_hz: float = IMUCAL_RATE_HZ, text: str | None = None) -> Recording:
    """Read an imucal Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s²).

    ``n_samples`` is the sample counter (0, 1, 2, ... in the example: checked to be
    integer and strictly increasing), so ``t = n_samples / rate_hz``.  The gyro
    columns are validated but not returned.
    """
    cols = ("n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z")
    df = _drop_trailing_blank(_read_table(csv_path, "an imucal session CSV", text))
    _require(df, cols, csv_path)
    # Gyro columns are checked too: a damaged gyro field means a damaged file.
    v = {c: _to_float(df, c, csv_path, first_line=2) for c in cols}
    _check_counter(v["n_samples"], "n_samples", csv_path, first_line=2)
    t = v["n_samples"] / rate_hz
    _check_time(t, csv_path, first_line=2)
    return Recording(t, np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]]), None, str(csv_path), unit="m/s^2",
                     notes=(f"imucal session: t = n_samples / {rate_hz:g} Hz (the file has no rate)",))


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


def read_imucal_annotated(csv_path, rate_hz: float = IMUCAL_RATE_HZ,
                          text: str | None = None) -> tuple[Recording, np.ndarray]:
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
    df = _drop_trailing_blank(_read_table(csv_path, "an imucal annotated session CSV", text))
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
    return Recording(t, acc, None, str(csv_path), unit="counts"), parts


def read_mpu6050_csv(path, text: str | None = None) -> Recording:
    """Read the MPU-6050 calibration CSV of tomisuarez2/ImuCalibration.

    Layout: four ``key,value`` lines (``Fs,100``, ``Logging Type,0``,
    ``Initialization time,36.5``, ``Waiting time,3``), a header ``ax,ay,az,gx,gy,gz``
    and raw int16 counts.  ``t = row / Fs``.  See ``nominal_conversion('mpu6050')``.
    """
    path = Path(path)
    meta = _read_table(path, "an MPU-6050 CSV (Fs line, 3 metadata lines, header ax,ay,az,...)", text,
                       header=None, nrows=4, names=["key", "value"])
    if len(meta) < 4 or meta.iloc[0, 0].strip() != "Fs":
        raise RecordingError(f"{path}: expected 4 metadata lines starting with 'Fs,<rate>'")
    try:
        fs = float(meta.iloc[0, 1])
    except ValueError:
        fs = float("nan")
    if not np.isfinite(fs) or fs <= 0:
        raise RecordingError(f"{path}: invalid sampling rate Fs={meta.iloc[0, 1]!r}")
    df = _drop_trailing_blank(_read_table(path, "an MPU-6050 CSV", text, skiprows=4))
    cols = ("ax", "ay", "az", "gx", "gy", "gz")
    _require(df, cols, path)
    if len(df) == 0:
        raise RecordingError(f"{path}: header but no data rows")
    v = {c: _to_float(df, c, path, first_line=6) for c in cols}  # gyro checked: catches truncation
    acc = np.column_stack([v["ax"], v["ay"], v["az"]])
    t = np.arange(len(df)) / fs
    _check_time(t, path, first_line=6)
    return Recording(t, acc, None, str(path), unit="counts", notes=(f"MPU-6050 log: t = row / Fs = {fs:g} Hz",))


def _require(df, cols, path) -> None:
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


# --------------------------------------------------------------------------- block logs

#: Prompt that opens a block of a serial-monitor block log (FastAhrs' FXOS8700 calibration sketch).
_BLOCK_START = re.compile(r">>>\s*Gathering data for\s+([0-9.]+)\s*seconds", re.IGNORECASE)
_UNIT_LINE = re.compile(r"^\s*Type:\s*Acceleration\s*\((.+)\)\s*$", re.IGNORECASE)
#: Largest relative spread of the per-block sampling rates (rows / stated seconds).
BLOCK_RATE_TOLERANCE = 0.02


def read_block_log(path, text: str | None = None) -> Recording:
    """Read a serial-monitor log whose poses are separate blocks of ``x, y, z`` rows.

    Layout (vspruyt/FastAhrs ``data_sample*.csv``, FXOS8700): an optional sensor banner
    (``Type: Acceleration (m/s2)`` gives the unit), a line ``x, y, z``, then per pose the
    prompt lines ``>>> Place accelerometer ...``, ``>>> Type key when ready...``,
    ``>>> Gathering data for 10 seconds...`` followed by rows ``x, y, z``.  Lines starting
    with ``---`` (the monitor's own messages) and blank lines are skipped.

    Each block is one known static interval (the sensor is placed, then logged): the
    recording carries them as :attr:`Recording.intervals`.  The file has no time stamps:
    the rate is the block's rows over its stated seconds (the same for every block, else
    an error), ``t`` is the sample index over that rate, and the unknown time between
    blocks is taken as zero (stated in :attr:`Recording.notes`).
    """
    path = Path(path)
    what = "a block log (>>> Gathering data for N seconds... then x, y, z rows)"
    lines = _text_lines(path, what) if text is None else text.splitlines()
    if not lines:
        raise RecordingError(f"{path}: empty file (expected {what})")
    rows, blocks, seconds, unit = [], [], [], None
    current = None  # index into blocks of the block being filled, None outside a block
    for no, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("---"):
            continue
        m = _BLOCK_START.search(s)
        if m:
            seconds.append(float(m.group(1)))
            blocks.append([len(rows), len(rows), no])
            current = len(blocks) - 1
            continue
        if s.startswith(">>>"):
            current = None
            continue
        u = _UNIT_LINE.match(s)
        if u:
            unit = u.group(1).strip()
            continue
        if current is None:
            continue  # banner, header 'x, y, z', anything before the first block
        parts = s.split(",")
        try:
            vals = [float(x) for x in parts]
        except ValueError:
            vals = []
        if len(vals) != 3 or not all(np.isfinite(vals)):
            raise RecordingError(f"{path}: line {no}: expected three numbers 'x, y, z' in block {current}, "
                                 f"got {s[:40]!r}")
        rows.append(vals)
        blocks[current][1] = len(rows)
    if not blocks:
        raise RecordingError(f"{path}: no '>>> Gathering data for N seconds' block found; not a block log "
                             "(pass --format to choose another reader)")
    empty = [k for k, (a, b, _) in enumerate(blocks) if b - a < MIN_ROWS]
    if empty:
        k = empty[0]
        raise RecordingError(f"{path}: block {k} (line {blocks[k][2]}) has {blocks[k][1] - blocks[k][0]} rows; "
                             f"need at least {MIN_ROWS} (truncated or interrupted log?)")
    rates = np.array([(b - a) / sec if sec > 0 else np.nan for (a, b, _), sec in zip(blocks, seconds)])
    if not np.all(np.isfinite(rates)):
        raise RecordingError(f"{path}: a block states a duration of 0 seconds; cannot infer the sampling rate")
    rate = float(np.median(rates))
    off = np.flatnonzero(np.abs(rates / rate - 1) > BLOCK_RATE_TOLERANCE)
    if off.size:
        k = int(off[0])
        raise RecordingError(f"{path}: block {k} (line {blocks[k][2]}) has {blocks[k][1] - blocks[k][0]} rows for "
                             f"{seconds[k]:g} s where the others give {rate:g} Hz (truncated or interrupted block?)")
    acc = np.array(rows, dtype=float)
    t = np.arange(len(acc)) / rate
    notes = [f"no time stamps: t = sample index / {rate:g} Hz (rows per block over its stated seconds); "
             "the time between blocks is unknown and taken as zero",
             f"{len(blocks)} blocks read as known static intervals"]
    canonical = None
    if unit:
        from .units import G0, acceleration_unit

        canonical = acceleration_unit(unit)
        if canonical in ("g", "mg"):
            acc = acc * (G0 if canonical == "g" else G0 * 1e-3)
            canonical = "m/s^2"
        notes.append(f"unit from the banner: {unit}")
    return Recording(t, acc, None, str(path), intervals=[(a, b) for a, b, _ in blocks],
                     labels=tuple(f"block{k:02d}" for k in range(len(blocks))), notes=tuple(notes), unit=canonical)


def _text_lines(path: Path, what: str) -> list[str]:
    """The lines of a text file; a missing, empty or binary file is a one-line RecordingError."""
    if not path.is_file():
        raise RecordingError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    raw = path.read_bytes()
    if not raw:
        raise RecordingError(f"{path}: empty file (expected {what})")
    try:
        return raw.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text file (undecodable bytes), expected {what}") from None
