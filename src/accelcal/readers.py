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
    IMU-TK ASCII (``xsens_acc.mat``; :func:`accelcal.recording.read_imutk_ascii`).
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

import gzip
import re
import zlib
from dataclasses import replace
from pathlib import Path

import numpy as np

from .errors import RecordingError
from .recording import (MIN_ROWS, Recording, intervals_from_labels, read_block_log, read_imucal_annotated,
                        read_imucal_section_list, read_imucal_session, read_imutk_ascii, read_mpu6050_csv)
from .units import G0, acceleration_unit, time_unit, to_celsius, unit_in_name

FORMATS = ("auto", "csv", "imutk", "mpu6050", "imucal", "imucal-annotated", "block-log")
ROLES = ("t", "ax", "ay", "az", "temp", "pose")
#: Comment lines start with one of these (after leading blanks).
COMMENT_MARKERS = ("#", "%", "//")
#: Delimiters tried, in order of preference when two fit equally well.
DELIMITERS = ("\t", ";", ",", "|", " ")
#: Canonical sampling rate the time-unit inference aims at [Hz] (typical IMU logging).
TYPICAL_RATE_HZ = 100.0

_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+([eE][+-]?\d+)?$")

#: Column names (lower case, without unit, separators removed) for each role.
_ACC = re.compile(r"^(?:field)?(?:imu)?(?:linear)?(?:acc|accel|accl|acceleration|accelerometer|acceleromter|a)"
                  r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_ACC_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:acc|accel|acceleration|a)$")
_TIME = {"t", "time", "times", "timestamp", "timestamps", "ts", "stamp", "sec", "secs", "seconds", "elapsed",
         "elapsedtime", "datetime", "date", "clock", "millis", "micros", "nanos", "tsec", "fieldheaderstamp",
         "headerstamp", "%time", "timeus", "timems", "timens", "zeit", "zeitstempel", "tiempo", "temps", "tempo"}
_TIME_UNIT_BY_NAME = {"millis": "ms", "micros": "us", "nanos": "ns", "timems": "ms", "timeus": "us", "timens": "ns"}
_TEMP = {"temp", "temperature", "imutemp", "dietemp", "temperaturec", "tempc", "thermometer"}
_POSE = {"pose", "poseid", "staticpose", "posename"}
#: Documented for the CLI's help: what each role is found by.
ALIASES = {
    "t": "t, time, timestamp, ts, stamp, seconds, elapsed, datetime, millis, micros, %time, field.header.stamp",
    "ax, ay, az": "ax, acc_x, accX, AX, accel_x, Accel. X, a_x, x_acc, acceleration_x, accelerometer_x, "
                  "linear_acceleration.x (x, y, z alone when nothing else matches)",
    "temp": "temp, temperature, imu_temp, die_temp",
    "pose": "pose, pose_id (label of the known static pose of each sample; empty between poses)",
}


# --------------------------------------------------------------------------- entry point


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
        return rec if rec.unit is not None else _infer_unit(rec)
    u = acceleration_unit(unit)
    if rec.unit is not None and rec.unit != ("counts" if u == "counts" else "m/s^2"):
        raise RecordingError(f"{path}: --unit {unit} contradicts the format, whose values are in {rec.unit}")
    acc, note = _convert_acc(rec.acc, u, "--unit")
    return replace(rec, acc=acc, unit="counts" if u == "counts" else "m/s^2", notes=rec.notes + (note,))


# --------------------------------------------------------------------------- text


def load_text(path: Path) -> tuple[str, list[str]]:
    """The decoded text of ``path`` (gzip undone) and notes on what was done.

    Raises
    ------
    RecordingError
        Missing, empty, binary (with the likely kind: zip/Excel, HDF5, MATLAB, R data),
        corrupt gzip.
    """
    if not path.exists():
        raise RecordingError(f"{path}: no such file")
    if not path.is_file():
        raise RecordingError(f"{path}: not a file")
    raw = path.read_bytes()
    notes = []
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError, zlib.error) as e:
            raise RecordingError(f"{path}: damaged gzip file ({' '.join(str(e).split())}); "
                                 "decompress it with gunzip to see what is left") from None
        notes.append("gzip-compressed")
    if not raw.strip():
        raise RecordingError(f"{path}: empty file (expected a recording: a table of t, ax, ay, az)")
    kind = _binary_kind(raw)
    if kind:
        raise RecordingError(f"{path}: {kind}, not a text table; export the recording as CSV")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
        notes.append("not UTF-8: decoded as Windows-1252")
    return text, notes


def _binary_kind(raw: bytes) -> str | None:
    head = raw[:65536]
    for magic, kind in ((b"PK\x03\x04", "a zip archive (or an Excel .xlsx workbook)"),
                        (b"\x89HDF", "an HDF5 file"), (b"MATLAB 5.0", "a MATLAB .mat binary file"),
                        (b"RDX", "an R data file"), (b"\xfd7zXZ", "an xz-compressed file"),
                        (b"BZh", "a bzip2-compressed file"), (b"\xd0\xcf\x11\xe0", "an Excel .xls workbook"),
                        (b"#ROSBAG", "a ROS bag (export the IMU topic with rostopic echo -p)"),
                        (b"\x93NUMPY", "a numpy .npy file")):
        if head.startswith(magic):
            return kind
    if b"\x00" in head:
        return "binary data (NUL bytes)"
    control = sum(1 for b in head if b < 32 and b not in (9, 10, 13))
    if control > 0.01 * len(head):
        return "binary data (control characters)"
    return None


def _is_comment(line: str) -> bool:
    s = line.lstrip()
    return s.startswith(COMMENT_MARKERS)


# --------------------------------------------------------------------------- format detection


def detect_format(text: str) -> str:
    """The format of a recording from its first lines (:data:`FORMATS` without ``'auto'``)."""
    head = text[:8192]
    if re.search(r">>>\s*Gathering data for", head, re.IGNORECASE):
        return "block-log"
    lines = [ln.strip() for ln in head.splitlines() if ln.strip() and not _is_comment(ln)]
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


# --------------------------------------------------------------------------- tables


def parse_columns(spec) -> dict:
    """``'t=time,ax=AccX,...'`` (or a dict) → ``{role: name or 0-based index}``.

    Numbers are 1-based column positions (as a user counts them); names match the header
    with its whitespace stripped, case-insensitively.
    """
    if spec is None:
        return {}
    items = spec.items() if isinstance(spec, dict) else (
        (p.split("=", 1) if "=" in p else (p, None)) for p in str(spec).split(",") if p.strip())
    out = {}
    for role, col in items:
        role = str(role).strip().lower()
        if role not in ROLES or col is None or str(col).strip() == "":
            raise RecordingError(f"--columns: expected ROLE=COLUMN with ROLE in {', '.join(ROLES)} "
                                 f"(e.g. t=time,ax=AccX,ay=AccY,az=AccZ), got {role!r}")
        col = str(col).strip()
        if col.isdigit():
            if int(col) < 1:
                raise RecordingError(f"--columns: column numbers start at 1, got {role}={col}")
            out[role] = int(col) - 1
        else:
            out[role] = col
    return out


def _split(line: str, delim: str) -> list[str]:
    return line.split() if delim == " " else [f.strip() for f in line.split(delim)]


def _numeric_share(rows, decimal_comma: bool) -> float:
    cells = [c for r in rows for c in r]
    if not cells:
        return 0.0
    pat = _DECIMAL_COMMA if decimal_comma else _NUMBER
    return sum(1 for c in cells if _NUMBER.match(c) or pat.match(c)) / len(cells)


def sniff(lines: list[str]) -> tuple[str, bool, int]:
    """Delimiter, decimal comma and field count of the data rows (the last lines).

    The delimiter that splits the last (up to 200) content lines into the same number of
    fields (at least 3) with the largest share of numbers wins; a decimal comma is
    recognised when the delimiter is not a comma and fields look like ``9,81``.
    """
    tail = lines[-200:]
    best = None
    for order, delim in enumerate(DELIMITERS):
        rows = [_split(ln, delim) for ln in tail]
        rows = [r[:-1] if r and r[-1] == "" and len(r) > 1 else r for r in rows]  # trailing delimiter
        counts = np.bincount([len(r) for r in rows])
        k = int(np.argmax(counts))
        if k < 3:
            continue
        consistent = counts[k] / len(rows)
        same = [r for r in rows if len(r) == k]
        dc = delim != "," and any(_DECIMAL_COMMA.match(c) for r in same[:50] for c in r)
        score = consistent * _numeric_share(same, dc)
        if best is None or score > best[0] + 1e-9:
            best = (score, delim, dc, k, order)
    if best is None or best[0] < 0.3:
        widest = max((len(_split(ln, d)), d) for d in DELIMITERS for ln in tail[:1])
        first = ", ".join(_split(lines[0], widest[1]))[:80] if widest[0] > 1 else lines[0][:60]
        raise RecordingError(f"no table of 3 or more columns found (first line: {first!r}); a recording needs "
                             "three acceleration columns (and time): name them with --columns t=..,ax=..,ay=..,az=..")
    return best[1], best[2], best[3]


def read_table(path, *, text: str | None = None, columns=None, unit: str | None = None,
               time_unit: str | None = None, rate: float | None = None) -> Recording:
    """Read a delimited text table (the ``csv`` format; see the module docstring).

    Raises
    ------
    RecordingError
        No table, missing or ambiguous columns, bad values (with the line), time that
        does not increase, a unit that cannot be determined consistently.
    """
    path = Path(path)
    notes: list[str] = []
    if text is None:
        text, notes = load_text(path)
    all_lines = text.splitlines()
    numbered = [(no, ln) for no, ln in enumerate(all_lines, start=1) if ln.strip() and not _is_comment(ln)]
    if not numbered:
        raise RecordingError(f"{path}: only comments and blank lines, no data")
    try:
        delim, dc, k = sniff([ln for _, ln in numbered])
    except RecordingError as e:
        raise RecordingError(f"{path}: {e}") from None
    rows = []
    for no, ln in numbered:
        r = _split(ln, delim)
        if len(r) == k + 1 and r[-1] == "":
            r = r[:-1]
        rows.append(r)
    header, first = _find_header(rows, k, dc)
    if header is None and first == 0:  # a header that looks like a comment: rostopic's '%time,field...'
        rows, numbered, header = _comment_header(all_lines, numbered, rows, delim, k)
        first = 1 if header is not None else 0
    preamble = [(numbered[i][0], rows[i]) for i in range(first if header is None else header)]
    data = rows[first:]
    lines = [numbered[i][0] for i in range(first, len(rows))]
    bad = next((i for i, r in enumerate(data) if len(r) != k), None)
    if bad is not None:
        raise RecordingError(f"{path}: line {lines[bad]} has {len(data[bad])} fields where the table has {k} "
                             "(truncated, or a line of another kind inside the data)")
    if len(data) < MIN_ROWS:
        raise RecordingError(f"{path}: only {len(data)} data rows; need at least {MIN_ROWS}")
    names = rows[header] if header is not None else None
    what = {"\t": "tab", ";": "semicolon", ",": "comma", "|": "'|'", " ": "whitespace"}[delim]
    if delim != "," or dc:
        notes.append(f"{what}-separated" + (", decimal comma" if dc else ""))
    roles, units = _map_columns(names, k, parse_columns(columns), path)
    if names is None:
        notes.append("no header: columns read as " + ", ".join(
            f"{r}=column {i + 1}" for r, i in roles.items()) + " (pass --columns to change)")
    cols = list(zip(*data))

    def column(role):
        return np.asarray(cols[roles[role]], dtype=object)

    acc = np.column_stack([_numbers(column(a), dc, path, a, names, roles[a], lines) for a in ("ax", "ay", "az")])
    acc, unit_name, note = _acceleration_unit(acc, units, unit, path)
    notes.append(note)
    t, tnote = _time(column("t") if "t" in roles else None, rate, time_unit, units.get("t"), names, roles, dc, path,
                     lines, preamble)
    notes.append(tnote)
    temp = None
    if "temp" in roles:
        temp = _numbers(column("temp"), dc, path, "temp", names, roles["temp"], lines)
        if units.get("temp") in ("K", "degF"):
            temp = to_celsius(temp, units["temp"])
            notes.append(f"temperature converted from {units['temp']} to degC")
    iv, labels = (intervals_from_labels(column("pose").astype(str)) if "pose" in roles else (None, None))
    time_column = None
    if "t" in roles and rate is None:
        time_column = (names[roles["t"]].strip() if names is not None else "t", column("t").astype(str))
    return Recording(t, acc, temp, str(path), intervals=iv, labels=labels, notes=tuple(n for n in notes if n),
                     unit=unit_name, time_column=time_column)


def _comment_header(all_lines, numbered, rows, delim, k):
    """The comment line just above the data as the header, if it has the data's field
    count and names (``%time,field.header.seq,...`` of ``rostopic echo -p``)."""
    above = numbered[0][0] - 1  # 1-based line number of the line above the first data row
    if above < 1 or not _is_comment(all_lines[above - 1]):
        return rows, numbered, None
    cand = _split(all_lines[above - 1].strip(), delim)
    if len(cand) != k or sum(1 for c in cand if _NUMBER.match(c)) > 0:
        return rows, numbered, None
    return [cand] + rows, [(above, all_lines[above - 1])] + numbered, 0


def _find_header(rows, k: int, dc: bool) -> tuple[int | None, int]:
    """(header row index or None, first data row index).

    Data start at the first row of ``k`` fields from which on every row has ``k`` fields
    (or, for a damaged file, the first row of ``k`` mostly numeric fields); the header is
    the row just before it if it has ``k`` fields and is not mostly numeric.
    """
    def numeric(r):
        return sum(1 for c in r if _NUMBER.match(c) or (dc and _DECIMAL_COMMA.match(c))) >= max(2, len(r) // 2)

    first = next((i for i, r in enumerate(rows) if len(r) == k and numeric(r)), None)
    if first is None:
        raise RecordingError("no data rows found")
    if first > 0 and len(rows[first - 1]) == k and not numeric(rows[first - 1]):
        return first - 1, first
    return None, first


def _norm(name: str) -> str:
    return re.sub(r"[\s_.\-:/]+", "", name.lower())


def _map_columns(names, k: int, given: dict, path) -> tuple[dict, dict]:
    """``{role: column index}`` and ``{role: unit found in the header}``."""
    roles, units = {}, {}
    if names is None:
        if set(given) - {"t", "ax", "ay", "az", "temp", "pose"} or any(isinstance(v, str) for v in given.values()):
            raise RecordingError(f"{path}: the file has no header, so --columns needs column numbers "
                                 "(e.g. t=1,ax=2,ay=3,az=4)")
        default = {4: ("t", "ax", "ay", "az"), 3: ("ax", "ay", "az"), 5: ("t", "ax", "ay", "az", "temp")}
        if not given and k not in default:
            raise RecordingError(f"{path}: no header and {k} columns: say which is which with --columns "
                                 "(e.g. t=1,ax=2,ay=3,az=4)")
        roles = dict(given) if given else {r: i for i, r in enumerate(default[k])}
    else:
        stripped = [n.strip() for n in names]
        for role, col in given.items():
            if isinstance(col, int):
                if col >= k:
                    raise RecordingError(f"{path}: --columns {role}={col + 1}: the table has {k} columns")
                roles[role] = col
            else:
                hits = [i for i, n in enumerate(stripped) if n.lower() == col.lower()]
                if not hits:
                    raise RecordingError(f"{path}: --columns {role}={col}: no such column "
                                         f"(found: {', '.join(stripped)[:150]})")
                roles[role] = hits[0]
        _find_roles(stripped, roles, path)
    missing = [r for r in ("ax", "ay", "az") if r not in roles]
    if missing:
        found = ", ".join(n.strip() for n in names)[:150] if names is not None else f"{k} unnamed columns"
        raise RecordingError(f"{path}: no column for {', '.join(missing)} (found: {found}); "
                             "name them with --columns t=TIME,ax=X,ay=Y,az=Z")
    used = {}
    for role, i in roles.items():
        if i in used:
            raise RecordingError(f"{path}: column {i + 1} given for both {used[i]} and {role}")
        used[i] = role
    if names is not None:
        for role, i in roles.items():
            kind = {"t": "time", "temp": "temperature", "pose": None}.get(role, "acceleration")
            if kind:
                base, u = unit_in_name(names[i].strip(), kind)
                if role == "t" and u is None:
                    u = _TIME_UNIT_BY_NAME.get(_norm(base))
                if u is not None:
                    units.setdefault(role, u)
                    if role in ("ax", "ay", "az"):
                        units.setdefault("acc_units", {})[role] = u
    return roles, units


def _find_roles(names, roles: dict, path) -> None:
    """Fill ``roles`` (in place) from the header by the aliases, for roles not given."""
    cand = {r: [] for r in ROLES}
    for i, n in enumerate(names):
        if i in roles.values():
            continue
        for kind in ("acceleration", "time", "temperature"):
            base, _ = unit_in_name(n, kind)
            key = _norm(base)
            m = _ACC.match(key) or _ACC_AXIS_FIRST.match(key)
            if kind == "acceleration" and m:
                cand["a" + m.group("axis")].append(i)
            elif kind == "time" and (key in _TIME or key in _TIME_UNIT_BY_NAME):
                cand["t"].append(i)
            elif kind == "temperature" and key in _TEMP:
                cand["temp"].append(i)
        if _norm(n) in _POSE:
            cand["pose"].append(i)
    if not any(cand[a] for a in ("ax", "ay", "az")) and not any(r in roles for r in ("ax", "ay", "az")):
        for i, n in enumerate(names):  # plain x, y, z columns (FastAhrs 'x, y, z')
            if _norm(n) in ("x", "y", "z") and i not in roles.values():
                cand["a" + _norm(n)].append(i)
    for role, hits in cand.items():
        hits = sorted(set(hits))
        if role in roles or not hits:
            continue
        if role == "t" and len(hits) > 1 and {_norm(names[i]) for i in hits} == {"%time", "fieldheaderstamp"}:
            # rostopic echo -p: %time is when the message was received, the header stamp
            # when the sensor sampled it
            hits = [i for i in hits if _norm(names[i]) == "fieldheaderstamp"]
        if len(hits) > 1:
            raise RecordingError(f"{path}: {len(hits)} columns could be {role} ({', '.join(names[i] for i in hits)}); "
                                 f"choose one with --columns {role}=NAME")
        roles[role] = hits[0]


def _numbers(values, dc: bool, path, role: str, names, col: int, lines) -> np.ndarray:
    """Strict float conversion of one column; the first bad value is reported with its line."""
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
    nonfinite = ~np.isfinite(out)
    if nonfinite.any():
        i = int(np.flatnonzero(nonfinite)[0])
        raise RecordingError(f"{path}: {label}: non-finite value {s[i]!r} at line {lines[i]}")
    return out


def _convert_acc(acc, u: str, how: str):
    if u in ("g", "mg"):
        f = G0 if u == "g" else G0 * 1e-3
        return acc * f, f"unit: {u} ({how}), converted to m/s^2 with standard gravity {G0} m/s^2 per g"
    return acc, f"unit: {u} ({how})"


def _acceleration_unit(acc, units: dict, unit: str | None, path):
    """Acceleration in m/s² or counts, its unit name, and a note saying where the unit came from."""
    header = units.get("acc_units", {})
    if unit is not None:
        u, how = acceleration_unit(unit), "--unit"
        if header and set(header.values()) != {u}:
            how = f"--unit, overriding the header's {'/'.join(sorted(set(header.values())))}"
    elif header:
        if len(header) < 3 and set(header.values()) != {"counts"}:
            pass
        if len(set(header.values())) > 1:
            raise RecordingError(f"{path}: the acceleration columns are in different units "
                                 f"({', '.join(f'{r}: {v}' for r, v in sorted(header.items()))}); "
                                 "convert them to one unit or pass --unit")
        u, how = next(iter(header.values())), "from the header"
    else:
        return _infer(acc, path)
    acc, note = _convert_acc(acc, u, how)
    return acc, "counts" if u == "counts" else "m/s^2", note


def _infer(acc, path):
    norm = float(np.median(np.linalg.norm(acc, axis=1)))
    integer = bool(np.all(acc == np.round(acc)))
    if 0.3 <= norm <= 3.0:
        u = "g"
    elif 3.0 < norm <= 30.0:
        u = "m/s^2"
    elif 300.0 <= norm <= 3000.0 and not integer:
        u = "mg"
    else:
        u = "counts"
    acc, note = _convert_acc(acc, u, f"inferred from the median |a| = {norm:.4g}; pass --unit if wrong")
    return acc, "counts" if u == "counts" else "m/s^2", note


def _infer_unit(rec: Recording) -> Recording:
    acc, u, note = _infer(rec.acc, rec.source)
    return replace(rec, acc=acc, unit=u, notes=rec.notes + (note,))


# --------------------------------------------------------------------------- time


_RATE_KEYS = {"fs", "rate", "samplerate", "samplingrate", "samplingfrequency", "frequency", "hz", "odr",
              "samplingratehz", "ratehz", "fshz"}


def _preamble_rate(preamble) -> tuple[float | None, str]:
    for no, r in preamble:
        if len(r) >= 2 and _norm(r[0]) in _RATE_KEYS:
            try:
                fs = float(r[1].replace(",", "."))
            except ValueError:
                continue
            if np.isfinite(fs) and fs > 0:
                return fs, f"t = sample index / {fs:g} Hz (rate from the line {no} '{r[0]}')"
    return None, ""


def _time(values, rate, tu, header_unit, names, roles, dc, path, lines, preamble):
    """Time [s] from the first sample, and a note on how it was obtained."""
    n = len(lines)
    if rate is not None:
        ignored = " (time column ignored)" if values is not None else ""
        return np.arange(n) / rate, f"t = sample index / {rate:g} Hz (--rate){ignored}"
    if values is None:
        fs, note = _preamble_rate(preamble)
        if fs is None:
            found = ", ".join(names)[:150] if names is not None else "none"
            raise RecordingError(f"{path}: no time column (found: {found}); pass --rate HZ to time the samples "
                                 "by their index, or --columns t=NAME")
        return np.arange(n) / fs, note
    s = np.char.strip(values.astype(str))
    label = f"time (column {names[roles['t']].strip()!r})" if names is not None else "time"
    numeric = np.array([bool(_NUMBER.match(v) or (dc and _DECIMAL_COMMA.match(v))) for v in s[:1000]])
    if not numeric.all():
        return _datetime_time(s, path, label, lines)
    if dc:
        s = np.char.replace(s, ",", ".")
    integer = all(re.fullmatch(r"[+-]?\d+", v) for v in s[:1000]) and all(re.fullmatch(r"[+-]?\d+", v) for v in s)
    if integer and all(len(v.lstrip("+-")) < 19 for v in s):
        ti = s.astype(np.int64)
        rel = (ti - ti[0]).astype(float)  # exact in int64, then float: epoch ns keep their digits
        x = ti.astype(float)
        t0 = float(ti[0])
    else:
        x = _numbers(values, dc, path, "t", names, roles["t"], lines)
        t0 = float(x[0])
        rel = x - x[0]
    _check_increasing(rel, path, label, lines)
    if tu is not None:
        unit, how = time_unit(tu), "--time-unit"
    elif header_unit is not None:
        unit, how = header_unit, "from the header"
    else:
        unit, how = _infer_time_unit(rel, t0, integer)
    f = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[unit]
    epoch = abs(t0) * f >= 1e6  # clock or epoch time: seconds from the first sample keep the digits
    t = rel * f if epoch else x * f
    rate_hz = 1.0 / float(np.median(np.diff(t)))
    note = f"time unit: {unit} ({how}): {rate_hz:.4g} Hz over {t[-1] - t[0]:.4g} s"
    if how.startswith("inferred") or not 1.0 <= rate_hz <= 20000.0:
        note += "; pass --time-unit if wrong"
    if epoch:
        note += f"; counted from the first sample (t0 = {t0:.17g} {unit})"
    return t, note


def _infer_time_unit(rel, t0: float, integer: bool) -> tuple[str, str]:
    """The time unit from the values: epoch magnitude first, else the sampling rate."""
    factors = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
    if abs(t0) >= 1e8:  # an epoch time stamp: its magnitude names the unit (years 1973-2286)
        for u, f in factors.items():
            if 1e8 <= abs(t0) * f < 1e10:
                return u, f"inferred from the epoch time stamp {t0:.6g}"
    dt = float(np.median(np.diff(rel)))
    cands = ("ms", "us", "ns", "s") if integer else ("s", "ms")
    best = min(cands, key=lambda u: abs(np.log10(1.0 / (dt * factors[u]) / TYPICAL_RATE_HZ)))
    why = "integer steps" if integer else "fractional values"
    return best, f"inferred: {why} of median {dt:.4g} give {1 / (dt * factors[best]):.4g} Hz in {best}"


def _datetime_time(s, path, label, lines):
    import pandas as pd

    try:
        ts = pd.to_datetime(pd.Series(s), format="ISO8601", utc=True)
    except (ValueError, TypeError):
        ts = None
    if ts is None or ts.isna().any():
        bad = 0 if ts is None else int(np.flatnonzero(ts.isna().to_numpy())[0])
        if ts is None:
            for i, v in enumerate(s):
                try:
                    pd.to_datetime(v, format="ISO8601")
                except (ValueError, TypeError):
                    bad = i
                    break
        raise RecordingError(f"{path}: {label}: {s[bad][:30]!r} at line {lines[bad]} is neither a number nor an "
                             "ISO 8601 date-time; pass --rate HZ to time the samples by their index")
    ns = ts.dt.tz_localize(None).to_numpy().astype("datetime64[ns]").astype(np.int64)
    t = (ns - ns[0]).astype(float) * 1e-9
    _check_increasing(t, path, label, lines)
    rate_hz = 1.0 / float(np.median(np.diff(t)))
    return t, (f"time: ISO 8601 date-times from {ts.iloc[0].isoformat()} (UTC): {rate_hz:.4g} Hz, {t[-1]:.4g} s")


def _check_increasing(t, path, label, lines):
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        what = "repeats" if d[bad[0]] == 0 else "goes back"
        hint = ("time stamps coarser than the sampling? pass --rate HZ to time the samples by their index"
                if d[bad[0]] == 0 else "rows out of order or two recordings joined; sort or split the file")
        raise RecordingError(f"{path}: {label} {what} at line {lines[i]} ({int(bad.size)} such step(s)); {hint}")


# --------------------------------------------------------------------------- known intervals


def read_intervals(path, rec: Recording) -> Recording:
    """``rec`` with the known static intervals of a file (replacing any it had).

    Accepted files:

    * an imucal section list (JSON ``{name: {"start": i, "end": j}}``, sample indices,
      end exclusive): every section whose name does not end in ``_rot`` (imucal's
      rotations);
    * JSON ``[[start, end], ...]`` or ``{"intervals": [...]}``: times [s] from the
      recording's start;
    * a CSV with columns ``start``, ``end`` (times [s] from the recording's start, or
      sample indices if the header says ``start_index``/``start_sample``) and an
      optional ``label``.

    A time interval covers the samples with ``start <= t <= end``.
    """
    import json

    path = Path(path)
    text, _ = load_text(path)
    stripped = text.lstrip()
    spans, labels, kind = [], [], ""
    if stripped.startswith("{") and '"start"' in stripped:
        sections = read_imucal_section_list(path)
        for name, (a, b) in sections.items():
            if not name.endswith("_rot"):
                spans.append((a, b))
                labels.append(name)
        kind = "imucal section list (samples; *_rot sections left out)"
        idx = spans
    elif stripped.startswith(("[", "{")):
        try:
            obj = json.loads(text)
        except json.JSONDecodeError as e:
            raise RecordingError(f"{path}: not valid JSON ({' '.join(str(e).split())})") from None
        items = obj.get("intervals") if isinstance(obj, dict) else obj
        if not isinstance(items, list) or not all(isinstance(x, (list, tuple)) and len(x) == 2 for x in items):
            raise RecordingError(f"{path}: expected [[start, end], ...] in seconds or an imucal section list")
        try:
            spans = [(float(a), float(b)) for a, b in items]
        except (TypeError, ValueError):
            raise RecordingError(f"{path}: interval bounds must be numbers (seconds)") from None
        labels = [f"pose{k:02d}" for k in range(len(spans))]
        idx, kind = _time_spans_to_samples(spans, rec, path), "JSON list of [start, end] in s"
    else:
        tab = _interval_table(text, path)
        idx, labels, kind = tab(rec)
    if not idx:
        raise RecordingError(f"{path}: no static interval in the file")
    order = np.argsort([a for a, _ in idx], kind="stable")
    idx = [idx[i] for i in order]
    labels = [labels[i] for i in order]
    for a, b in idx:
        if not (0 <= a < b <= rec.n):
            raise RecordingError(f"{path}: interval {a}-{b} (samples) lies outside the recording's {rec.n} samples; "
                                 "are the bounds in seconds from the start of the recording?")
    rec = replace(rec, intervals=np.array(idx), labels=tuple(labels),
                  notes=rec.notes + (f"{len(idx)} known static intervals from {path.name} ({kind})",))
    return rec


def _time_spans_to_samples(spans, rec: Recording, path):
    out = []
    for a, b in spans:
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise RecordingError(f"{path}: interval ({a:g}, {b:g}) is not a range of times")
        i = int(np.searchsorted(rec.t, a, side="left"))
        j = int(np.searchsorted(rec.t, b, side="right"))
        if j - i < 2:
            raise RecordingError(f"{path}: interval {a:g}-{b:g} s holds fewer than 2 samples of the recording "
                                 f"(which lasts {rec.t[-1]:.4g} s)")
        out.append((i, j))
    return out


def _interval_table(text: str, path):
    lines = [ln for ln in text.splitlines() if ln.strip() and not _is_comment(ln)]
    delim = next((d for d in ("\t", ";", ",") if d in lines[0]), " ")
    head = [_norm(c) for c in _split(lines[0], delim)]
    col = {h: i for i, h in enumerate(head)}
    start = next((h for h in ("start", "starts", "startindex", "startsample", "tstart", "begin", "from") if h in col),
                 None)
    end = next((h for h in ("end", "stop", "endindex", "endsample", "stopindex", "tend", "tstop", "to") if h in col),
               None)
    if start is None or end is None:
        raise RecordingError(f"{path}: an interval file needs a header with start and end columns "
                             "(seconds, or start_index/end_index in samples)")
    samples = "index" in start or "sample" in start
    lab = next((h for h in ("label", "name", "pose", "section") if h in col), None)
    rows = [_split(ln, delim) for ln in lines[1:]]
    try:
        vals = [(float(r[col[start]]), float(r[col[end]])) for r in rows]
    except (ValueError, IndexError):
        raise RecordingError(f"{path}: every interval row needs numeric start and end") from None
    labels = [r[col[lab]] if lab is not None and len(r) > col[lab] else f"pose{k:02d}" for k, r in enumerate(rows)]

    def convert(rec):
        if samples:
            if any(a != int(a) or b != int(b) for a, b in vals):
                raise RecordingError(f"{path}: sample indices must be integers")
            return [(int(a), int(b)) for a, b in vals], labels, "CSV of sample ranges (end exclusive)"
        return _time_spans_to_samples(vals, rec, path), labels, "CSV of times in s"

    return convert


__all__ = ["ALIASES", "FORMATS", "ROLES", "detect_format", "load_text", "parse_columns", "read", "read_intervals",
           "read_table", "sniff"]
