"""Compiled parser of a plain numeric table's data lines (numba, the optional ``fast`` extra).

:func:`parse_lines` reads the ASCII bytes of ``k`` plain decimal numbers per line straight
into the columns' float arrays: no decoded copy of the block, no pandas (0.25 s and ~40 MB
to import) and no chunks concatenated afterwards (pandas' C reader holds every column
twice at its end).  It is stricter than pandas' reader, and gives up (returns -1) on
anything it does not read exactly as Python's ``float`` reads it; the caller
(:func:`accelcal.formats.numeric_block.parse_block`) then parses the block with pandas or
numpy as before, so the numbers are the same whichever reads them:

* a field is ``[blanks] [+-] digits [. digits] [(e|E) [+-] digits] [blanks]`` (``.5`` and
  ``5.`` too), blanks being spaces and tabs; a line is ``k`` fields separated by the
  delimiter (runs of blanks for a whitespace table) and ends with LF or CRLF;
* its value is exact: at most 15 significant digits and a power of ten within 10^±22
  (Clinger's fast path: both factors are exact doubles and one multiplication or division
  rounds correctly, which is what ``float`` gives); anything longer (e.g. the 17 digits of
  ``repr``) is left to the other parsers.

Imported only through :func:`accelcal.kernels.compiled` (it imports numba).
"""

from __future__ import annotations

import numpy as np

from ..kernels import jit

#: The exact powers of ten of a double (10^0 … 10^22).
_POW10 = np.array([10.0**e for e in range(23)])
#: Largest mantissa of the fast path (15 digits: below 2^53, so exact).
_MAX_DIGITS = 15


def _blank(c, delim):
    """A blank around a field: a space, or a tab unless tabs delimit the fields."""
    return c == 32 or (c == 9 and delim != 9)


def _number(buf, pos, end, out, col, row):
    """Parse one number at ``buf[pos:end]`` into ``out[col, row]``; the position after it, or -1."""
    neg = False
    if pos < end and (buf[pos] == 43 or buf[pos] == 45):  # + -
        neg = buf[pos] == 45
        pos += 1
    mant = 0
    digits = 0  # significant digits taken (leading zeros not counted)
    seen = 0  # digits of the mantissa, zeros included
    scale = 0  # power of ten from the digits after the point
    while pos < end and 48 <= buf[pos] <= 57:
        d = buf[pos] - 48
        if digits > 0 or d != 0:
            digits += 1
            mant = mant * 10 + d
        seen += 1
        pos += 1
    if pos < end and buf[pos] == 46:  # .
        pos += 1
        # the integer part's loop again, with the scale: a shared helper returning a tuple
        # made the whole parse 1.18x slower (measured side by side, 15 rounds)
        while pos < end and 48 <= buf[pos] <= 57:
            d = buf[pos] - 48
            if digits > 0 or d != 0:
                digits += 1
                mant = mant * 10 + d
            seen += 1
            scale -= 1
            pos += 1
    if seen == 0 or digits > _MAX_DIGITS:
        return -1
    if pos < end and (buf[pos] == 101 or buf[pos] == 69):  # e E
        pos += 1
        eneg = False
        if pos < end and (buf[pos] == 43 or buf[pos] == 45):
            eneg = buf[pos] == 45
            pos += 1
        e = 0
        ed = 0
        while pos < end and 48 <= buf[pos] <= 57:
            if e < 10000:
                e = e * 10 + (buf[pos] - 48)
            ed += 1
            pos += 1
        if ed == 0:
            return -1
        scale += -e if eneg else e
    if mant == 0:
        v = 0.0
    elif 0 <= scale <= 22:
        v = float(mant) * _POW10[scale]
    elif -22 <= scale < 0:
        v = float(mant) / _POW10[-scale]
    else:
        return -1
    out[col, row] = -v if neg else v
    return pos


def _line(buf, pos, end, delim, out, row):
    """Parse the line at ``buf[pos:]`` (its ``k`` fields) into row ``row``; the position after
    its line feed (or ``end``), or -1 if it is not ``k`` plain numbers."""
    k = out.shape[0]
    for col in range(k):
        while pos < end and _blank(buf[pos], delim):
            pos += 1
        pos = _number(buf, pos, end, out, col, row)
        if pos < 0:
            return -1
        while pos < end and _blank(buf[pos], delim):
            pos += 1
        if col < k - 1:
            if delim == 32:
                if pos == end or not _blank(buf[pos - 1], delim):
                    return -1
            elif pos < end and buf[pos] == delim:
                pos += 1
            else:
                return -1
    if pos < end and buf[pos] == 13:
        pos += 1
        if pos == end or buf[pos] != 10:
            return -1
    if pos < end:
        if buf[pos] != 10:
            return -1
        pos += 1
    return pos


def _parse(buf, delim, out, row0):
    """Parse the lines of ``buf`` into rows ``row0, row0 + 1, …`` of ``out`` (k, n); the
    number of lines read, or -1."""
    end = buf.shape[0]
    pos = 0
    row = row0
    n = out.shape[1]
    while pos < end:
        if row >= n:
            return -1
        pos = _line(buf, pos, end, delim, out, row)
        if pos < 0:
            return -1
        row += 1
    return row - row0


# The helpers inlined into the loop (numba's IR inliner): called once per byte or field,
# as calls they cost a third of the parse.
_inline = jit(error_model="python", inline="always")
_blank = _inline(_blank)
_number = _inline(_number)
_line = _inline(_line)
_parse = jit(error_model="python")(_parse)


def parse_lines(pieces, delim: str, k: int, n: int) -> list[np.ndarray] | None:
    """The ``k`` columns (``n`` floats each, an array of its own per column: a reader frees the
    columns it has used) of the lines in ``pieces`` (ASCII ``bytes``, each ending after a line
    feed but the last), or None if a line is not ``k`` plain numbers (module docstring) or the
    lines are not ``n``."""
    columns = [np.empty(n) for _ in range(k)]
    row = 0
    code = 32 if delim == " " else ord(delim)
    for piece in pieces:
        block = np.empty((k, piece.count(b"\n") + 1))
        got = _parse(np.frombuffer(piece, np.uint8), code, block, 0)
        if got < 0 or row + got > n:
            return None
        for column, values in zip(columns, block):
            column[row:row + got] = values[:got]
        row += got
    return columns if row == n else None


__all__ = ["parse_lines"]
