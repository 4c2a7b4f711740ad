"""ROS 1 bags, ROS 2 bags (sqlite3 or MCAP, a bag folder or its storage file) and bare MCAP files.

Read through the ``rosbags`` library (pure Python, the ``ros`` extra), one
``sensor_msgs/Imu`` topic into a :class:`~accelcal.recording.Recording`:
``linear_acceleration`` [m/s²] as ``acc``, ``angular_velocity`` [rad/s] as ``gyro``.

Type stores: ROS 1 messages are checked against the ROS 1 (Noetic) definition of
``sensor_msgs/Imu`` (its md5 sum, which every ROS 1 bag stores), ROS 2 messages against
the newest ROS 2 store (the RIHS01 hash where the bag stores one); the definition has
not changed between distributions.  A topic of that name with another definition is
refused rather than misread.

Decoding.  ``rosbags`` deserialises a message into Python objects at about 16 µs each,
as much again as iterating the bag; an hour at 400 Hz would spend half a minute there.
``sensor_msgs/Imu`` has one variable-length field, ``header.frame_id``, before 37
doubles, so the layout of a message follows from its frame id's length (CDR aligns the
doubles to 8 bytes; ROS 1 serialisation does not align): messages are gathered in
chunks of :data:`CHUNK` raw byte strings and decoded together with numpy.  Every message
is checked to have exactly the standard length for its frame id, and the first one is
also deserialised by ``rosbags`` and compared, so a layout that is not the standard one
cannot be read silently wrong.  Memory: the output arrays (preallocated from the bag's
message count) plus one chunk.

Time: ``time_source='header'`` (default) uses ``header.stamp``, ``'log'`` the time the
bag recorded the message; ``t`` is seconds since the first sample, and the recorded
nanoseconds are kept as the recording's time column (``header_stamp_ns`` or
``log_time_ns``).
"""

from __future__ import annotations

import struct
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import LogFormatError, RecordingError, TopicError
from ..recording import checked_recording
from . import ros_recover
from .clock import looks_like_counter
from .logs import (ColumnBuffer, Progress, check_time_source, choose, clock_note, make_recording, require_extra,
                   stamps_to_time, topic_origin)
from .ros_mag import add_magnetometer

IMU_TYPE = "sensor_msgs/msg/Imu"
ROS1_MAGIC = b"#ROSBAG V2.0\n"
MCAP_MAGIC = b"\x89MCAP0\r\n"
SQLITE_MAGIC = b"SQLite format 3\x00"
#: Raw messages decoded together (bounded memory: CHUNK × ~330 bytes).
CHUNK = 8192
#: Bytes of the 37 doubles after the header: orientation (4), its covariance (9),
#: angular_velocity (3), covariance (9), linear_acceleration (3), covariance (9).
_BODY = 37 * 8
_GYRO_AT, _ACC_AT = (4 + 9) * 8, (4 + 9 + 3 + 9) * 8


def sniff(path, head: bytes) -> bool:
    """True for a ROS 1 bag, a ROS 2 bag folder (or its metadata.yaml), a .db3 bag file or an MCAP file."""
    path = Path(path)
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    if path.name == "metadata.yaml":
        return head.lstrip().startswith(b"rosbag2_bagfile_information")
    return head.startswith(ROS1_MAGIC) or head.startswith(MCAP_MAGIC) or \
        (head.startswith(SQLITE_MAGIC) and path.suffix == ".db3")


def read(path, *, topic: str | None = None, time_source: str = "header", progress=None, mag_topic: str | None = None):
    """Read the ``sensor_msgs/Imu`` topic of a ROS bag or MCAP file.

    Parameters
    ----------
    path : path-like
        ROS 1 ``.bag``; ROS 2 bag folder, its ``metadata.yaml``, or its ``.db3`` / ``.mcap``
        storage file; a bare ``.mcap`` file.
    topic : str, optional
        The IMU topic; default the only ``sensor_msgs/Imu`` topic (several: an error
        that lists them).
    time_source : {'header', 'log'}
        ``header.stamp`` (default) or the bag's record time.
    progress : None, False or callable
        Progress on stderr after 2 s (None), silent (False), or ``f(done, total)``.
    mag_topic : str, optional
        The ``sensor_msgs/MagneticField`` topic; default the only one (:mod:`.ros_mag`).

    Returns
    -------
    Recording
        ``acc`` [m/s²], ``gyro`` [rad/s], ``t`` [s] from the first sample, ``mag`` [µT] on the
        rows nearest its samples (NaN between them), ``notes``.

    Raises
    ------
    MissingExtraError, LogFormatError, TopicError
        One line naming the cause and the fix.
    """
    return read_topic(path, topic=topic, time_source=time_source, progress=progress, mag_topic=mag_topic).recording


class TopicRead(NamedTuple):
    """:func:`read_topic`'s result: the recording and what a writer of the same bag needs."""

    recording: object
    order: np.ndarray       # order[r]: index, among the topic's messages in the bag's order, of recording row r
    topic: str
    kind: str               # "ROS 1 bag", "ROS 2 bag", "ROS 2 bag file (sqlite3)" or "MCAP file"
    header_ns: np.ndarray   # header stamps [ns] of the topic's messages in the bag's order
    recovered: Path | None = None  # the damaged storage file read up to its damage (formats.ros_recover)


def read_topic(path, *, topic: str | None = None, time_source: str = "header", progress=None,
               mag_topic: str | None = False) -> TopicRead:
    """:func:`read`, with the bag's order of the messages (the recording's rows are sorted by
    header stamp when the bag recorded some out of order); ``mag_topic=False``: no magnetometer.
    The recording is checked as :func:`accelcal.formats.read` checks every reader's
    (:func:`~accelcal.recording.checked_recording`): ``accelcal apply`` reads a bag through here."""
    check_time_source(time_source)
    path = Path(path)
    require_extra("ros", path)
    bag_path, kind = _locate(path)
    try:
        with _open(bag_path, kind) as reader:
            got = _read_open(reader, path, bag_path, kind, topic, time_source, progress, mag_topic)
        return got._replace(recording=checked_recording(got.recording))
    except DamagedBagError as damaged:
        storage = storage_file(bag_path, kind)
        if storage is None:
            raise
        try:
            reader = ros_recover.recover(storage)
        except Exception as e:  # damaged beyond its header: the first error, and why nothing is left
            why = str(e).split(": ", 1)[-1] if isinstance(e, LogFormatError) else f"recovery failed: {_why(e)}"
            raise LogFormatError(f"{damaged}; {why}") from None
        try:
            got = _read_open(reader, path, bag_path, kind, topic, time_source, progress, mag_topic)
            got = got._replace(recording=checked_recording(got.recording))
        except RecordingError as e:  # nothing usable before the damage
            raise LogFormatError(f"{damaged}; read up to the damage: {str(e).split(': ', 1)[-1]}") from None
        finally:
            reader.close()
        note = reader.note(got.topic, _expected_count(bag_path, kind, got.topic))
        rec = replace(got.recording, notes=got.recording.notes + (note,))
        return got._replace(recording=rec, recovered=storage)


def _read_open(reader, path, bag_path, kind, topic, time_source, progress, mag_topic) -> TopicRead:
    """The topic of an open reader (a rosbags reader, or the intact part of a damaged file)."""
    from rosbags.typesys import Stores, get_typestore

    ros1 = kind == "ROS 1 bag"
    typestore = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.LATEST)
    conns = _connections(reader, bag_path, kind)
    everything = {c.topic: f"{c.msgtype}, {c.msgcount} messages" for c in conns}
    imu = {c.topic: f"{c.msgcount} messages" for c in conns if c.msgtype == IMU_TYPE}
    name = choose(path, imu, topic, everything, kind="sensor_msgs/Imu topic", option="--topic")
    mine = [c for c in conns if c.topic == name]
    _check_definition(path, name, mine, typestore, ros1)
    count = sum(max(int(c.msgcount or 0), 0) for c in mine)
    decoded = _stream(reader, mine, path, name, kind, count, ros1, typestore, progress)
    rec, order = _recording(path, name, kind, decoded, time_source)
    if mag_topic is not False:
        rec = add_magnetometer(rec, reader, conns, path, kind, ros1, typestore, mag_topic, time_source,
                               decoded["stamps"][:, :2][_rows(decoded, time_source)])
    return TopicRead(rec, order, name, kind, decoded["stamps"][:, 0].copy())


def _rows(decoded, time_source: str) -> np.ndarray:
    """The bag's message indices in the recording's row order (sorted by header stamp, as :func:`_recording`)."""
    head = decoded["stamps"][:, 0]
    late = time_source == "header" and np.any(np.diff(head) < 0)
    return np.argsort(head, kind="stable") if late else np.arange(len(head))


def _locate(path: Path) -> tuple[Path, str]:
    """The path rosbags opens and the kind of log, or a one-line error."""
    if not path.exists():
        raise LogFormatError(f"{path}: no such file or folder")
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise LogFormatError(f"{path}: a folder without metadata.yaml is not a ROS 2 bag; give the .db3 or .mcap "
                                 "file inside it")
        return path, "ROS 2 bag"
    if path.name == "metadata.yaml":
        return path.parent, "ROS 2 bag"
    with open(path, "rb") as f:
        head = f.read(16)
    if head.startswith(ROS1_MAGIC):
        return path, "ROS 1 bag"
    if head.startswith(MCAP_MAGIC):
        if path.suffix != ".mcap":
            raise LogFormatError(f"{path}: an MCAP file named without .mcap; rename it to end in .mcap")
        return path, "MCAP file"
    if head.startswith(SQLITE_MAGIC) and path.suffix == ".db3":
        return path, "ROS 2 bag file (sqlite3)"
    raise LogFormatError(f"{path}: not a ROS bag or MCAP file (no ROS 1, MCAP or sqlite3 signature)")


class DamagedBagError(LogFormatError):
    """A bag rosbags cannot open or read through; its MCAP or sqlite3 storage may be recovered."""


def storage_file(bag_path: Path, kind: str) -> Path | None:
    """The one MCAP or sqlite3 file of a log, which :mod:`.ros_recover` can read up to a damage (else None)."""
    if kind in ("MCAP file", "ROS 2 bag file (sqlite3)"):
        return bag_path
    if kind == "ROS 2 bag":
        files = sorted([*bag_path.glob("*.mcap"), *bag_path.glob("*.db3")])
        return files[0] if len(files) == 1 else None
    return None


def _expected_count(bag_path: Path, kind: str, topic: str) -> int | None:
    """The topic's message count in a ROS 2 bag's metadata.yaml (None when there is none)."""
    if kind != "ROS 2 bag":
        return None
    from ruamel.yaml import YAML  # rosbags' own YAML parser

    try:
        meta = YAML(typ="safe").load((bag_path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
        return next(int(t["message_count"]) for t in meta["topics_with_message_count"]
                    if t["topic_metadata"]["name"] == topic)
    except Exception:  # no usable count: the note estimates instead
        return None


class _open:
    """Open a bag with rosbags; every failure becomes one LogFormatError line."""

    def __init__(self, path: Path, kind: str):
        self.path, self.kind = path, kind

    def __enter__(self):
        try:
            if self.kind == "ROS 1 bag":
                from rosbags.rosbag1 import Reader
            else:
                from rosbags.rosbag2 import Reader
            self.reader = Reader(self.path)
            self.reader.open()
        except Exception as e:  # rosbags, sqlite3, struct, yaml, zstd: all mean a damaged or foreign file
            raise DamagedBagError(f"{self.path}: cannot open this {self.kind} ({_why(e)}); "
                                  f"{_fix(self.kind)}") from None
        return self.reader

    def __exit__(self, *exc):
        try:
            self.reader.close()
        except Exception:  # closing a damaged bag may fail again; the first error is the one to report
            pass
        return False


def _why(e: Exception) -> str:
    text = " ".join(str(e).split()) or type(e).__name__
    return text[:160]


def _fix(kind: str) -> str:
    if kind == "ROS 1 bag":
        return "the bag is damaged or was not closed (an unindexed bag: run `rosbag reindex` on it)"
    return "the bag is damaged or truncated (a bag still being recorded, or a partial copy): record or copy it again"


def _connections(reader, path, kind):
    try:
        return list(reader.connections)
    except Exception as e:
        raise DamagedBagError(f"{path}: cannot list the topics of this {kind} ({_why(e)}); {_fix(kind)}") from None


def _check_definition(path, topic, conns, typestore, ros1: bool) -> None:
    """Refuse a topic typed sensor_msgs/Imu whose stored definition is not the standard one."""
    for c in conns:
        if ros1:
            want = typestore.generate_msgdef(IMU_TYPE)[1]
            if c.digest and c.digest != want:
                raise TopicError(f"{path}: topic {topic} is sensor_msgs/Imu with a non-standard definition "
                                 f"(md5 {c.digest}, the standard one is {want}); it cannot be read as an IMU")
        elif c.digest and c.digest.startswith("RIHS01_") and c.digest != typestore.hash_rihs01(IMU_TYPE):
            raise TopicError(f"{path}: topic {topic} is sensor_msgs/msg/Imu with a non-standard definition "
                             f"(type hash {c.digest[:20]}...); it cannot be read as an IMU")


def _stream(reader, conns, path, topic, kind, count, ros1, typestore, progress) -> dict:
    """Decode every message of the topic into preallocated arrays (module docstring)."""
    floats = ColumnBuffer(count, 6)
    stamps = ColumnBuffer(count, 3, np.int64)  # header stamp, record time, header.seq (ROS 1; else -1)
    report = Progress(f"{path} {topic}", count or None, progress)
    decoder = _Decoder(path, topic, ros1)
    raws, logs, frames = [], [], set()
    first = True
    try:
        for _, log_ns, raw in reader.messages(connections=conns):
            if first:
                _compare_with_rosbags(path, topic, raw, ros1, typestore, decoder)
                first = False
            raws.append(bytes(raw))
            logs.append(log_ns)
            if len(raws) == CHUNK:
                decoder.flush(raws, logs, floats, stamps, frames)
                report(floats.n)
        decoder.flush(raws, logs, floats, stamps, frames)
    except (LogFormatError, TopicError):
        raise
    except Exception as e:  # a damaged chunk, index or compressed block in the middle of the bag
        raise DamagedBagError(f"{path}: {kind} damaged after {floats.n + len(raws)} messages of {topic} "
                              f"({_why(e)}); {_fix(kind)}") from None
    return {"floats": floats.result(), "stamps": stamps.result(), "frames": frames}


class _Decoder:
    """Numpy decoding of raw ``sensor_msgs/Imu`` messages, ROS 1 or CDR (module docstring)."""

    def __init__(self, path, topic, ros1: bool):
        self.path, self.topic, self.ros1 = path, topic, ros1
        self.count = 0

    def layout(self, raw: bytes) -> tuple[int, str, int]:
        """(offset of the first double, byte order, frame id length) of one message; checks its length."""
        n = len(raw)
        if self.ros1:  # seq, secs, nsecs, string length: little-endian, no alignment
            if n < 16:
                self._short(n, 16)
            flen = struct.unpack_from("<I", raw, 12)[0]
            body, order = 16 + flen, "<"
        else:  # 4-byte encapsulation header, then the CDR payload; doubles aligned to 8 within it
            if n < 16 or raw[0] != 0 or raw[1] not in (0, 1):
                raise LogFormatError(f"{self.path}: topic {self.topic}: message {self.count} is not plain CDR "
                                     f"(encapsulation {raw[:2].hex() if n >= 2 else 'missing'})")
            order = "<" if raw[1] == 1 else ">"
            flen = struct.unpack_from(order + "I", raw, 12)[0]
            body = 4 + -(-(12 + flen) // 8) * 8
        if n != body + _BODY:
            self._short(n, body + _BODY)
        return body, order, flen

    def _short(self, n: int, want: int) -> None:
        raise LogFormatError(f"{self.path}: topic {self.topic}: message {self.count} has {n} bytes where a standard "
                             f"sensor_msgs/Imu with its frame id has {want} (truncated or not the standard type)")

    def flush(self, raws: list, logs: list, floats: ColumnBuffer, stamps: ColumnBuffer, frames: set) -> None:
        if not raws:
            return
        lay = [self.layout(r) for r in raws] if len({len(r) for r in raws}) > 1 else None
        if lay is None:
            body, order, flen = self.layout(raws[0])
            block = np.frombuffer(b"".join(raws), dtype=np.uint8).reshape(len(raws), -1)
            flens = _field(block, 12, order + "u4")
            if np.all(flens == flen):
                floats.extend(np.hstack([_field(block, body + _ACC_AT, order + "f8", 3),
                                         _field(block, body + _GYRO_AT, order + "f8", 3)]))
                # both serialisations put the stamp at byte 4 and the frame id's characters at byte 16
                sec = _field(block, 4, order + ("u4" if self.ros1 else "i4")).astype(np.int64)
                nsec = _field(block, 8, order + "u4").astype(np.int64)
                seq = _field(block, 0, order + "u4").astype(np.int64) if self.ros1 else np.full(len(raws), -1)
                stamps.extend(np.column_stack([sec * 1_000_000_000 + nsec, np.asarray(logs, dtype=np.int64), seq]))
                frames.add(bytes(block[0, 16:16 + flen]).rstrip(b"\0"))
                self.count += len(raws)
                raws.clear()
                logs.clear()
                return
            lay = [self.layout(r) for r in raws]
        for raw, log_ns, (body, order, flen) in zip(raws, logs, lay):  # frame ids of varying length: one by one
            acc = struct.unpack_from(order + "3d", raw, body + _ACC_AT)
            gyro = struct.unpack_from(order + "3d", raw, body + _GYRO_AT)
            sec, nsec = struct.unpack_from(order + ("II" if self.ros1 else "iI"), raw, 4)
            floats.extend(np.array([acc + gyro]))
            seq = struct.unpack_from(order + "I", raw, 0)[0] if self.ros1 else -1
            stamps.extend(np.array([[sec * 1_000_000_000 + nsec, log_ns, seq]], dtype=np.int64))
            frames.add(raw[16:16 + flen].rstrip(b"\0"))
            self.count += 1
        raws.clear()
        logs.clear()


def _field(block: np.ndarray, at: int, dtype: str, k: int = 1) -> np.ndarray:
    """Column ``at`` .. ``at + k·size`` of a block of equal-length messages as values of ``dtype``."""
    size = np.dtype(dtype).itemsize
    out = np.ascontiguousarray(block[:, at: at + k * size]).view(dtype)
    return out if k > 1 else out[:, 0]


def _compare_with_rosbags(path, topic, raw, ros1, typestore, decoder) -> None:
    """Deserialise the first message with rosbags too: the fast layout must give the same numbers."""
    try:
        msg = typestore.deserialize_ros1(raw, IMU_TYPE) if ros1 else typestore.deserialize_cdr(raw, IMU_TYPE)
    except Exception as e:
        raise LogFormatError(f"{path}: topic {topic}: the first message does not deserialise as sensor_msgs/Imu "
                             f"({_why(e)})") from None
    body, order, _ = decoder.layout(bytes(raw))
    fast = struct.unpack_from(order + "3d", raw, body + _ACC_AT) + struct.unpack_from(order + "3d", raw,
                                                                                      body + _GYRO_AT)
    ref = (msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z,
           msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z)
    if not np.array_equal(np.array(fast), np.array(ref), equal_nan=True):
        raise LogFormatError(f"{path}: topic {topic}: the message layout is not the standard sensor_msgs/Imu")


def _recording(path, topic, kind, decoded, time_source):
    floats, stamps = decoded["floats"], decoded["stamps"]
    acc, gyro = floats[:, :3], floats[:, 3:]
    header_ns, log_ns, seq = stamps[:, 0], stamps[:, 1], stamps[:, 2]
    order = np.arange(len(acc))
    frames = ", ".join(sorted(f.decode("utf-8", "replace") or "''" for f in decoded["frames"]))
    notes = [f"{kind}, topic {topic} (sensor_msgs/Imu, frame {frames}): {len(acc)} messages; "
             "linear_acceleration [m/s^2] and angular_velocity [rad/s]"]
    if time_source == "header":
        if len(header_ns) and np.all(header_ns == 0):
            raise LogFormatError(f"{path}: topic {topic}: every header stamp is zero (the driver does not stamp its "
                                 "messages); use the bag's record time (--time-source log)")
        late = int(np.sum(np.diff(header_ns) < 0))
        if late:  # a bag is in record order: latency jitter can swap messages the sensor stamped in order
            order = np.argsort(header_ns, kind="stable")
            acc, gyro, header_ns, log_ns, seq = acc[order], gyro[order], header_ns[order], log_ns[order], seq[order]
            notes.append(f"{late} message(s) were recorded out of header-stamp order: sorted by header stamp")
        t = stamps_to_time(header_ns)
        stamp, fix = "header.stamp", "the driver's stamps are not in order; use the bag's record time (--time-source log)"
        notes.append("time: header.stamp, t = 0 at the first message")
        time_col = ("header_stamp_ns", header_ns.copy())
    else:
        t = stamps_to_time(log_ns)
        stamp, fix = "the bag's record time", "the bag is damaged"
        notes.append("time: the bag's record time (--time-source log), t = 0 at the first message")
        time_col = ("log_time_ns", log_ns.copy())
    note = clock_note(header_ns, log_ns, "header stamps", "bag record times")
    if note and np.any(header_ns != 0):
        notes.append(f"warning: {note}; {'header stamps used' if time_source == 'header' else 'record times used'}")
    # ROS 1 numbers each message in header.seq (a counter of the publisher's messages: one per sample);
    # drivers that leave it 0 number nothing
    counter = seq if np.all(seq >= 0) and looks_like_counter(seq) else None
    origin = topic_origin(f"topic {topic}", time=stamp, time_fix=fix, numbers=order,
                          acc=tuple(f"linear_acceleration.{a}" for a in "xyz"),
                          gyro=tuple(f"angular_velocity.{a}" for a in "xyz"))
    rec = make_recording(path, t=t, acc=acc, gyro=gyro, notes=notes, time_name=time_col[0], time_values=time_col[1],
                         counter=counter, counter_name="header.seq", origin=origin)
    return rec, order


__all__ = ["IMU_TYPE", "TopicRead", "read", "read_topic", "sniff"]
