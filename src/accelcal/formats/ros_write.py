"""A calibrated copy of a ROS bag or MCAP file: the same kind of log, its IMU topic corrected.

``accelcal apply CAL BAG --out OUT`` writes a log of the kind it read (a ROS 1 bag, a ROS 2
bag folder with sqlite3 or MCAP storage, its lone ``.db3`` file, or a bare MCAP file),
through ``rosbags``' own writers (the ``ros`` extra):

* every message of every other topic is copied byte for byte, with its record time, its
  connection's type, definition, hash, QoS profiles (ROS 2) or caller id and latching
  (ROS 1);
* the IMU topic's messages keep their header, frame id, orientation and its covariance;
  ``linear_acceleration`` (and ``angular_velocity`` when the calibration corrects the
  gyroscope) are replaced by the calibrated values, patched into the serialised message at
  the offsets the reader checks (:mod:`accelcal.formats.ros`: one frame id length fixes
  the layout), so nothing else of the message can change;
* the ``*_covariance`` fields are filled from a noise report when one is given:
  diagonal, the per-sample variance of the white noise, ``N² · f_s`` with ``N`` the noise
  density of each axis [u/√Hz] and ``f_s`` this log's IMU rate (a continuous-time density
  discretised at the sample period, as Kalibr and OpenVINS discretise theirs); without a
  report they are copied as recorded.

Outputs appear whole or not at all: the log is written beside the target under a hidden
temporary name and renamed onto it when complete.  A target that exists is refused (a bag
folder cannot be replaced atomically).  Storage details that are not content are not kept:
compression (the copy is uncompressed), the split of a ROS 2 bag into several files (the
copy is one file), the chunk size of a ROS 1 bag.
"""

from __future__ import annotations

import os
import shutil
import struct
import tempfile
from pathlib import Path

import numpy as np

from ..errors import LogFormatError
from . import ros_recover
from .logs import Progress, require_extra
from .ros import _ACC_AT, _GYRO_AT, IMU_TYPE, _Decoder, _locate, _open, _why

#: The suffix the output of each kind of log must have ("": a ROS 2 bag folder).
OUTPUT_SUFFIX = {"ROS 1 bag": ".bag", "ROS 2 bag": "", "ROS 2 bag file (sqlite3)": ".db3", "MCAP file": ".mcap"}
#: Byte offsets (from the first double) of the two covariances a noise report fills.
_GYRO_COV_AT, _ACC_COV_AT = (4 + 9 + 3) * 8, (4 + 9 + 3 + 9 + 3) * 8
_CHUNK = 8192


def check_output(src, kind: str, out) -> Path:
    """The output path of a calibrated copy of the ``kind`` log ``src``, or a one-line error."""
    out = Path(out)
    want = OUTPUT_SUFFIX[kind]
    if out.exists():
        raise LogFormatError(f"{out} exists; a calibrated log is written only to a new path (remove it or choose "
                             "another --out)")
    if want and out.suffix != want:
        raise LogFormatError(f"{src} is a {kind}: its calibrated copy is a {want} file, not {out.name} (or --out "
                             "NAME.csv for a table)")
    if not want and out.suffix in (".bag", ".mcap", ".db3", ".csv", ".yaml"):
        raise LogFormatError(f"{src} is a ROS 2 bag folder: its calibrated copy is a folder, not {out.name} (or "
                             "--out NAME.csv for a table)")
    if Path(src).resolve() == out.resolve():
        raise LogFormatError(f"--out {out} is the input itself; write the calibrated copy beside it")
    return out


def covariance_bytes(variances) -> dict:
    """``{'<': bytes, '>': bytes}`` of a diagonal 3×3 covariance (row major) of the three variances."""
    cov = np.diag(np.asarray(variances, dtype=float)).ravel()
    return {o: struct.pack(o + "9d", *cov) for o in "<>"}


def write_calibrated(src, out, *, topic: str, stamps_ns: np.ndarray, acc: np.ndarray, gyro: np.ndarray | None = None,
                     acc_cov=None, gyro_cov=None, recovered: Path | None = None, progress=None) -> dict:
    """Copy the log ``src`` to ``out`` (same kind) with the IMU ``topic`` corrected.

    Parameters
    ----------
    src, out : path-like
        The log read, and the new log (checked by :func:`check_output`).
    topic : str
        The ``sensor_msgs/Imu`` topic to correct.
    stamps_ns : ndarray of int64, shape (n,)
        The header stamps of its messages in the bag's order: each message is checked to be
        the one its values were computed from.
    acc, gyro : ndarray, shape (n, 3)
        The calibrated ``linear_acceleration`` [m/s²] and ``angular_velocity`` [rad/s] of
        the topic's n messages in the bag's order (:func:`accelcal.formats.ros.read_topic`);
        ``gyro`` None keeps the recorded rates.
    acc_cov, gyro_cov : sequence of 3 floats, optional
        Per-sample variances of each axis: the diagonal of the covariance written; None
        keeps the recorded covariance.
    recovered : path, optional
        The damaged storage file the read recovered (:attr:`TopicRead.recovered`): the copy
        holds its intact part, as the read did.

    Returns
    -------
    dict
        ``messages`` (all copied), ``corrected`` (of the topic), ``topics``.
    """
    require_extra("ros", src)
    bag_path, kind = _locate(Path(src))
    out = check_output(src, kind, out)
    patch = _Patcher(src, topic, kind == "ROS 1 bag", stamps_ns, acc, gyro, acc_cov, gyro_cov)
    tmpdir = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent if out.parent.exists() else None))
    try:
        target = tmpdir / (out.name if kind in ("ROS 1 bag", "ROS 2 bag") else "bag")
        counts = _copy(bag_path, kind, target, patch, recovered, progress)
        made = target if kind in ("ROS 1 bag", "ROS 2 bag") else next(target.glob("*" + OUTPUT_SUFFIX[kind]))
        out.parent.mkdir(parents=True, exist_ok=True)
        os.rename(made, out)  # atomic within one file system: the log appears whole
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
    if patch.i != len(acc):
        raise LogFormatError(f"{src}: topic {topic} changed while it was copied ({patch.i} messages, {len(acc)} "
                             "read)")
    return {**counts, "corrected": patch.i}


def _copy(bag_path: Path, kind: str, target: Path, patch, recovered, progress) -> dict:
    """Every message of the log into a new one at ``target``, the IMU topic's through ``patch``."""
    ros1 = kind == "ROS 1 bag"
    opened = ros_recover.recover(recovered) if recovered is not None else _open(bag_path, kind)
    with opened as reader, _Writer(target, kind, _storage(bag_path, kind)) as writer:
        conns = list(reader.connections)
        cmap = {c.id: _add_connection(writer, c, ros1) for c in conns}
        total = sum(max(int(c.msgcount or 0), 0) for c in conns)
        report = Progress(f"copying {bag_path}", total or None, progress)
        n = 0
        try:
            for conn, log_ns, raw in reader.messages():
                if conn.topic == patch.topic and conn.msgtype == IMU_TYPE:
                    raw = patch(raw)
                writer.write(cmap[conn.id], log_ns, raw)
                n += 1
                if n % 65536 == 0:
                    report(n)
        except LogFormatError:
            raise
        except Exception as e:  # a damaged block met while copying: the copy is not written
            raise LogFormatError(f"{bag_path}: {kind} damaged after {n} messages ({_why(e)}); nothing written") \
                from None
    return {"messages": n, "topics": len({c.topic for c in conns})}


def _storage(bag_path: Path, kind: str) -> str:
    if kind == "ROS 1 bag":
        return "ros1"
    if kind == "ROS 2 bag":
        return "mcap" if any(bag_path.glob("*.mcap")) else "sqlite3"
    return "mcap" if kind == "MCAP file" else "sqlite3"


class _Writer:
    """rosbags' writer of the kind read; closed (its index written) only when the copy succeeded."""

    def __init__(self, path: Path, kind: str, storage: str):
        self.path, self.kind, self.storage = path, kind, storage

    def __enter__(self):
        if self.storage == "ros1":
            from rosbags.rosbag1 import Writer

            self.w = Writer(self.path)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer

            plugin = StoragePlugin.MCAP if self.storage == "mcap" else StoragePlugin.SQLITE3
            self.w = Writer(self.path, version=Writer.VERSION_LATEST, storage_plugin=plugin)
        self.w.open()
        return self.w

    def __exit__(self, exc_type, *exc):
        try:
            self.w.close()
        except Exception:
            if exc_type is None:
                raise
        return False


def _add_connection(writer, c, ros1: bool):
    """The writer's connection for the reader's ``c``: the same topic, type, definition and options."""
    existing = [w for w in writer.connections if w.topic == c.topic and w.msgtype == c.msgtype and w.ext == c.ext]
    if existing:
        return existing[0]
    msgdef, digest = (c.msgdef.data if c.msgdef else ""), c.digest
    if ros1:
        return writer.add_connection(c.topic, c.msgtype, msgdef=msgdef, md5sum=digest, callerid=c.ext.callerid,
                                     latching=c.ext.latching)
    if not msgdef or not digest:  # older ROS 2 bags store neither: the type store supplies both
        msgdef, digest = _definition(c)
    return writer.add_connection(c.topic, c.msgtype, msgdef=msgdef, rihs01=digest,
                                 serialization_format=c.ext.serialization_format,
                                 offered_qos_profiles=c.ext.offered_qos_profiles)


def _definition(c) -> tuple[str, str]:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.LATEST)
    if c.msgtype not in store.types:
        raise LogFormatError(f"topic {c.topic} ({c.msgtype}) has no message definition in the bag and its type is not "
                             "a standard ROS 2 type: this bag cannot be written back (write a table: --out NAME.csv)")
    return store.generate_msgdef(c.msgtype, ros_version=2)[0], store.hash_rihs01(c.msgtype)


class _Patcher:
    """The calibrated values (and covariances) written into each serialised IMU message, in the bag's order."""

    def __init__(self, src, topic: str, ros1: bool, stamps_ns, acc, gyro, acc_cov, gyro_cov):
        self.topic, self.i, self.ros1 = topic, 0, ros1
        self.stamps = np.asarray(stamps_ns, dtype=np.int64).tolist()
        self.decoder = _Decoder(src, topic, ros1)
        self.acc = np.ascontiguousarray(acc, dtype=float)
        self.gyro = None if gyro is None else np.ascontiguousarray(gyro, dtype=float)
        self.acc_cov = None if acc_cov is None else covariance_bytes(acc_cov)
        self.gyro_cov = None if gyro_cov is None else covariance_bytes(gyro_cov)
        self.block = (-2 * _CHUNK, None, None)  # no chunk converted yet

    def _values(self, i: int):
        """The chunk of rows holding row ``i``, as Python floats (converted per chunk: a row costs 0.2 µs)."""
        start, a, g = self.block
        if not start <= i < start + _CHUNK:
            start = i - i % _CHUNK
            a = self.acc[start: start + _CHUNK].tolist()
            g = None if self.gyro is None else self.gyro[start: start + _CHUNK].tolist()
            self.block = (start, a, g)
        return a[i - start], None if g is None else g[i - start]

    def __call__(self, raw) -> bytes:
        i = self.i
        if i >= len(self.acc):
            raise LogFormatError(f"topic {self.topic} has more messages than were read ({len(self.acc)})")
        raw = bytes(raw)
        body, order, _ = self.decoder.layout(raw)  # checks the standard length, as the reader did
        sec, nsec = struct.unpack_from(order + ("II" if self.ros1 else "iI"), raw, 4)
        if sec * 1_000_000_000 + nsec != self.stamps[i]:
            raise LogFormatError(f"topic {self.topic}: message {i} is stamped {sec * 1_000_000_000 + nsec} ns where "
                                 f"the read gave {self.stamps[i]} ns (the bag yields its messages in another order "
                                 "when copied); nothing written")
        buf = bytearray(raw)
        a, g = self._values(i)
        struct.pack_into(order + "3d", buf, body + _ACC_AT, *a)
        if g is not None:
            struct.pack_into(order + "3d", buf, body + _GYRO_AT, *g)
        if self.acc_cov is not None:
            buf[body + _ACC_COV_AT: body + _ACC_COV_AT + 72] = self.acc_cov[order]
        if self.gyro_cov is not None:
            buf[body + _GYRO_COV_AT: body + _GYRO_COV_AT + 72] = self.gyro_cov[order]
        self.i += 1
        self.decoder.count += 1
        return bytes(buf)


__all__ = ["OUTPUT_SUFFIX", "check_output", "covariance_bytes", "write_calibrated"]
