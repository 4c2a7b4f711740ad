"""Any delimited text table (the ``csv`` format): delimiter, header and columns found.

Comma, semicolon, tab, ``|`` or whitespace, decimal point or decimal comma,
``#``/``%``/``//`` comment lines, metadata lines above the header, gzip-compressed or
not.  Columns are found by their usual names (``t``, ``time``, ``timestamp``, ``acc_x``,
``accX``, ``AX``, ``Accel. X``, ``linear_acceleration.x`` ...; a gyroscope's ``gx``,
``gyr_x``, ``wx``, ``Gyro. X``, ``angular_velocity.x`` ...; :data:`ALIASES`) or given
with ``columns=``.  The header may be written as a comment line just above the data
(``# time tx ty tz wx wy wz ...``, ``%time,field.header.stamp,...``).  A headerless
table of 4 numbers per row is IMU-TK's layout (t, x, y, z).  Units and time are inferred
when the file does not say (:mod:`.inference`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import RecordingError
from ..recording import MIN_ROWS, Recording, intervals_from_labels
from ..units import to_celsius, unit_in_name
from .clock import clocked_time, is_counter_name, looks_like_counter
from .inference import resolve_acceleration_unit, resolve_gyro_unit, time_seconds
from .magnetic import MAG_ROLES, mag_axis, mag_unit_in_name, resolve_mag_unit
from .numeric_block import Body, TextColumn, parse_block
from .parsing import DECIMAL_COMMA, NUMBER, norm_name, parse_numbers, split_fields
from .text import COMMENT_MARKERS, is_comment, load_text

ROLES = ("t", "ax", "ay", "az", "gx", "gy", "gz", "mx", "my", "mz", "temp", "pose", "counter")
ACC_ROLES, GYRO_ROLES = ("ax", "ay", "az"), ("gx", "gy", "gz")
#: Delimiters tried, in order of preference when two fit equally well.
DELIMITERS = ("\t", ";", ",", "|", " ")

#: Column names (lower case, without unit, separators removed) for each role.
_ACC = re.compile(r"^(?:field)?(?:imu)?(?:linear)?(?:acc|accel|accl|acceleration|accelerometer|acceleromter|a)"
                  r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_ACC_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:acc|accel|acceleration|a)$")
_GYRO = re.compile(r"^(?:field)?(?:imu)?(?:g|gyr|gyro|gyroscope|w|omega|angularvelocity|angvel|angularrate|rate)"
                   r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_GYRO_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:gyr|gyro|g|w)$")
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
    "gx, gy, gz": "gx, gyr_x, gyro_x, gyroX, Gyro. X, wx, omega_x, angular_velocity.x (optional: the "
                  "gyroscope)",
    "mx, my, mz": "mx, mag_x, magX, Mag. X, magnetometer_x, compass_x, magnetic_field.x (optional: the "
                  "magnetometer; units uT, T, mT, nT, gauss, mG or counts)",
    "temp": "temp, temperature, imu_temp, die_temp",
    "pose": "pose, pose_id (label of the known static pose of each sample; empty between poses)",
    "counter": "INDEX, seq, counter, sample, n_samples, field.header.seq ... (a sample counter: the clock's "
               "sample numbers, accelcal.formats.clock)",
}


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


def _numeric_share(rows, decimal_comma: bool) -> float:
    cells = [c for r in rows for c in r]
    if not cells:
        return 0.0
    pat = DECIMAL_COMMA if decimal_comma else NUMBER
    return sum(1 for c in cells if NUMBER.match(c) or pat.match(c)) / len(cells)


def sniff(lines: list[str]) -> tuple[str, bool, int]:
    """Delimiter, decimal comma and field count of the data rows (the last lines).

    The delimiter that splits the last (up to 200) content lines into the same number of
    fields (at least 3) with the largest share of numbers wins; a decimal comma is
    recognised when the delimiter is not a comma and fields look like ``9,81``.
    """
    tail = lines[-200:]
    best = None
    for order, delim in enumerate(DELIMITERS):
        rows = [split_fields(ln, delim) for ln in tail]
        rows = [r[:-1] if r and r[-1] == "" and len(r) > 1 else r for r in rows]  # trailing delimiter
        counts = np.bincount([len(r) for r in rows])
        k = int(np.argmax(counts))
        if k < 3:
            continue
        consistent = counts[k] / len(rows)
        same = [r for r in rows if len(r) == k]
        dc = delim != "," and any(DECIMAL_COMMA.match(c) for r in same[:50] for c in r)
        score = consistent * _numeric_share(same, dc)
        if best is None or score > best[0] + 1e-9:
            best = (score, delim, dc, k, order)
    if best is None or best[0] < 0.3:
        widest = max((len(split_fields(ln, d)), d) for d in DELIMITERS for ln in tail[:1])
        first = ", ".join(split_fields(lines[0], widest[1]))[:80] if widest[0] > 1 else lines[0][:60]
        raise RecordingError(f"no table of 3 or more columns found (first line: {first!r}); a recording needs "
                             "three acceleration columns (and time): name them with --columns t=..,ax=..,ay=..,az=..")
    return best[1], best[2], best[3]


class _Table(NamedTuple):
    """The rows of a table: header names (or None), data rows, their file line numbers, the
    lines above the header (line number, fields), delimiter, decimal comma, field count;
    a plain numeric table (:func:`_fast_table`) has ``block`` (its floats) and its data
    lines in ``raw`` instead of ``data``, and ``lines`` a range."""

    names: list[str] | None
    data: list[list[str]] | None
    lines: Sequence[int]
    preamble: list[tuple[int, list[str]]]
    delim: str
    dc: bool
    k: int
    block: np.ndarray | None = None
    raw: Body | None = None

    def column(self, i: int) -> np.ndarray | TextColumn:
        """The strings of column ``i`` (an object or str array, or a :class:`.TextColumn`
        that cuts them out of the text when asked)."""
        if self.data is not None:
            return np.asarray([r[i] for r in self.data], dtype=object)
        if self.raw is None:  # a matrix (read_matrix): its numbers as text
            return np.asarray([repr(float(v)) for v in self.block[:, i]], dtype=object)
        return TextColumn(self.raw, i, self.delim, self.k, len(self.block))


def read_table(path, *, text: str | None = None, columns=None, unit: str | None = None,
               time_unit: str | None = None, rate: float | None = None, gyro_unit: str | None = None,
               clock: str = "auto", mag_unit: str | None = None) -> Recording:
    """Read a delimited text table (the ``csv`` format; see the module docstring).

    ``gyro_unit`` (``rad/s``, ``deg/s``, ``counts``) is the unit of the gyro columns, if
    any (default: the header's, else inferred from the values).  ``clock``: ``'auto'``
    times the samples by the sensor's clock fitted to the time stamps against the sample
    counter (or the row index), ``'stamps'`` by the stamps as they are
    (:mod:`accelcal.formats.clock`).

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
    return _table_recording(_split_table(text, path), path, notes, columns, unit, time_unit, rate, gyro_unit,
                            clock=clock, mag_unit=mag_unit)


def read_matrix(path, names, block: np.ndarray, *, notes=(), columns=None, unit: str | None = None,
                time_unit: str | None = None, rate: float | None = None, gyro_unit: str | None = None,
                file_rate: tuple[float, str] | None = None) -> Recording:
    """A recording from a numeric matrix (a variable of a ``.mat`` or ``.rda`` file), its
    columns found as a table's: by ``names`` (column names, or None: numbered as in a
    headerless table) or by ``columns=``.  ``file_rate`` (Hz, where the file states it)
    times the samples when the matrix has no time column and ``rate`` is not given."""
    block = np.asarray(block, dtype=float)
    if block.ndim != 2 or len(block) < MIN_ROWS:
        raise RecordingError(f"{path}: only {len(block)} rows; need at least {MIN_ROWS}")
    tab = _Table(None if names is None else [str(n) for n in names], None, range(1, len(block) + 1), [], ",", False,
                 block.shape[1], block, None)
    return _table_recording(tab, Path(path), list(notes), columns, unit, time_unit, rate, gyro_unit, file_rate)


def _table_recording(tab, path, notes, columns, unit, time_unit, rate, gyro_unit, file_rate=None, *,
                     clock: str = "auto", mag_unit: str | None = None) -> Recording:
    """The recording of a split table (:func:`read_table`'s second half)."""
    names, dc, lines = tab.names, tab.dc, tab.lines
    what = {"\t": "tab", ";": "semicolon", ",": "comma", "|": "'|'", " ": "whitespace"}[tab.delim]
    if tab.delim != "," or dc:
        notes.append(f"{what}-separated" + (", decimal comma" if dc else ""))
    roles, units = _map_columns(names, tab.k, parse_columns(columns), path)
    if names is None:
        notes.append("no header: columns read as " + ", ".join(
            f"{r}=column {i + 1}" for r, i in roles.items()) + " (pass --columns to change)")
    block = _numeric_block(tab)
    strings = {}

    def column(role):
        if role not in strings:
            strings[role] = tab.column(roles[role])
        return strings[role]

    def parsed(role):  # the column's floats when the whole table converted (else parse_numbers names the bad value)
        return block[:, roles[role]] if block is not None and np.all(np.isfinite(block[:, roles[role]])) else None

    def numbers(role):
        x = parsed(role)
        return x if x is not None else parse_numbers(column(role), dc, path, role, names, roles[role], lines)

    def triad(axes):
        return np.column_stack([numbers(a) for a in axes])

    acc, unit_name = None, None
    if "ax" in roles:
        acc, unit_name, note = resolve_acceleration_unit(triad(ACC_ROLES), units, unit, path)
        notes.append(note)
    elif unit is not None:
        raise RecordingError(f"{path}: --unit {unit} given, but the table has no acceleration columns (gyro only)")
    gyro, gyro_unit_name = None, None
    notes.append(units.get("gyro_note", ""))
    if "gx" in roles:
        gyro, gyro_unit_name, note = resolve_gyro_unit(triad(GYRO_ROLES), units, gyro_unit, path)
        notes.append(note)
    mag, mag_unit_name = None, None
    if "mx" in roles:
        mag, mag_unit_name, note = resolve_mag_unit(triad(MAG_ROLES), units.get("mag_units", {}), mag_unit, path)
        notes.append(note)
    if "t" not in roles and rate is None and file_rate is not None:
        t, tnote = np.arange(len(lines)) / file_rate[0], f"t = sample index / {file_rate[0]:g} Hz ({file_rate[1]})"
    else:
        t, tnote = time_seconds(column("t") if "t" in roles else None, rate, time_unit, units.get("t"), names, roles,
                                dc, path, lines, tab.preamble, parsed=parsed("t") if "t" in roles else None,
                                counter=_counter_label(names, roles))
    t, cnotes = _sensor_clock(t, tnote, numbers, names, roles, units, clock, rate, lines, path)
    notes += cnotes
    temp = None
    if "temp" in roles:
        temp = numbers("temp")
        if units.get("temp") in ("K", "degF"):
            temp = to_celsius(temp, units["temp"])
            notes.append(f"temperature converted from {units['temp']} to degC")
    iv, labels = (intervals_from_labels(column("pose").astype(str)) if "pose" in roles else (None, None))
    time_column = None
    if "t" in roles and rate is None:
        written = column("t")  # a TextColumn stays one: cut out of the text if apply asks for it
        time_column = (names[roles["t"]].strip() if names is not None else "t",
                       written if isinstance(written, TextColumn) else written.astype(str))
    return Recording(t, acc, temp, str(path), intervals=iv, labels=labels, notes=tuple(n for n in notes if n),
                     unit=unit_name, time_column=time_column, gyro=gyro, gyro_unit=gyro_unit_name,
                     mag=mag, mag_unit=mag_unit_name)


def _counter_label(names, roles) -> str | None:
    if "counter" not in roles:
        return None
    return f"counter {names[roles['counter']].strip()!r}" if names is not None else "the counter"


def _sensor_clock(t, tnote, numbers, names, roles, units, clock, rate, lines, path):
    """The times from the sensor's clock (:func:`accelcal.formats.clock.clocked_time`) and the notes."""
    counter = None
    if "counter" in roles:
        counter = numbers("counter")
        if not looks_like_counter(counter) and not units.get("counter_given"):
            name = names[roles["counter"]].strip()
            return t, [tnote, f"column {name!r} is not a sample counter (not integers going up): not used as one"]
    name = names[roles["counter"]].strip() if "counter" in roles and names is not None else "counter"
    timed_by_rate = "t" not in roles or rate is not None
    t_new, notes = clocked_time(t, counter, counter_name=name, mode=clock, timed_by_rate=timed_by_rate,
                                where=lambda i: f"line {lines[i]}", path=path)
    if notes and not timed_by_rate and clock != "stamps":
        tnote = re.sub(r": [0-9.e+-]+ Hz over ", ", ", tnote)  # the clock's note states the rate
    return t_new, [tnote, *notes]


def _numeric_block(tab: _Table):
    """Every data field as a float, in one conversion (a third of the time of column by
    column), or None when a field is not a plain number (text, empty, decimal comma): the
    columns are then converted one by one, which names the first bad value and its line."""
    if tab.block is not None:
        return tab.block
    if tab.dc:
        return None
    try:
        return np.array(tab.data, dtype=float)
    except ValueError:
        return None


def _split_table(text: str, path) -> _Table:
    """Delimiter, header and data rows of the text (comments and blank lines skipped): a
    plain numeric table by a compiled parser (:func:`_fast_table`), anything else line by
    line (:func:`_general_table`), which names what is wrong."""
    fast = _fast_table(text)
    return fast if fast is not None else _general_table(text, path)


def _general_table(text: str, path) -> _Table:
    """:func:`_split_table` field by field: every line split in Python (seconds for 10⁶ lines)."""
    all_lines = text.splitlines()
    # is_comment inlined: this runs once per line of files of 10^5 lines
    numbered = [(no, ln) for no, ln in enumerate(all_lines, start=1)
                if (s := ln.lstrip()) and not s.startswith(COMMENT_MARKERS)]
    if not numbered:
        raise RecordingError(f"{path}: only comments and blank lines, no data")
    try:
        delim, dc, k = sniff([ln for _, ln in numbered])
    except RecordingError as e:
        raise RecordingError(f"{path}: {e}") from None
    rows = _split_rows([ln for _, ln in numbered], delim, k)
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
    return _Table(rows[header] if header is not None else None, data, lines, preamble, delim, dc, k)


def _split_rows(lines: list[str], delim: str, k: int) -> list[list[str]]:
    """The stripped fields of each line; a trailing empty field after ``k`` fields dropped."""
    if delim == " ":
        rows = [ln.split() for ln in lines]
    else:
        rows = [[f.strip() for f in ln.split(delim)] for ln in lines]
    for i, r in enumerate(rows):
        if len(r) == k + 1 and r[-1] == "":
            rows[i] = r[:-1]
    return rows


#: Lines at the top of a file in which :func:`_fast_table` looks for the header and the first
#: data row (a preamble longer than this goes the general way).
_HEAD_LINES = 256
#: Content lines at the end of a file that :func:`sniff` reads.
_SNIFF_LINES = 200


def _fast_table(text: str) -> _Table | None:
    """A plain numeric table, its structure found as :func:`_general_table` finds it but from
    the first lines and the last :data:`_SNIFF_LINES` content lines only, its data parsed by a
    compiled parser (:func:`.numeric_block.parse_block`): the same names, rows, line numbers and numbers.
    None for anything else (decimal commas, text or empty fields, comment or blank lines
    inside the data, ragged rows, too few rows, a long preamble, any error): the general route
    then reads it and names what is wrong."""
    cut = _after_lines(text, _HEAD_LINES)
    head = text[:cut].splitlines(keepends=True)
    head_lines = text[:cut].splitlines()
    numbered = [(no, ln) for no, ln in enumerate(head_lines, start=1)
                if (s := ln.lstrip()) and not s.startswith(COMMENT_MARKERS)]
    if not numbered:
        return None
    sample = [ln for _, ln in numbered] if cut == len(text) else _sniff_sample(text, numbered[0][1])
    try:
        delim, dc, k = sniff(sample)
        rows = _split_rows([ln for _, ln in numbered], delim, k)
        header, first = _find_header(rows, k, dc)
    except RecordingError:
        return None
    if dc:
        return None
    if header is None and first == 0:
        rows, numbered, header = _comment_header(head_lines, numbered, rows, delim, k)
        first = 1 if header is not None else 0
    if first >= len(numbered):
        return None
    start_line = numbered[first][0]
    parsed = parse_block(text, sum(len(ln) for ln in head[:start_line - 1]), delim, k)
    if parsed is None or len(parsed[0]) < MIN_ROWS:
        return None
    block, body = parsed
    preamble = [(numbered[i][0], rows[i]) for i in range(first if header is None else header)]
    return _Table(rows[header] if header is not None else None, None, range(start_line, start_line + len(block)),
                  preamble, delim, dc, k, block, body)


def _after_lines(text: str, n: int) -> int:
    """The offset just after the ``n``-th newline of ``text`` (its length if it has fewer)."""
    pos = 0
    for _ in range(n):
        pos = text.find("\n", pos) + 1
        if pos == 0:
            return len(text)
    return pos


def _sniff_sample(text: str, first: str) -> list[str]:
    """What :func:`sniff` reads of all the content lines of ``text`` (the first and the last
    :data:`_SNIFF_LINES`), from a tail of the text grown until it holds them."""
    size = 1 << 14
    while True:
        start = max(0, len(text) - size)
        lines = text[start:].splitlines()[1 if start else 0:]  # the first may be cut
        content = [ln for ln in lines if (s := ln.lstrip()) and not s.startswith(COMMENT_MARKERS)]
        if start == 0:
            return content
        if len(content) >= _SNIFF_LINES:
            return [first] + content[-_SNIFF_LINES:]
        size *= 4


def _comment_header(all_lines, numbered, rows, delim, k):
    """The comment line just above the data as the header, if it has the data's field
    count and names: as written (``%time,field.header.seq,...`` of ``rostopic echo -p``)
    or without its comment marker (``# time tx ty tz wx wy wz ...``)."""
    above = numbered[0][0] - 1  # 1-based line number of the line above the first data row
    if above < 1 or not is_comment(all_lines[above - 1]):
        return rows, numbered, None
    line = all_lines[above - 1].strip()
    bare = next(line[len(m):].strip() for m in COMMENT_MARKERS if line.startswith(m))
    for text in (line, bare):
        cand = split_fields(text, delim)
        if len(cand) == k and all(c and not NUMBER.match(c) for c in cand):
            return [cand] + rows, [(above, all_lines[above - 1])] + numbered, 0
    return rows, numbered, None


def _find_header(rows, k: int, dc: bool) -> tuple[int | None, int]:
    """(header row index or None, first data row index).

    Data start at the first row of ``k`` fields from which on every row has ``k`` fields
    (or, for a damaged file, the first row of ``k`` mostly numeric fields); the header is
    the row just before it if it has ``k`` fields and is not mostly numeric.
    """
    def numeric(r):
        return sum(1 for c in r if NUMBER.match(c) or (dc and DECIMAL_COMMA.match(c))) >= max(2, len(r) // 2)

    first = next((i for i, r in enumerate(rows) if len(r) == k and numeric(r)), None)
    if first is None:
        raise RecordingError("no data rows found")
    if first > 0 and len(rows[first - 1]) == k and not numeric(rows[first - 1]):
        return first - 1, first
    return None, first


def _map_columns(names, k: int, given: dict, path, required=ACC_ROLES) -> tuple[dict, dict]:
    """``{role: column index}`` and ``{role: unit found in the header}``; the ``required``
    roles must be found."""
    roles, units = {}, {}
    if names is None:
        if any(isinstance(v, str) for v in given.values()):
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
    if "counter" in given:
        units["counter_given"] = True
    found = ", ".join(n.strip() for n in names)[:150] if names is not None else f"{k} unnamed columns"
    missing = [r for r in required if r not in roles]
    if missing and required == ACC_ROLES and not any(r in roles for r in ACC_ROLES) and \
            all(r in roles for r in GYRO_ROLES):
        missing = []  # a gyro-only table (rate-table rotations): the gyro columns named, no accelerometer
    if missing:
        raise RecordingError(f"{path}: no column for {', '.join(missing)} (found: {found}); "
                             "name them with --columns t=TIME,ax=X,ay=Y,az=Z (a gyro alone: gx=..,gy=..,gz=..)")
    gyro = [r for r in GYRO_ROLES if r in roles]
    if 0 < len(gyro) < 3:
        if any(r in given for r in GYRO_ROLES):
            raise RecordingError(f"{path}: --columns names a gyro column for {', '.join(gyro)} but none for "
                                 f"{', '.join(r for r in GYRO_ROLES if r not in roles)}: name all three "
                                 "(gx=..,gy=..,gz=..)")
        which = ", ".join(names[roles[r]].strip() for r in gyro)
        units["gyro_note"] = (f"gyro: a column for {', '.join(gyro)} only ({which}): not read (name all three with "
                              "--columns gx=..,gy=..,gz=..)")
        for r in gyro:
            del roles[r]
    mag = [r for r in MAG_ROLES if r in roles]
    if 0 < len(mag) < 3:
        if any(r in given for r in MAG_ROLES):
            raise RecordingError(f"{path}: --columns names a magnetometer column for {', '.join(mag)} only: name "
                                 "all three (mx=..,my=..,mz=..)")
        for r in mag:
            del roles[r]
    used = {}
    for role, i in roles.items():
        if i in used:
            raise RecordingError(f"{path}: column {i + 1} given for both {used[i]} and {role}")
        used[i] = role
    if names is not None:
        for role in (r for r in MAG_ROLES if r in roles):
            u = mag_unit_in_name(names[roles[role]].strip())[1]
            if u is not None:
                units.setdefault("mag_units", {})[role] = u
        for role, i in roles.items():
            if role in MAG_ROLES:
                continue
            kind = {"t": "time", "temp": "temperature", "pose": None, "counter": None}.get(
                role, "angular_rate" if role in GYRO_ROLES else "acceleration")
            if kind:
                base, u = unit_in_name(names[i].strip(), kind)
                if role == "t" and u is None:
                    u = _TIME_UNIT_BY_NAME.get(norm_name(base))
                if u is not None:
                    units.setdefault(role, u)
                    if role in ACC_ROLES:
                        units.setdefault("acc_units", {})[role] = u
                    if role in GYRO_ROLES:
                        units.setdefault("gyro_units", {})[role] = u
    return roles, units


def _find_roles(names, roles: dict, path) -> None:
    """Fill ``roles`` (in place) from the header by the aliases, for roles not given."""
    cand = {r: [] for r in ROLES}
    for i, n in enumerate(names):
        if i in roles.values():
            continue
        for kind in ("acceleration", "angular_rate", "time", "temperature"):
            base, _ = unit_in_name(n, kind)
            key = norm_name(base)
            m = _ACC.match(key) or _ACC_AXIS_FIRST.match(key)
            mg = _GYRO.match(key) or _GYRO_AXIS_FIRST.match(key)
            if kind == "acceleration" and m:
                cand["a" + m.group("axis")].append(i)
            elif kind == "angular_rate" and mg:
                cand["g" + mg.group("axis")].append(i)
            elif kind == "time" and (key in _TIME or key in _TIME_UNIT_BY_NAME):
                cand["t"].append(i)
            elif kind == "temperature" and key in _TEMP:
                cand["temp"].append(i)
        axis = mag_axis(norm_name(mag_unit_in_name(n)[0]))
        if axis is not None:
            cand["m" + axis].append(i)
        if norm_name(n) in _POSE:
            cand["pose"].append(i)
        if is_counter_name(n):
            cand["counter"].append(i)
    if not any(cand[a] for a in ("ax", "ay", "az")) and not any(r in roles for r in ("ax", "ay", "az")):
        for i, n in enumerate(names):  # plain x, y, z columns (FastAhrs 'x, y, z')
            if norm_name(n) in ("x", "y", "z") and i not in roles.values():
                cand["a" + norm_name(n)].append(i)
    for role, hits in cand.items():
        hits = sorted(set(hits))
        if role in roles or not hits:
            continue
        if role == "t" and len(hits) > 1 and {norm_name(names[i]) for i in hits} == {"%time", "fieldheaderstamp"}:
            # rostopic echo -p: %time is when the message was received, the header stamp
            # when the sensor sampled it
            hits = [i for i in hits if norm_name(names[i]) == "fieldheaderstamp"]
        if role == "counter":
            hits = hits[:1]  # the first counter; --columns counter=NAME chooses another
        if len(hits) > 1:
            raise RecordingError(f"{path}: {len(hits)} columns could be {role} ({', '.join(names[i] for i in hits)}); "
                                 f"choose one with --columns {role}=NAME")
        roles[role] = hits[0]
