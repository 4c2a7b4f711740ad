"""The structure of a MATLAB v5 file checked before SciPy parses it.

SciPy's v5 reader (``scipy.io.loadmat``, compiled ``_mio5_utils``) trusts the file: a
damaged byte can make it read past an array's end or index its type table with an
unknown code, and the process dies (segmentation fault or bus error: known to SciPy,
whose ``loadmat`` docstring warns that the reader is not hardened), where this project owes
the user a one-line refusal.  Found by the reader fuzz (tests/test_reader_fuzz.py):
4000 files damaged by 1-3 random bytes or cuts crashed SciPy 1.17.1 14 times; every
one of them is refused here, and none of the files this check lets through crashed.

The check walks every data element (MATLAB's "MAT-File Format", 2021, chapter 1):
an 8-byte tag (type, byte count; or the 4-byte small form) whose type is known and
whose bytes lie inside the file; an array's flags, dimensions (none negative, the
count below 2^31) and name; a numeric or char array's one real part, plus an
imaginary part exactly when its complex flag is set, of as many values as the
dimensions say; a sparse array's four or five parts; cells and structs recursively;
compressed elements inflated (zlib) and walked the same way.  It checks the layout,
not the values: what it lets through, SciPy reads or refuses with an exception.
"""

from __future__ import annotations

import struct
import zlib

#: Data types of an element: int8..uint32, single, double, int64, uint64, matrix, compressed, utf8..utf32.
SIZES = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8, 14: 1, 16: 1, 17: 2, 18: 4}
MATRIX, COMPRESSED, INT32, UINT32 = 14, 15, 5, 6
#: Array classes: cell, struct, object, char, sparse, the numeric ones, function, opaque.
CELL, STRUCT, OBJECT, CHAR, SPARSE = 1, 2, 3, 4, 5
NUMERIC = range(6, 16)
CONTAINERS = (CELL, STRUCT, OBJECT, 16, 17)
COMPLEX_FLAG = 0x0800
MAX_DEPTH = 32
#: An inflated compressed element larger than this is refused (a zlib bomb, not a recording).
MAX_INFLATED = 1 << 31


class DamagedMat(ValueError):
    """The file's layout is not MATLAB v5's (the message says where)."""


def check_v5(data: bytes) -> None:
    """Raise :class:`DamagedMat` unless ``data`` (a whole .mat file) has v5's layout."""
    if len(data) < 128:
        raise DamagedMat("shorter than the 128-byte header")
    order = "<" if data[126:128] == b"IM" else ">"
    _walk_top(memoryview(data), 128, len(data), order, inflated=False)


def _tag(buf, at: int, end: int, order: str) -> tuple[int, int, int, int]:
    """``(type, bytes, data start, next element)`` of the element at ``at``."""
    if at + 8 > end:
        raise DamagedMat(f"a data element's tag is cut at byte {at}")
    first, second = struct.unpack_from(order + "II", buf, at)
    if first >> 16:  # the small form: type and count in 4 bytes, at most 4 data bytes after
        n = first >> 16
        if n > 4:
            raise DamagedMat(f"a small element at byte {at} declares {n} bytes (at most 4)")
        return first & 0xFFFF, n, at + 4, at + 8
    if at + 8 + second > end:
        raise DamagedMat(f"the element at byte {at} declares {second} bytes, {end - at - 8} are left")
    return first, second, at + 8, at + 8 + second + (-second) % 8


def _walk_top(buf, at: int, end: int, order: str, inflated: bool) -> None:
    """The file's variables (an inflated compressed element holds one or more)."""
    while end - at >= 8:
        kind, n, data, after = _tag(buf, at, end, order)
        if kind == COMPRESSED and not inflated:
            try:
                raw = zlib.decompressobj().decompress(bytes(buf[data:data + n]), MAX_INFLATED)
            except zlib.error as e:
                raise DamagedMat(f"the compressed element at byte {at} does not inflate ({e})") from None
            _walk_top(memoryview(raw), 0, len(raw), order, inflated=True)
            after = data + n  # compressed elements are not padded
        elif kind == MATRIX:
            _walk_array(buf, data, data + n, order, 1)
        elif kind not in SIZES:
            raise DamagedMat(f"unknown data type {kind} at byte {at}")
        at = after


def _parts(buf, at: int, end: int, order: str) -> list[tuple[int, int, int]]:
    """``(type, bytes, data start)`` of each element between ``at`` and ``end``."""
    out = []
    while at < end:
        kind, n, data, after = _tag(buf, at, end, order)
        if kind not in SIZES:
            raise DamagedMat(f"unknown data type {kind} at byte {at}")
        if n % SIZES[kind]:
            raise DamagedMat(f"{n} bytes at byte {at} are not whole values of data type {kind}")
        out.append((kind, n, data))
        at = min(after, end)
    return out


def _walk_array(buf, at: int, end: int, order: str, depth: int) -> None:
    """One array (an empty element is MATLAB's empty cell entry)."""
    if at == end:
        return
    if depth > MAX_DEPTH:
        raise DamagedMat(f"arrays nested deeper than {MAX_DEPTH}")
    parts = _parts(buf, at, end, order)
    if len(parts) < 3 or parts[0][:2] != (UINT32, 8) or parts[1][0] != INT32 or parts[1][1] < 8:
        raise DamagedMat(f"the array at byte {at} lacks its flags, dimensions or name")
    flags = struct.unpack_from(order + "I", buf, parts[0][2])[0]
    cls, is_complex = flags & 0xFF, bool(flags & COMPLEX_FLAG)
    size = 1
    for d in struct.unpack_from(order + f"{parts[1][1] // 4}i", buf, parts[1][2]):
        if d < 0:
            raise DamagedMat(f"the array at byte {at} has a negative dimension")
        size *= d
    if cls != SPARSE and size >= 1 << 31:
        raise DamagedMat(f"the array at byte {at} claims {size} values")
    values = parts[3:]
    if cls in NUMERIC or cls == CHAR:
        if len(values) != 1 + is_complex:
            raise DamagedMat(f"the array at byte {at} has {len(values)} data parts where its flags say "
                             f"{1 + is_complex}")
        if cls != CHAR and any(n // SIZES[kind] != size for kind, n, _ in values):
            raise DamagedMat(f"the array at byte {at} holds a different number of values than its dimensions")
    elif cls == SPARSE:
        if len(values) != 3 + is_complex:
            raise DamagedMat(f"the sparse array at byte {at} has {len(values)} data parts where {3 + is_complex} "
                             "are due")
    elif cls in CONTAINERS:
        for kind, n, data in values:
            if kind == MATRIX:
                _walk_array(buf, data, data + n, order, depth + 1)
    else:
        raise DamagedMat(f"unknown array class {cls} at byte {at}")


__all__ = ["DamagedMat", "check_v5"]
