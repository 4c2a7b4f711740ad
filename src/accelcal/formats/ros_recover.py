"""Damaged ROS 2 storage files read up to the damage: a truncated or corrupted MCAP or sqlite3 file.

A bag cut short by a crash (or a partial copy) has no MCAP summary and footer, or an
sqlite3 file shorter than its header says; ``rosbags`` refuses both whole.  Their
messages before the damage are intact, and these readers return them, with a note
saying how much was lost:

* MCAP: the records are scanned from the start (``rosbags``' own record scanner,
  :meth:`McapReader.messages_scan`, with the data section taken to run to the end of the
  file) until the first record that is incomplete or fails its check (a chunk's CRC, its
  decompression).  Every message of the complete records before it is returned.  The
  bytes from the end of the last complete record to the end of the file are lost; what the
  recording held beyond the file's end is not known (a truncated MCAP has no summary), and
  the note says so.
* sqlite3: every table-leaf page of the file is read directly (:mod:`.sqlite_pages`: the
  b-tree's interior pages are what a cut file loses first, and without them SQLite cannot
  reach the intact rows), the rows of the ``messages`` table in rowid (insertion) order.
  The header's page count is the size the file had when it was last committed: the note
  gives the share of it that is missing and the messages that share would hold at the
  density of the part read (an estimate, said so), and the rows missing between those read.

A ROS 2 bag folder whose ``metadata.yaml`` lists the message counts gives the exact
number lost per topic.  A file damaged in its header (no MCAP header record, no sqlite3
schema) has nothing to recover: the caller's one-line error stands.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import LogFormatError
from . import sqlite_pages


class Recovered:
    """A reader-like view of the intact part of a damaged storage file (``connections``, ``messages``)."""

    def __init__(self, path: Path, connections: list, rows, lost: str, cleanup=None):
        self.path, self.connections, self._rows, self.lost = path, connections, rows, lost
        self._cleanup = cleanup
        self.recovered = {c.id: c.msgcount for c in connections}

    def messages(self, connections=()):
        ids = {c.id for c in connections} if connections else None
        by_id = {c.id: c for c in self.connections}
        for cid, t, data in self._rows():
            if ids is None or cid in ids:
                yield by_id[cid], t, data

    def note(self, topic: str, expected: int | None = None) -> str:
        """The warning of a recovered read of ``topic``."""
        n = sum(c.msgcount for c in self.connections if c.topic == topic)
        exact = f"; {expected - n} of its {expected} messages are lost" if expected is not None else ""
        return (f"warning: {self.path.name} is damaged: read up to the damage, {n} messages of {topic}{exact}; "
                f"{self.lost}")

    def close(self) -> None:
        if self._cleanup is not None:
            self._cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def recover(path: Path) -> Recovered:
    """The intact part of a damaged ``.mcap`` or ``.db3`` file; LogFormatError when nothing is left."""
    if path.suffix == ".mcap":
        return _mcap(path)
    if path.suffix == ".db3":
        return _sqlite(path)
    raise LogFormatError(f"{path}: only MCAP and sqlite3 storage files are recovered")


# --------------------------------------------------------------------------- MCAP


def _mcap(path: Path) -> Recovered:
    from rosbags.rosbag2.storage_mcap import McapReader

    size = path.stat().st_size
    r = McapReader(path)
    r.bio = path.open("rb")
    try:
        head = r.bio.read(17)
        if len(head) < 17 or head[:9] != b"\x89MCAP0\r\n\x01":
            raise LogFormatError(f"{path}: no MCAP header: damaged beyond its header, nothing to recover")
        r.data_start = 17 + struct.unpack("<Q", head[9:])[0]
        r.data_end = size
        if r.data_start > size:
            raise LogFormatError(f"{path}: the MCAP header is cut: damaged beyond its header, nothing to recover")
        try:
            r.meta_scan()  # schemas and channels up to the damage
        except Exception:
            pass
        counts, good_end = _scan(r, size)
        r.bio.seek(good_end)
        tail = _tail(r, _partial_chunk(r.bio.read()))
    except BaseException:
        r.bio.close()
        raise
    for cid, _, _ in tail:
        counts[cid] = counts.get(cid, 0) + 1
    conns = [c._replace(msgcount=counts.get(c.id, 0)) for c in r.connections]
    lost = (f"the file ends in an incomplete record ({len(tail)} messages read from the incomplete chunk in the last "
            f"{_size(size - good_end)}); what the recording held beyond the file's end is not known (a cut MCAP file "
            "has no summary)")
    n = sum(counts.values()) - len(tail)

    def rows():
        r.bio.seek(r.data_start)
        if n:
            for i, (conn, t, data) in enumerate(r.messages_scan(r.connections)):
                yield conn.id, t, data
                if i + 1 >= n:  # stop before the scanner reaches the damage
                    break
        yield from tail

    return Recovered(path, conns, rows, lost, cleanup=r.bio.close)


def _scan(r, size: int) -> tuple[dict, int]:
    """Messages per channel before the first bad record, and the file offset where the good part ends."""
    counts: dict[int, int] = {}
    good_end = r.data_start
    try:
        for conn, _, _ in r.messages_scan(r.connections):
            counts[conn.id] = counts.get(conn.id, 0) + 1
            good_end = r.bio.tell()
    except Exception:  # the damage: everything before it is counted
        pass
    return counts, min(good_end, size)


def _decompressor(compression: str):
    """A streaming decompressor of the MCAP chunk compressions rosbags reads (its own dependencies)."""
    if compression == "lz4":
        from lz4.frame import LZ4FrameDecompressor

        return LZ4FrameDecompressor()
    if compression != "zstd":
        raise ValueError(compression)
    try:
        from compression import zstd
    except ImportError:  # Python < 3.14
        from backports import zstd
    return zstd.ZstdDecompressor()


def _tail(r, records: bytes) -> list:
    """(channel id, log time, data) of the messages in the complete records of an incomplete chunk, parsed by
    rosbags' own scanners (its schemas and channels too: a cut first chunk holds them)."""
    if not records:
        return []
    from io import BytesIO

    main, span = r.bio, (r.data_start, r.data_end)
    r.bio, r.data_start, r.data_end = BytesIO(records), 0, len(records)
    try:
        r.meta_scan()
        r.bio.seek(0)
        return [(c.id, t, bytes(d)) for c, t, d in r.messages_scan(r.connections)]
    except Exception:  # records that parse but do not scan: the chunk is lost whole
        return []
    finally:
        r.bio, (r.data_start, r.data_end) = main, span


def _partial_chunk(data: bytes) -> bytes:
    """The complete records at the start of an incomplete chunk (uncompressed, zstd or lz4), else b"";
    the complete records before it (the last chunk's message indexes) are skipped."""
    at = 0
    while at + 9 <= len(data) and data[at] != 0x06:
        at += 9 + struct.unpack_from("<Q", data, at + 1)[0]
    data = data[at:]
    if len(data) < 1 + 8 + 28 + 4 or data[0] != 0x06:
        return b""
    at = 1 + 8 + 28
    (k,) = struct.unpack_from("<I", data, at)
    compression = data[at + 4: at + 4 + k].decode("ascii", "replace")
    body = data[at + 4 + k + 8:]
    if compression:
        try:
            body = _decompressor(compression).decompress(body)  # streaming: what the partial frame holds
        except Exception:  # an unknown compression, or damaged bytes: the chunk is lost whole
            return b""
    i = 0
    while i + 9 <= len(body):
        length = struct.unpack_from("<Q", body, i + 1)[0]
        if i + 9 + length > len(body):
            break
        i += 9 + length
    return body[:i]


# --------------------------------------------------------------------------- sqlite3


def _sqlite(path: Path) -> Recovered:
    from rosbags.interfaces import Connection, ConnectionExtRosbag2, MessageDefinition, MessageDefinitionFormat
    from rosbags.rosbag2.metadata import parse_qos

    try:
        topics, rowids, topic_ids, pages = sqlite_pages.scan(path)
    except ValueError:
        raise LogFormatError(f"{path}: no sqlite3 header: damaged beyond its header, nothing to recover") from None
    if not topics:
        pages.close()
        raise LogFormatError(f"{path}: its topics table is lost: damaged beyond its header, nothing to recover")
    ids, counts = np.unique(topic_ids, return_counts=True)
    counts = dict(zip(ids.tolist(), counts.tolist()))
    conns = [Connection(cid, name, typ, MessageDefinition(MessageDefinitionFormat.NONE, ""), "", counts.get(cid, 0),
                        ConnectionExtRosbag2(fmt, _qos(parse_qos, qos)), None) for cid, name, typ, fmt, qos in topics]
    have = pages.pages * pages.page_size
    read = len(rowids)
    gaps = int(rowids[-1] - rowids[0] + 1 - read) if read else 0
    if pages.stated > have:
        share = 1 - have / pages.stated
        lost = (f"the file holds {have / pages.stated:.1%} of the {_size(pages.stated)} its header states: about "
                f"{round(read * share / (1 - share))} more messages (at the density of the part read) are lost")
    else:
        lost = "the damage is inside the file (its size is the one its header states)"
    if gaps:
        lost += f"; {gaps} rows between the first and the last read are missing (damaged pages)"
    return Recovered(path, conns, lambda: sqlite_pages.rows(pages), lost, cleanup=pages.close)


def _qos(parse_qos, text: str) -> list:
    try:
        return parse_qos(text)
    except Exception:  # an unreadable QoS string: the copy offers the default
        return []


def _size(n: int) -> str:
    return f"{n / 2**20:.3g} MB" if n >= 2**20 else f"{n / 1024:.3g} kB" if n >= 1024 else f"{n} bytes"


__all__ = ["Recovered", "recover"]
