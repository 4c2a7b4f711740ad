"""The table reader's compiled route gives what the line-by-line route gives, and fast.

A plain numeric table is parsed by a C parser (pandas' for large blocks, numpy's loadtxt for
small ones) after its structure (delimiter, preamble, header, first data line) is found from
its first and last lines (``accelcal.formats.table._fast_table``); anything else is read
line by line (``_general_table``), which names what is wrong.  Here both routes read the
same texts, tricky and fuzzed (tests/test_reader_fuzz.py's tables, damaged), under both
parsers: wherever the compiled route answers, it answers what the line-by-line route does
(header, preamble, data line numbers, every number bit for bit, every column's strings).
Then its speed and memory against pandas' own reader on the same file, in one run.
"""

from __future__ import annotations

import gzip
import time
import weakref

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.errors import RecordingError
from accelcal.formats import dispatch, numeric_block, table
from accelcal.formats import text as text_module
from accelcal.formats.table import _fast_table, _general_table, read_table
from accelcal.formats.text import load_text

from .test_reader_fuzz import JUNK, _valid_table

ROWS = "\n".join(f"{0.01 * i:.2f},{0.1 + 1e-3 * (i % 7):.6g},-0.2{i % 10},9.8{i % 3}" for i in range(30))


def late(row: str) -> str:
    """The table with its 20th data row (well inside the data) replaced by ``row``."""
    rows = ROWS.split("\n")
    rows[20] = row
    return "t,ax,ay,az\n" + "\n".join(rows)


TEXTS = {
    "plain": "t,ax,ay,az\n" + ROWS + "\n",
    "no header": ROWS,
    "crlf": ("t,ax,ay,az\n" + ROWS).replace("\n", "\r\n") + "\r\n",
    "lone cr": ("t,ax,ay,az\n" + ROWS).replace("\n", "\r"),
    "trailing blank lines": "t,ax,ay,az\n" + ROWS + "\n\n  \n\t\n",
    "blank line inside": late("\n0.20,0.106,-0.20,9.82"),
    "comment inside": late("# pause\n0.20,0.106,-0.20,9.82"),
    "comment header": "# t ax ay az\n" + ROWS.replace(",", " "),
    "rostopic header": "%time,field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z\n"
                       + ROWS,
    "preamble": "# logger v2\nrate: 100 Hz\n\nsensor;MPU\nt;ax;ay;az\n" + ROWS.replace(",", ";"),
    "whitespace": "  t   ax  ay az\n" + "\n".join("  " + ln.replace(",", " \t ") + " " for ln in ROWS.split("\n")),
    "tabs": "t\tax\tay\taz\n" + ROWS.replace(",", "\t"),
    "pipes": "t|ax|ay|az\n" + ROWS.replace(",", "|"),
    "spaces in fields": "t , ax , ay , az\n" + ROWS.replace(",", " , "),
    "trailing delimiter": "t,ax,ay,az,\n" + ROWS.replace("\n", ",\n") + ",",
    "unit header": "t [s],acc_x [m/s²],acc_y [m/s²],acc_z [m/s²]\n" + ROWS,
    "non-ascii data": late("0.20,0.106,-0.20,９.82"),
    "form feed": late("0.20,0.106\x0c,-0.20,9.82"),
    "vertical tab": late("0.20,0.106,\x0b-0.20,9.82"),
    "unit separator": late("0.20,0.106\x1f,-0.20,9.82"),
    "lone cr inside": late("0.20,0.106,-0.20\r,9.82"),
    "quoted": late('0.20,"0.106",-0.20,9.82'),
    "nan": late("0.20,nan,-0.20,9.82"),
    "inf": late("0.20,inf,-0.20,9.82"),
    "empty field": late("0.20,,-0.20,9.82"),
    "short row": late("0.20,0.106,-0.20"),
    "long row": late("0.20,0.106,-0.20,9.82,1"),
    "exponents and signs": late("2e-1,+.106,-2.0E-1,0009.82"),
    "decimal comma": "t;ax;ay;az\n" + ROWS.replace(",", ";").replace(".", ","),
    "long preamble": "".join(f"# line {i}\n" for i in range(300)) + "t,ax,ay,az\n" + ROWS,
    "long file": "t,ax,ay,az\n" + "\n".join(ROWS for _ in range(12)),
    "text column": "t,ax,ay,az,pose\n" + ROWS.replace("\n", ",a\n") + ",a",
    "iso time": "t,ax,ay,az\n" + "\n".join(f"2024-01-01T00:00:{i:02d},1,2,3" for i in range(30)),
}


def both_routes(text: str):
    """``(compiled, line by line)``; the second an exception if that route refuses."""
    fast = _fast_table(text)
    try:
        general = _general_table(text, "x.csv")
    except Exception as e:  # noqa: BLE001 (compared below: the compiled route must have refused too)
        general = e
    return fast, general


def assert_same(fast, general) -> None:
    assert not isinstance(general, Exception), f"compiled route read what the general route refuses: {general}"
    assert fast.names == general.names and fast.preamble == general.preamble
    assert (fast.delim, fast.dc, fast.k) == (general.delim, general.dc, general.k)
    assert list(fast.lines) == list(general.lines)
    np.testing.assert_array_equal(np.column_stack(fast.numbers), np.array(general.data, dtype=float))
    for i in range(fast.k):
        assert fast.column(i).tolist() == general.column(i).tolist()


@pytest.fixture(params=[True, False], ids=["pandas", "loadtxt"])
def parser(request, monkeypatch):
    monkeypatch.setattr(numeric_block, "use_pandas", lambda chars: request.param)
    return request.param


@pytest.mark.parametrize("name", TEXTS)
def test_compiled_route_reads_what_the_line_by_line_route_reads(name, parser):
    fast, general = both_routes(TEXTS[name])
    if fast is not None:
        assert_same(fast, general)
    plain = name in {"plain", "no header", "crlf", "trailing blank lines", "comment header", "rostopic header",
                     "preamble", "whitespace", "tabs", "pipes", "spaces in fields", "unit header", "long file",
                     "exponents and signs"}
    plain = plain or name == "inf" or (name == "nan" and not parser)  # pandas refuses 'nan', numpy takes it
    assert (fast is not None) == plain  # what it takes, and what it leaves to the general route


@st.composite
def nearly_plain_tables(draw) -> str:
    """tests/test_reader_fuzz.py's valid tables, some with one line damaged (junk, a comment,
    a blank line, a field more or fewer, another line ending, blanks around the fields)."""
    lines = _valid_table(draw).split("\n")
    i = draw(st.integers(0, max(len(lines) - 1, 0)))
    op = draw(st.sampled_from(["none", "none", "junk", "comment", "blank", "more", "fewer", "crlf", "blanks"]))
    if op == "junk":
        j = draw(st.integers(0, len(lines[i])))
        lines[i] = lines[i][:j] + draw(st.sampled_from(JUNK)) + lines[i][j:]
    elif op in ("comment", "blank"):
        lines.insert(i, "# note" if op == "comment" else draw(st.sampled_from(["", " ", "\t"])))
    elif op == "more":
        lines[i] += draw(st.sampled_from([",1", ";1", "\t1", " 1", "|1", ","]))
    elif op == "fewer":
        lines[i] = lines[i][: max(lines[i].rfind(draw(st.sampled_from([",", ";", "\t", " ", "|"]))), 0)]
    elif op == "crlf":
        return "\r\n".join(lines)
    elif op == "blanks":
        lines = [draw(st.sampled_from(["", " ", "\t"])) + ln + draw(st.sampled_from(["", " ", " \t"])) for ln in lines]
    return "\n".join(lines)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(nearly_plain_tables())
def test_compiled_route_agrees_on_fuzzed_tables(text):
    for use in (True, False):
        choice = numeric_block.use_pandas
        numeric_block.use_pandas = lambda chars, use=use: use
        try:
            fast, general = both_routes(text)
        finally:
            numeric_block.use_pandas = choice
        if fast is not None:
            assert_same(fast, general)


def test_a_large_table_reads_within_a_few_times_pandas(tmp_path):
    """200 000 rows of t + 6 channels: ``read_table`` (reading, units, time, checks) takes at
    most 4x the CPU time of ``pandas.read_csv`` on the same file, both timed here, best of 2
    (measured 1.4-1.6x at load 20 on 2 cores, 2.3-3.2x before the time column was cut on
    demand; a 3x slip fails it; the line-by-line route took 12-19x)."""
    rng = np.random.default_rng(0)
    tails = [",".join(f"{v:.5g}" for v in row)
             for row in rng.normal(size=(997, 6)) * 0.01 + [0.1, -0.2, 0.3, 0.0, 0.0, -1.0]]
    path = tmp_path / "large.csv"
    path.write_text("time,gx,gy,gz,ax,ay,az\n" + "\n".join(f"{i / 100:.2f},{tails[i % 997]}" for i in range(200_000)))
    cost = {}
    for name, read in (("pandas", pd.read_csv), ("accelcal", read_table)) * 2:
        c0 = time.process_time()
        read(path)
        cost[name] = min(cost.get(name, np.inf), time.process_time() - c0)
    assert cost["accelcal"] < 4 * cost["pandas"], cost


def test_time_column_is_cut_when_asked_and_as_written(tmp_path):
    """The compiled route keeps the time column as written without cutting it out of the text
    until asked (a third of a 10⁶-line read): its strings, a leading slice and the whole, equal
    the line-by-line route's."""
    p = tmp_path / "t.csv"
    p.write_text("t,ax,ay,az\n" + "".join(f" {0.01 * i:.2f} ,0.1,-0.2,9.8{i % 3}\n" for i in range(1500)))
    rec = read_table(p)
    name, written = rec.time_column
    general = _general_table(p.read_text(), p).column(0).astype(str)
    assert name == "t" and isinstance(written, numeric_block.TextColumn) and written._strings is None
    assert list(written[:7]) == [v.strip() for v in general[:7]] and written._strings is None
    assert np.asarray(written).tolist() == [v.strip() for v in general] and len(written) == len(general)


@pytest.mark.parametrize("content", [b"t,ax,ay,az\n0,1,2,3\n", b"\xef\xbb\xbft;ax\n0;1\n", b"t,ax\n\xe9,1\n",
                                     b"", b"  \n\t\n", b"PK\x03\x04rest", b"a\x00b", gzip.compress(b"t,ax\n0,1\n"),
                                     b"\x1f\x8bdamaged"], ids=["plain", "bom", "cp1252", "empty", "blank", "zip",
                                                               "nul", "gzip", "bad gzip"])
def test_a_memory_mapped_file_loads_as_a_read_one(tmp_path, monkeypatch, content):
    """load_text maps large files instead of reading them (fewer page faults): the same
    text, notes and refusals as reading, whatever the bytes."""
    p = tmp_path / "f.csv"
    p.write_bytes(content)

    def outcome():
        try:
            return load_text(p)
        except RecordingError as e:
            return str(e)

    read = outcome()
    monkeypatch.setattr(text_module, "_MAP_FROM_BYTES", 1)
    assert outcome() == read


class _Text(str):
    """A decoded text whose lifetime a weak reference follows (a ``str`` takes none)."""


@pytest.mark.parametrize("time_column", [False, True])
def test_without_its_time_column_a_table_lets_its_text_go_before_the_clock(tmp_path, monkeypatch, time_column):
    """formats.read(time_column=False) (``accelcal noise``): no reference to the file's text is
    left, the dispatcher's included, when the clock is fitted (47 MB of the 10⁶-row ADIS CSV's
    peak); with the time column the text stays (its strings are cut from it).  The
    recording is the same but for the time column (its numeric pose labels read: their column
    was sized by the time column's floats, let go by then: a TypeError)."""
    p = tmp_path / "t.csv"
    p.write_text("t,ax,ay,az,pose\n" + "".join(f"{0.01 * i:.2f},0.1,-0.2,9.8{i % 3},{i // 500}\n" for i in range(1500)))
    refs, alive = [], []
    load, clock = dispatch.load_text, table._sensor_clock

    def loaded(path):
        text, notes = load(path)
        refs.append(weakref.ref(kept := _Text(text)))
        return kept, notes

    def clocked(*args, **kw):
        alive.append(refs[0]() is not None)
        return clock(*args, **kw)

    monkeypatch.setattr(dispatch, "load_text", loaded)
    monkeypatch.setattr(table, "_sensor_clock", clocked)
    rec = dispatch.read(p, time_column=time_column)
    assert alive == [time_column] and (rec.time_column is not None) == time_column
    monkeypatch.undo()
    ref = dispatch.read(p)
    assert np.array_equal(rec.t, ref.t) and np.array_equal(rec.acc, ref.acc) and rec.notes == ref.notes
    assert np.array_equal(rec.intervals, ref.intervals) and rec.labels == ref.labels


def test_a_bad_value_is_still_named_when_the_text_would_be_let_go(tmp_path):
    """A value a C parser reads but the reader refuses (``nan``) is named with its line: the
    text is kept for the message where a column's floats are not all finite."""
    p = tmp_path / "t.csv"
    p.write_text("t,ax,ay,az\n" + "".join(f"{0.01 * i:.2f},{'nan' if i == 700 else 0.1},-0.2,9.8\n"
                                          for i in range(1500)))
    with pytest.raises(RecordingError, match="line 702") as e:
        dispatch.read(p, time_column=False)
    with pytest.raises(RecordingError) as e2:
        dispatch.read(p)
    assert str(e.value) == str(e2.value)
