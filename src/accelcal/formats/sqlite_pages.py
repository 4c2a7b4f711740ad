"""The rows of a damaged rosbag2 sqlite3 file, read from its table-leaf pages (SQLite's file format).

SQLite reaches a row through its table's b-tree; in a file cut short (a crash while
recording, a partial copy) the interior pages a growing table allocated last are often
missing, and then every row beneath them is unreachable through SQL although its leaf
page is intact.  As SQLite's own ``.recover`` does, this reads every table-leaf page of the
file directly (https://www.sqlite.org/fileformat2.html: page header, cell pointers, cell =
payload size, rowid, record; record = header of serial types, then values; payloads longer
than a page continue in a chain of overflow pages) and keeps the records shaped as
rosbag2's two tables::

    messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB)
    topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT,
           offered_qos_profiles TEXT[, type_description_hash TEXT])

(the ``id`` column, an alias of the rowid, is stored as NULL).  A row whose overflow chain
runs into a missing page is dropped.  Rows are returned in rowid order (rosbag2 inserts
in the order it receives the messages); a rowid met twice (a stale copy on a freed page)
is kept once.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

_TABLE_LEAF = 0x0D


class SqlitePages:
    """The table-leaf pages of one sqlite3 file, read without SQLite."""

    def __init__(self, path: Path):
        self.f = open(path, "rb")
        head = self.f.read(100)
        if len(head) < 100 or not head.startswith(b"SQLite format 3\x00"):
            self.f.close()
            raise ValueError("no sqlite3 header")
        page = struct.unpack(">H", head[16:18])[0]
        self.page_size = 65536 if page == 1 else page
        self.usable = self.page_size - head[20]
        self.size = path.stat().st_size
        self.pages = self.size // self.page_size
        self.stated = struct.unpack(">I", head[28:32])[0] * self.page_size

    def close(self) -> None:
        self.f.close()

    def page(self, n: int) -> bytes | None:
        """Page ``n`` (1-based), or None beyond the end of the file."""
        if not 1 <= n <= self.pages:
            return None
        self.f.seek((n - 1) * self.page_size)
        return self.f.read(self.page_size)

    def cells(self, n: int, data: bytes):
        """(rowid, record values) of every cell of table-leaf page ``n``; nothing for other pages."""
        base = 100 if n == 1 else 0
        if len(data) < base + 8 or data[base] != _TABLE_LEAF:
            return
        count = struct.unpack_from(">H", data, base + 3)[0]
        for k in range(count):
            at = struct.unpack_from(">H", data, base + 8 + 2 * k)[0]
            try:
                payload_size, at = _varint(data, at)
                rowid, at = _varint(data, at)
                payload = self._payload(data, at, payload_size)
                values = _record(payload) if payload is not None else None
            except (IndexError, struct.error, ValueError):  # a damaged cell
                continue
            if values is not None:
                yield rowid, values

    def _payload(self, data: bytes, at: int, size: int) -> bytes | None:
        x = self.usable - 35
        if size <= x:
            return data[at: at + size]
        m = (self.usable - 12) * 32 // 255 - 23
        k = m + (size - m) % (self.usable - 4)
        local = k if k <= x else m
        parts, got = [data[at: at + local]], local
        nxt = struct.unpack_from(">I", data, at + local)[0]
        while got < size:
            page = self.page(nxt)
            if page is None:
                return None  # the chain runs into a missing page: the row is lost
            take = min(size - got, self.usable - 4)
            parts.append(page[4: 4 + take])
            got += take
            nxt = struct.unpack_from(">I", page, 0)[0]
        return b"".join(parts)


def _varint(b: bytes, at: int) -> tuple[int, int]:
    v = 0
    for i in range(8):
        c = b[at + i]
        v = (v << 7) | (c & 0x7F)
        if c < 0x80:
            return v, at + i + 1
    return (v << 8) | b[at + 8], at + 9


_INT_SIZES = {1: 1, 2: 2, 3: 3, 4: 4, 5: 6, 6: 8}


def _record(p: bytes) -> list:
    """The values of one SQLite record (ints, floats, bytes for blobs, str for texts, None)."""
    hsize, at = _varint(p, 0)
    types = []
    while at < hsize:
        t, at = _varint(p, at)
        types.append(t)
    out, at = [], hsize
    for t in types:
        if t == 0:
            out.append(None)
        elif t in _INT_SIZES:
            n = _INT_SIZES[t]
            out.append(int.from_bytes(p[at: at + n], "big", signed=True))
            at += n
        elif t == 7:
            out.append(struct.unpack_from(">d", p, at)[0])
            at += 8
        elif t in (8, 9):
            out.append(t - 8)
        elif t >= 12:
            n = (t - 12) // 2
            if at + n > len(p):
                raise ValueError("record runs past its payload")
            out.append(p[at: at + n] if t % 2 == 0 else p[at: at + n].decode("utf-8", "replace"))
            at += n
        else:
            raise ValueError(f"serial type {t}")
    return out


def _is_message(v: list) -> bool:
    return len(v) == 4 and v[0] is None and type(v[1]) is int and type(v[2]) is int and type(v[3]) is bytes


def _is_topic(v: list) -> bool:
    return (len(v) in (5, 6) and v[0] is None and all(isinstance(x, str) for x in v[1:])
            and v[1].startswith("/") and "/" in v[2])


def scan(path: Path) -> tuple[list, np.ndarray, np.ndarray, SqlitePages]:
    """(topics rows (rowid, name, type, serialization format, QoS text), message rowids and topic ids in rowid
    order, the open file) of a damaged rosbag2 sqlite3 file.  The message pages are read again by
    :func:`rows`."""
    pages = SqlitePages(path)
    topics, rowids, topic_ids, where = {}, [], [], []
    for n in range(1, pages.pages + 1):
        data = pages.page(n)
        for rowid, v in pages.cells(n, data):
            if _is_message(v):
                rowids.append(rowid)
                topic_ids.append(v[1])
                where.append(n)
            elif _is_topic(v):
                topics[rowid] = (rowid, v[1], v[2], v[3], v[4])
    rowids, topic_ids, where = (np.asarray(x, dtype=np.int64) for x in (rowids, topic_ids, where))
    order = np.argsort(rowids, kind="stable")
    keep = np.ones(len(order), bool)
    keep[1:] = np.diff(rowids[order]) != 0
    order = order[keep]
    pages.order = (rowids[order], where[order])
    return sorted(topics.values()), rowids[order], topic_ids[order], pages


def rows(pages: SqlitePages):
    """(topic id, timestamp, data) of the messages :func:`scan` found, in rowid order."""
    ids, where = pages.order
    cache: dict[int, dict] = {}
    for rowid, n in zip(ids.tolist(), where.tolist()):
        if n not in cache:
            cache.clear()  # rows come page after page: one page's cells at a time
            cache[n] = {r: v for r, v in pages.cells(n, pages.page(n)) if _is_message(v)}
        v = cache[n][rowid]
        yield v[1], v[2], v[3]


__all__ = ["SqlitePages", "rows", "scan"]
