"""Any delimited text table (the ``csv`` format): delimiter, header and columns found.

Comma, semicolon, tab, ``|`` or whitespace, decimal point or decimal comma,
``#``/``%``/``//`` comment lines, metadata lines above the header, gzip-compressed or
not.  Columns are found by their usual names (``t``, ``time``, ``timestamp``, ``acc_x``,
``accX``, ``AX``, ``Accel. X``, ``linear_acceleration.x`` ...; a gyroscope's ``gx``,
``gyr_x``, ``wx``, ``Gyro. X``, ``angular_velocity.x`` ...; :data:`.columns.ALIASES`) or given
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
from ..recording import MIN_ROWS, Origin, Recording, handed_over, intervals_from_labels
from ..units import to_celsius
from .clock import clocked_time, looks_like_counter
from .columns import ACC_ROLES, GYRO_ROLES, map_columns, parse_columns
from .inference import resolve_acceleration_unit, resolve_gyro_unit, time_seconds
from .magnetic import MAG_ROLES, resolve_mag_unit
from .numeric_block import Body, TextColumn, parse_block
from .parsing import DECIMAL_COMMA, NUMBER, parse_numbers, split_fields
from .text import COMMENT_MARKERS, is_comment, load_text

#: Delimiters tried, in order of preference when two fit equally well.
DELIMITERS = ("\t", ";", ",", "|", " ")

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
    a plain numeric table (:func:`_fast_table`) or a matrix (:func:`read_matrix`) has
    ``numbers`` (each column's floats) instead of ``data`` (and the table its data lines in
    ``raw``), and ``lines`` a range."""

    names: list[str] | None
    data: list[list[str]] | None
    lines: Sequence[int]
    preamble: list[tuple[int, list[str]]]
    delim: str
    dc: bool
    k: int
    numbers: list[np.ndarray] | None = None
    raw: Body | None = None

    def column(self, i: int) -> np.ndarray | TextColumn:
        """The strings of column ``i`` (an object or str array, or a :class:`.TextColumn`
        that cuts them out of the text when asked)."""
        if self.data is not None:
            return np.asarray([r[i] for r in self.data], dtype=object)
        if self.raw is None:  # a matrix (read_matrix): its numbers as text
            return np.asarray([repr(float(v)) for v in self.numbers[i]], dtype=object)
        return TextColumn(self.raw, i, self.delim, self.k, len(self.lines))  # a column's floats may be let go


def read_table(path, *, text: str | list | None = None, columns=None, unit: str | None = None,
               time_unit: str | None = None, rate: float | None = None, gyro_unit: str | None = None,
               clock: str = "auto", mag_unit: str | None = None, time_column: bool = True) -> Recording:
    """Read a delimited text table (the ``csv`` format; see the module docstring).

    ``gyro_unit`` (``rad/s``, ``deg/s``, ``counts``) is the unit of the gyro columns, if
    any (default: the header's, else inferred from the values).  ``clock``: ``'auto'``
    times the samples by the sensor's clock fitted to the time stamps against the sample
    counter (or the row index), ``'stamps'`` by the stamps as they are
    (:mod:`accelcal.formats.clock`).  ``time_column=False``: the time column as written is
    not kept, and the text is let go once the time is read (before the clock's fit: a
    10⁶-row table's 47 MB are then no part of the reading's peak memory, where the caller
    holds no reference to it either: :func:`accelcal.formats.read` hands it over as
    ``[text]``, which is emptied).

    Raises
    ------
    RecordingError
        No table, missing or ambiguous columns, bad values (with the line), time that
        does not increase, a unit that cannot be determined consistently.
    """
    path = Path(path)
    notes: list[str] = []
    held = text if isinstance(text, list) else [text]  # handed over (formats.read), or given
    del text  # the split table holds the only reference from here: _table_recording may let it go
    if held[0] is None:
        held[0], notes = load_text(path)
    return _table_recording(_split_table(held.pop(), path), path, notes, columns, unit, time_unit, rate, gyro_unit,
                            clock=clock, mag_unit=mag_unit, time_column=time_column)


def read_matrix(path, names, block: np.ndarray, *, notes=(), columns=None, unit: str | None = None,
                time_unit: str | None = None, rate: float | None = None, gyro_unit: str | None = None,
                file_rate: tuple[float, str] | None = None) -> Recording:
    """A recording from a numeric matrix (a variable of a ``.mat`` or ``.rda`` file), its
    columns found as a table's: by ``names`` (column names, or None: numbered as in a
    headerless table) or by ``columns=``.  ``file_rate`` (Hz, where the file states it)
    times the samples when the matrix has no time column and ``rate`` is not given."""
    block = np.asarray(block, dtype=float)
    if block.ndim != 2:
        raise RecordingError(f"{path}: a numeric variable of {block.ndim} dimensions, not a matrix of one row per sample")
    tab = _Table(None if names is None else [str(n) for n in names], None, range(1, len(block) + 1), [], ",", False,
                 block.shape[1], list(block.T), None)
    return _table_recording(tab, Path(path), list(notes), columns, unit, time_unit, rate, gyro_unit, file_rate,
                            numbered="row")


class _Columns:
    """The columns of a split table by role: strings (cut once), floats (from the table
    parsed at once when the whole table converted, else column by column, which names the
    first bad value and its line)."""

    def __init__(self, tab: _Table, roles: dict, path):
        self.tab, self.roles, self.path = tab, roles, path
        self.floats = numeric_columns(tab)
        self._strings = {}

    def column(self, role):
        if self.tab is None:
            raise RuntimeError("the table's text was let go; its string columns are read before")
        if role not in self._strings:
            self._strings[role] = self.tab.column(self.roles[role])
        return self._strings[role]

    def parsed(self, role):
        """The role's floats from the table parsed at once, or None where its conversion failed."""
        x = None if self.floats is None else self.floats[self.roles[role]]
        return x if x is not None and np.all(np.isfinite(x)) else None

    def numbers(self, role, finite: bool = False):
        x = self.parsed(role)
        if x is not None:
            return x
        tab = self.tab
        return parse_numbers(self.column(role), tab.dc, self.path, role, tab.names, self.roles[role], tab.lines,
                             finite)

    def let_go_of_text(self) -> None:
        """Let go of a plain table's text (its data lines, which the string columns are cut
        from) where every column still to be read has its floats (a bad value's message quotes
        the text: :meth:`numbers`); from here on only floats are read."""
        still = [r for r in self.roles if r not in ("t", "pose")]
        if self.tab.raw is not None and all(self.parsed(r) is not None for r in still):
            self.tab, self._strings = None, {}

    def release(self, role):
        """Let go of the role's floats (read once; a 10⁶-row column is 8 MB); a matrix's are
        kept: they are its columns' text too (:meth:`_Table.column`), and the caller's."""
        if self.floats is not None and role in self.roles and (self.tab is None or self.tab.raw is not None
                                                               or self.tab.data is not None):
            self.floats[self.roles[role]] = None

    def triad(self, axes, finite: bool = False):
        """The three columns as a fresh (n, 3) array; their floats are let go (each role is
        read once: a 10⁶-row table's triad is 24 MB of the reading's peak memory).  ``finite``:
        nan and inf refused here (:func:`.parsing.parse_numbers`)."""
        out = np.column_stack([self.numbers(a, finite) for a in axes])
        for a in axes:
            self.release(a)
        return out


def _table_recording(tab, path, notes, columns, unit, time_unit, rate, gyro_unit, file_rate=None, *,
                     clock: str = "auto", mag_unit: str | None = None, time_column: bool = True,
                     numbered: str = "line") -> Recording:
    """The recording of a split table (:func:`read_table`'s second half).  Its string columns
    (time, pose labels) are read first, so that without ``time_column`` the text is let go
    before the floats' work (units, the clock's fit).  ``numbered``: what ``tab.lines``
    number (a text's lines, a matrix's rows), for the messages of the recording's check."""
    names, lines, dc = tab.names, tab.lines, tab.dc
    what = {"\t": "tab", ";": "semicolon", ",": "comma", "|": "'|'", " ": "whitespace"}[tab.delim]
    if tab.delim != "," or tab.dc:
        notes.append(f"{what}-separated" + (", decimal comma" if tab.dc else ""))
    roles, units = map_columns(names, tab.k, parse_columns(columns), path)
    if names is None:
        notes.append("no header: columns read as " + ", ".join(
            f"{r}=column {i + 1}" for r, i in roles.items()) + " (pass --columns to change)")
    cols, preamble = _Columns(tab, roles, path), tab.preamble
    del tab  # only cols holds the table from here: it may let the text go
    if "t" not in roles and rate is None and file_rate is not None:
        t, tnote = np.arange(len(lines)) / file_rate[0], f"t = sample index / {file_rate[0]:g} Hz ({file_rate[1]})"
    else:
        t, tnote = time_seconds(cols.column("t") if "t" in roles else None, rate, time_unit, units.get("t"), names,
                                roles, dc, path, lines, preamble,
                                parsed=cols.parsed("t") if "t" in roles else None, counter=_counter_label(names, roles))
        cols.release("t")  # t is time_seconds' array now: the column's floats would sit beside the clock's fit
    iv, labels = (intervals_from_labels(cols.column("pose").astype(str)) if "pose" in roles else (None, None))
    written = None
    if "t" in roles and rate is None and time_column:
        written = cols.column("t")  # a TextColumn stays one: cut out of the text if apply asks for it
        written = (names[roles["t"]].strip() if names is not None else "t",
                   written if isinstance(written, TextColumn) else written.astype(str))
    else:
        cols.let_go_of_text()
    sensors = _sensors(cols, units, unit, gyro_unit, mag_unit, notes)
    t, cnotes = _sensor_clock(t, tnote, cols.numbers, names, roles, units, clock, rate, lines, path)
    notes += cnotes
    temp = None
    if "temp" in roles:
        temp = cols.numbers("temp")
        if units.get("temp") in ("K", "degF"):
            temp = to_celsius(temp, units["temp"])
            notes.append(f"temperature converted from {units['temp']} to degC")
    made = {k: handed_over(sensors[k]) for k in ("acc", "gyro", "mag")}  # arrays of ours: kept, not copied
    origin = table_origin(names, roles, lines, numbered, timed="t" in roles and rate is None)
    return Recording(handed_over(t), made["acc"], temp, str(path), intervals=iv, labels=labels,
                     notes=tuple(n for n in notes if n), unit=sensors["unit"], time_column=written,
                     gyro=made["gyro"], gyro_unit=sensors["gyro_unit"], mag=made["mag"],
                     mag_unit=sensors["mag_unit"], origin=origin)


def table_origin(names, roles, lines, numbered: str, timed: bool) -> Origin:
    """Where the table's samples are (its lines) and what its columns are called, for the recording's check."""
    def called(role_names):
        cols = [roles[r] for r in role_names if r in roles]
        if len(cols) != len(role_names):
            return None
        return tuple(f"column {names[c].strip()!r}" if names is not None else f"column {c + 1}" for c in cols)

    fields = {"t": ("t",) if timed else None, "acc": ACC_ROLES, "gyro": GYRO_ROLES}
    named = {f: called(r) for f, r in fields.items() if r is not None}
    return Origin(numbered, numbers=lines if isinstance(lines, range) else np.asarray(lines, dtype=np.int64),
                  names=tuple((f, c[0] if f == "t" else c) for f, c in named.items() if c))


def _sensors(cols: _Columns, units: dict, unit, gyro_unit, mag_unit, notes: list) -> dict:
    """The accelerometer's, gyroscope's and magnetometer's values in their units (None
    where the table has none), the units' notes appended to ``notes``."""
    roles, path = cols.roles, cols.path
    out = dict.fromkeys(("acc", "unit", "gyro", "gyro_unit", "mag", "mag_unit"))
    if "ax" in roles:
        out["acc"], out["unit"], note = resolve_acceleration_unit(cols.triad(ACC_ROLES), units, unit, path, own=True)
        notes.append(note)
    elif unit is not None:
        raise RecordingError(f"{path}: --unit {unit} given, but the table has no acceleration columns (gyro only)")
    notes.append(units.get("gyro_note", ""))
    if "gx" in roles:
        out["gyro"], out["gyro_unit"], note = resolve_gyro_unit(cols.triad(GYRO_ROLES), units, gyro_unit, path,
                                                                own=True)
        notes.append(note)
    if "mx" in roles:
        # a Recording's nan field is a log's "no sample here" (mag_logs), not a value a table's line may hold
        out["mag"], out["mag_unit"], note = resolve_mag_unit(cols.triad(MAG_ROLES, finite=True), units.get("mag_units", {}),
                                                             mag_unit, path)
        notes.append(note)
    return out


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


def numeric_columns(tab: _Table) -> list[np.ndarray] | None:
    """Every column's data fields as floats, in one conversion (a third of the time of
    column by column), or None when a field is not a plain number (text, empty, decimal
    comma): the columns are then converted one by one, which names the first bad value and
    its line."""
    if tab.numbers is not None:
        return tab.numbers
    if tab.dc:
        return None
    try:
        return list(np.array(tab.data, dtype=float).T)
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
    if parsed is None or len(parsed[0][0]) < MIN_ROWS:
        return None
    numbers, body = parsed
    preamble = [(numbered[i][0], rows[i]) for i in range(first if header is None else header)]
    return _Table(rows[header] if header is not None else None, None,
                  range(start_line, start_line + len(numbers[0])), preamble, delim, dc, k, numbers, body)


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
