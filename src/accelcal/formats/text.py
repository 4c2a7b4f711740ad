"""Text of a recording file: gzip undone, decoded, binary files named; comment lines.

This module imports only the standard library.
"""

from __future__ import annotations

import codecs
import contextlib
import gzip
import mmap
import zlib
from pathlib import Path

from ..errors import RecordingError

#: Comment lines start with one of these (after leading blanks).
COMMENT_MARKERS = ("#", "%", "//")


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
    with _file_bytes(path) as raw:
        return _decoded(path, raw)


#: Files from this size [bytes] are read through a memory map (:func:`_file_bytes`).
_MAP_FROM_BYTES = 1 << 22


@contextlib.contextmanager
def _file_bytes(path: Path):
    """The bytes of ``path``: a large file as a read-only memory map, whose pages come from
    the page cache 16 at a time (a copy read into a new buffer faults in each of its pages
    alone: 12 000 page faults, 0.1 s of system time, for a 47 MB table), else read."""
    size = path.stat().st_size
    if size < _MAP_FROM_BYTES or size == 0:
        yield path.read_bytes()
        return
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mapped:
        view = memoryview(mapped)
        try:
            yield view
        finally:
            view.release()


def _decoded(path: Path, raw) -> tuple[str, list[str]]:
    """:func:`load_text` of the bytes (or a memoryview of them) ``raw``."""
    notes = []
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError, zlib.error) as e:
            raise RecordingError(f"{path}: damaged gzip file ({' '.join(str(e).split())}); "
                                 "decompress it with gunzip to see what is left") from None
        notes.append("gzip-compressed")
    if not raw or (bytes(raw[:4096]).isspace() and bytes(raw).isspace()):  # (not raw.strip(): a copy of the file)
        raise RecordingError(f"{path}: empty file (expected a recording: a table of t, ax, ay, az)")
    kind = binary_kind(raw)
    if kind:
        raise RecordingError(f"{path}: {kind}, not a text table; export the recording as CSV")
    try:
        text = codecs.decode(raw, "utf-8-sig")
    except UnicodeDecodeError:
        text = codecs.decode(raw, "cp1252", errors="replace")
        notes.append("not UTF-8: decoded as Windows-1252")
    return text, notes


def binary_kind(raw: bytes) -> str | None:
    head = bytes(raw[:65536])
    for magic, kind in ((b"PK\x03\x04", "a zip archive (or an Excel .xlsx workbook)"),
                        (b"\x89HDF", "an HDF5 file"), (b"MATLAB 5.0", "a MATLAB .mat binary file"),
                        (b"RDX", "an R data file"), (b"\xfd7zXZ", "an xz-compressed file"),
                        (b"BZh", "a bzip2-compressed file"), (b"\xd0\xcf\x11\xe0", "an Excel .xls workbook"),
                        (b"#ROSBAG", "a ROS bag (read it with --format ros, or auto)"),
                        (b"\x89MCAP", "an MCAP file (read it with --format ros, or auto)"),
                        (b"ULog\x01\x12\x35", "a PX4 ULog (read it with --format px4, or auto)"),
                        (b"\x93NUMPY", "a numpy .npy file")):
        if head.startswith(magic):
            return kind
    if b"\x00" in head:
        return "binary data (NUL bytes)"
    control = sum(1 for b in head if b < 32 and b not in (9, 10, 13))
    if control > 0.01 * len(head):
        return "binary data (control characters)"
    return None


def is_comment(line: str) -> bool:
    s = line.lstrip()
    return s.startswith(COMMENT_MARKERS)


def content_lines(head: str) -> list[str]:
    """The non-blank, non-comment lines of ``head``, stripped (what the sniffs look at)."""
    return [ln.strip() for ln in head.splitlines() if ln.strip() and not is_comment(ln)]


def header_fields(line: str) -> set[str]:
    """The comma-separated names of a header line, stripped and in lower case."""
    return {c.strip().lower() for c in line.split(",")}
