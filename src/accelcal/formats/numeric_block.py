"""The numbers of a plain numeric table by a compiled parser, and its fields as strings.

A table whose data lines are ``k`` plain numbers each (no comment or blank line among them,
no text, empty or quoted field) is parsed by a compiled reader instead of line by line in
Python (0.2 s instead of 4 s for 10⁶ lines): :func:`parse_block`.  A large block is read by
the compiled parser of :mod:`._parse_kernels` where numba is installed (no pandas, no
decoded copy of the block) when numba is loaded already (its start-up, 0.5 s and ~100 MB,
repays itself only where the caller compiles anyway: ``accelcal noise`` loads its kernels
before reading), and by pandas' C reader otherwise or where that parser gives up; a small
one by numpy's ``loadtxt``.  The strings of
one column (a time column is kept as written) are cut out of the text by position, not by
splitting lines: :func:`field_strings`.  The structure of the table (delimiter, header,
first data line) is found by :mod:`.table`, which reads anything else line by line.
"""

from __future__ import annotations

import csv
import io
import sys
from typing import NamedTuple

import numpy as np

from .. import kernels

#: Data blocks from this size [characters] are parsed by pandas (6 ms/MB, 0.24 s to import),
#: smaller ones by numpy's loadtxt (25 ms/MB, numpy being loaded anyway); pandas also when loaded.
_PANDAS_FROM_CHARS = 12_000_000


def use_pandas(chars: int) -> bool:
    """Parse a block of ``chars`` characters by pandas (else by numpy's loadtxt)?"""
    return chars >= _PANDAS_FROM_CHARS or "pandas" in sys.modules


class Body(NamedTuple):
    """The data lines of a plain numeric table: ``text[start:end]``, ASCII."""

    text: str
    start: int
    end: int


class _AsciiStream(io.TextIOBase):
    """``text[start:end]`` as a file read in pieces (what the C parsers take: no copy of the
    whole text), counting the control characters it hands out and refusing non-ASCII text."""

    def __init__(self, body: Body):
        self.text, self.pos, self.end, self.controls = body.text, body.start, body.end, 0

    def readable(self) -> bool:
        return True

    def read(self, size: int | None = -1) -> str:
        stop = self.end if size is None or size < 0 else min(self.pos + size, self.end)
        piece = self.text[self.pos:stop]
        self.pos = stop
        if not piece.isascii():
            raise ValueError("not ASCII")
        self.controls += int(np.count_nonzero((np.frombuffer(piece.encode("ascii"), np.uint8) - np.uint8(32)) >= 95))
        return piece


def parse_block(text: str, offset: int, delim: str, k: int) -> tuple[list[np.ndarray], Body] | None:
    """``(the k columns' floats (n each), the lines)`` when each line of ``text`` from ``offset`` on holds
    ``k`` plain numbers (trailing blank lines aside), else None.  The C parsers are strict
    (a comment, a blank line, text, an empty or a quoted field, a row of another length
    fails them; their numbers are Python's ``float`` of the field) and counted: ``n`` must
    be the number of lines, and the text must hold no line break but LF and CRLF and no
    control character but those and tabs, so that line ``i`` of the block is the ``i``-th
    line from ``offset`` on for ``str.splitlines`` too."""
    end = len(text)
    while end > offset and text[end - 1].isspace():
        end -= 1
    n = text.count("\n", offset, end) + 1
    body = Body(text, offset, end)
    if end - offset >= _PANDAS_FROM_CHARS and "numba" in sys.modules:
        columns = _compiled_columns(body, delim, k, n)
        if columns is not None:
            return columns, body
    stream = _AsciiStream(body)
    try:
        if use_pandas(end - offset):
            columns = _pandas_columns(stream, delim, k, n)
        else:
            block = np.loadtxt(io.StringIO(stream.read()), delimiter=None if delim == " " else delim, ndmin=2,
                               comments=None, dtype=float)
            columns = list(block.T) if block.shape[1] == k else []
    except ValueError:  # pandas' ParserError is a ValueError
        return None
    if stream.pos != end or len(columns) != k or len(columns[0]) != n:
        return None
    if stream.controls > n - 1:  # carriage returns (of CRLF only), tabs, nothing else
        cr = text.count("\r", offset, end)
        if stream.controls != n - 1 + cr + text.count("\t", offset, end) or cr != text.count("\r\n", offset, end):
            return None
    return columns, body


#: Characters of a block handed to the compiled parser at once (their ASCII bytes a copy).
_PIECE_CHARS = 1 << 22


def _compiled_columns(body: Body, delim: str, k: int, n: int) -> list[np.ndarray] | None:
    """The ``k`` columns of the ``n`` lines of ``body`` by the compiled parser
    (:func:`._parse_kernels.parse_lines`), or None where the kernels are off or it gives up
    (pandas then reads the block, and decides).  The block is handed over in pieces of
    :data:`_PIECE_CHARS` characters that end after a line feed, so that no copy of the
    whole block is made (10⁶ lines of the ADIS record: 47 MB)."""
    parser = kernels.compiled("formats._parse_kernels")
    if parser is None:
        return None

    def pieces():
        text, pos = body.text, body.start
        while pos < body.end:
            stop = text.find("\n", min(pos + _PIECE_CHARS, body.end), body.end)
            stop = body.end if stop < 0 else stop + 1
            yield text[pos:stop].encode("ascii")
            pos = stop

    try:
        return parser.parse_lines(pieces(), delim, k, n)
    except UnicodeEncodeError:
        return None


def _pandas_columns(stream, delim: str, k: int, n: int) -> list[np.ndarray]:
    """``n`` lines of ``stream`` by pandas' C reader: no quoting, no NA spellings, no blank
    lines skipped, ``k`` columns (a row with more raises, one with fewer leaves an empty
    field, which raises).  In one call (read in chunks into an array of ours, the same table
    cost a fifth more page faults: each chunk's buffers allocated anew, 0.1-0.2 s of system
    time for 10⁶ lines), each column's array returned as pandas made it: the frame read
    with ``nrows`` keeps one block per column, and a (n, k) matrix of them would be a copy
    (0.1 s and 8 MB per 10⁶ rows and column, a fifth of the read)."""

    import pandas as pd  # here: a table of 10^5 lines or more repays its import

    frame = pd.read_csv(stream, sep=r"\s+" if delim == " " else delim, header=None, names=range(k), index_col=False,
                        dtype=np.float64, quoting=csv.QUOTE_NONE, na_filter=False, skip_blank_lines=False, engine="c",
                        nrows=n)
    return [frame[c].to_numpy() for c in range(k)]


def field_strings(body: Body, i: int, delim: str, k: int) -> np.ndarray:
    """The stripped strings of field ``i`` of every line of a block :func:`parse_block`
    read (``k`` fields on each line), cut out by position, :data:`_CHUNK_CHARS` at a time."""
    text, pieces, pos = body.text, [], body.start
    while pos < body.end:
        stop = text.find("\n", min(pos + _CHUNK_CHARS, body.end), body.end)
        stop = body.end if stop < 0 else stop
        pieces.append(_fields_of(np.frombuffer(text[pos:stop].encode("ascii"), np.uint8), i, delim, k))
        pos = stop + 1
    return np.concatenate(pieces)


class TextColumn:
    """Field ``i`` of the ``n`` lines of a block as strings, cut out of the text when first
    asked for (:func:`field_strings`): a table's time column is kept as written for
    ``accelcal apply`` (:attr:`accelcal.recording.Recording.time_column`), which most
    commands never use, and its first lines are what the time's sniffing reads (a third of
    the reading time of a 10⁶-line table saved).  Behaves as the array of strings: ``len``,
    indexing, ``astype``, ``numpy.asarray``; a leading slice ``[:m]`` cuts only ``m`` lines."""

    def __init__(self, body: Body, i: int, delim: str, k: int, n: int):
        self.body, self.i, self.delim, self.k, self.n = body, i, delim, k, n
        self._strings = None

    def __len__(self) -> int:
        return self.n

    def strings(self) -> np.ndarray:
        """The whole column (cut once)."""
        if self._strings is None:
            self._strings = field_strings(self.body, self.i, self.delim, self.k)
        return self._strings

    def __getitem__(self, key):
        if isinstance(key, slice) and not key.start and key.step in (None, 1) and key.stop is not None \
                and 0 < key.stop < self.n and self._strings is None:
            text, end = self.body.text, self.body.start
            for _ in range(key.stop):
                end = text.find("\n", end, self.body.end) + 1
            return field_strings(Body(text, self.body.start, end - 1), self.i, self.delim, self.k)
        return self.strings()[key]

    def __iter__(self):
        return iter(self.strings())

    def tolist(self) -> list:
        return self.strings().tolist()

    def astype(self, dtype, copy: bool = True) -> np.ndarray:
        return self.strings().astype(dtype, copy=copy)

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        a = self.strings()
        return a if dtype is None else a.astype(dtype)


#: Characters of the text cut into fields at once by :func:`field_strings` (memory).
_CHUNK_CHARS = 1 << 22


def _fields_of(a: np.ndarray, i: int, delim: str, k: int) -> np.ndarray:
    """Field ``i`` of each line of the ASCII bytes ``a`` (lines of ``k`` fields) as strings,
    without the blanks around it."""
    if delim == " ":  # fields are the runs of non-blanks
        blank = (a == 32) | (a == 9) | (a == 13) | (a == 10)
        edge = np.diff((~blank).view(np.int8), prepend=np.int8(0), append=np.int8(0))
        start, end = np.flatnonzero(edge == 1).reshape(-1, k)[:, i], np.flatnonzero(edge == -1).reshape(-1, k)[:, i]
    else:  # each line: k - 1 delimiters, then its line feed (none after the last)
        cuts = np.append(np.flatnonzero((a == ord(delim)) | (a == 10)), len(a)).reshape(-1, k)
        start = cuts[:, i - 1] + 1 if i > 0 else np.concatenate(([0], cuts[:-1, -1] + 1))
        end = cuts[:, i].copy()
        for edge, step in ((start, 1), (end, -1)):  # strip blanks (rare: a loop per blank, not per line)
            while True:
                at = edge if step == 1 else edge - 1
                more = (start < end) & np.isin(a[np.minimum(at, len(a) - 1)], _BLANKS)
                if not more.any():
                    break
                edge[more] += step
    width = max(int((end - start).max()), 1)
    out = np.empty((len(start), width), np.uint32)  # ASCII codes are UCS-4 code points: a str array
    for j in range(width):  # one pass per character position, not per line
        out[:, j] = np.where(start + j < end, a[np.minimum(start + j, len(a) - 1)], 0)
    return out.view(f"U{width}").ravel()  # the zero padding is no part of the strings


#: What ``str.strip`` removes around a field of an ASCII line (line feeds excepted).
_BLANKS = np.array([9, 11, 12, 13, 28, 29, 30, 31, 32], np.uint8)
