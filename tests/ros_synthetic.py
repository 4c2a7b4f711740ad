"""Write IMU samples as a ROS bag or MCAP file with ``rosbags``' own writers (test fixtures, benchmarks).

``write_imu_bag`` turns arrays into a ``sensor_msgs/Imu`` topic of a ROS 1 bag, a ROS 2
bag (sqlite3 or MCAP storage) or a bare MCAP file.  Messages are serialised by
``rosbags``' type store (``serialize='rosbags'``, the default: what the tests use, so the
readers are checked against an independent serialiser), or, for the hour-long benchmark
log, by numpy in chunks (``serialize='fast'``), whose first message is checked to be
byte-identical to ``rosbags``' serialisation of the same message.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from accelcal.errors import AccelcalError
from accelcal.formats.logs import require_extra

KINDS = ("ros1", "ros2-sqlite3", "ros2-mcap", "mcap")
_CHUNK = 20000


def write_imu_bag(path, t, acc, gyro, *, kind: str = "ros2-sqlite3", topic: str = "/imu", frame_id: str = "imu_link",
                  latency_s=0.002, extra_topics: dict | None = None, serialize: str = "rosbags",
                  mag: dict | None = None) -> Path:
    """Write a ``sensor_msgs/Imu`` topic; returns the path to give to a reader.

    Parameters
    ----------
    path : path-like
        The bag file (``ros1``: ``.bag``; ``mcap``: ``.mcap``) or folder (``ros2-*``); must not exist.
    t : array_like, shape (n,)
        Header stamps [s] (absolute, e.g. Unix time).
    acc, gyro : array_like, shape (n, 3)
        ``linear_acceleration`` [m/s²] and ``angular_velocity`` [rad/s].
    kind : {'ros1', 'ros2-sqlite3', 'ros2-mcap', 'mcap'}
        ``mcap`` writes a ROS 2 bag with MCAP storage and returns its ``.mcap`` file alone.
    latency_s : float or array_like
        Record time minus header stamp.
    extra_topics : dict, optional
        ``{topic: msgtype}`` of other topics to add, each with one default message per IMU
        sample time (``sensor_msgs/msg/Imu`` for a second IMU topic).
    serialize : {'rosbags', 'fast'}
        See the module docstring.
    mag : dict, optional
        ``{topic: (t [s], field [T] (k, 3), latency [s])}``: ``sensor_msgs/MagneticField`` topics,
        written in record-time order among the IMU's messages.
    """
    require_extra("ros")
    from rosbags.typesys import Stores, get_typestore

    if kind not in KINDS:
        raise AccelcalError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    t = np.asarray(t, dtype=float)
    acc, gyro = np.asarray(acc, dtype=float), np.asarray(gyro, dtype=float)
    stamp_ns = np.round(t * 1e9).astype(np.int64)
    log_ns = stamp_ns + np.round(np.broadcast_to(latency_s, t.shape) * 1e9).astype(np.int64)
    ros1 = kind == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.LATEST)
    path = Path(path)
    # a bare MCAP file is the storage file of a ROS 2 bag written beside it, then moved out
    target = Path(tempfile.mkdtemp(prefix=".mcap-", dir=path.parent)) / "bag" if kind == "mcap" else path
    with _writer(target, kind) as w:
        conn = _connection(w, topic, "sensor_msgs/msg/Imu", store, ros1)
        extras = [(_connection(w, name, typ, store, ros1), typ) for name, typ in (extra_topics or {}).items()]
        pending = _mag_messages(w, store, ros1, mag or {})
        for a in range(0, len(t), _CHUNK):
            b = min(a + _CHUNK, len(t))
            raws = _serialize(store, ros1, stamp_ns[a:b], acc[a:b], gyro[a:b], frame_id, serialize)
            for i, raw in enumerate(raws):
                while pending and pending[-1][0] <= log_ns[a + i]:
                    w.write(*pending.pop()[1:])
                w.write(conn, int(log_ns[a + i]), raw)
                for c, typ in extras:
                    w.write(c, int(log_ns[a + i]) + 1, _default_message(store, typ, ros1))
        for _, c, ns, raw in reversed(pending):
            w.write(c, ns, raw)
    if kind != "mcap":
        return path
    inner = next(target.glob("*.mcap"))
    shutil.move(str(inner), path)
    shutil.rmtree(target.parent)
    return path


class _writer:
    def __init__(self, path: Path, kind: str):
        self.path, self.kind = path, kind

    def __enter__(self):
        if self.kind == "ros1":
            from rosbags.rosbag1 import Writer

            self.w = Writer(self.path)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer

            plugin = StoragePlugin.SQLITE3 if self.kind == "ros2-sqlite3" else StoragePlugin.MCAP
            self.w = Writer(self.path, version=Writer.VERSION_LATEST, storage_plugin=plugin)
        self.w.open()
        return self.w

    def __exit__(self, *exc):
        self.w.close()
        return False


def _connection(w, topic, msgtype, store, ros1):
    return w.add_connection(topic, msgtype, typestore=store)


def _message(store, stamp_ns: int, acc, gyro, frame_id: str):
    types = store.types
    Time = types["builtin_interfaces/msg/Time"]
    Header = types["std_msgs/msg/Header"]
    Vec = types["geometry_msgs/msg/Vector3"]
    Quat = types["geometry_msgs/msg/Quaternion"]
    Imu = types["sensor_msgs/msg/Imu"]
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    z9 = np.zeros(9)
    header = Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=frame_id) if "seq" not in Header.__dataclass_fields__ \
        else Header(seq=0, stamp=Time(sec=sec, nanosec=nsec), frame_id=frame_id)
    return Imu(header=header, orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=z9,
               angular_velocity=Vec(x=float(gyro[0]), y=float(gyro[1]), z=float(gyro[2])),
               angular_velocity_covariance=z9,
               linear_acceleration=Vec(x=float(acc[0]), y=float(acc[1]), z=float(acc[2])),
               linear_acceleration_covariance=z9)


def _serialize(store, ros1, stamp_ns, acc, gyro, frame_id, how):
    ser = store.serialize_ros1 if ros1 else store.serialize_cdr
    if how == "rosbags":
        return [bytes(ser(_message(store, s, a, g, frame_id), "sensor_msgs/msg/Imu")) for s, a, g in
                zip(stamp_ns, acc, gyro)]
    raws = _fast(ros1, stamp_ns, acc, gyro, frame_id)
    ref = bytes(ser(_message(store, stamp_ns[0], acc[0], gyro[0], frame_id), "sensor_msgs/msg/Imu"))
    if raws[0] != ref:
        raise AccelcalError("the fast serialiser does not reproduce rosbags' bytes; use serialize='rosbags'")
    return raws


def _fast(ros1, stamp_ns, acc, gyro, frame_id):
    """Serialise a chunk with numpy: the inverse of the readers' layout (checked against rosbags above)."""
    name = frame_id.encode()
    if ros1:
        head = np.zeros(16 + len(name), np.uint8)
        head[12:16] = np.frombuffer(np.uint32(len(name)).tobytes(), np.uint8)
        head[16:] = np.frombuffer(name, np.uint8)
    else:
        strlen = len(name) + 1
        body = 4 + -(-(12 + strlen) // 8) * 8
        head = np.zeros(body, np.uint8)
        head[:4] = (0, 1, 0, 0)
        head[12:16] = np.frombuffer(np.uint32(strlen).tobytes(), np.uint8)
        head[16:16 + len(name)] = np.frombuffer(name, np.uint8)
    n = len(stamp_ns)
    doubles = np.zeros((n, 37))
    doubles[:, 3] = 1.0  # orientation w
    doubles[:, 13:16] = gyro
    doubles[:, 25:28] = acc
    sec, nsec = np.divmod(stamp_ns, 1_000_000_000)
    block = np.empty((n, head.size + 37 * 8), np.uint8)
    block[:, : head.size] = head
    block[:, 4:8] = sec.astype("<u4" if ros1 else "<i4").view(np.uint8).reshape(n, 4)
    block[:, 8:12] = nsec.astype("<u4").view(np.uint8).reshape(n, 4)
    block[:, head.size:] = doubles.astype("<f8").view(np.uint8).reshape(n, -1)
    return [row.tobytes() for row in block]


def _mag_messages(w, store, ros1: bool, mag: dict) -> list:
    """``(record ns, connection, record ns, raw)`` of every magnetometer message, latest first (popped in order)."""
    types = store.types
    Time, Header = types["builtin_interfaces/msg/Time"], types["std_msgs/msg/Header"]
    Vec, Mag = types["geometry_msgs/msg/Vector3"], types["sensor_msgs/msg/MagneticField"]
    ser = store.serialize_ros1 if ros1 else store.serialize_cdr
    out = []
    for topic, (tm, field, latency) in mag.items():
        conn = w.add_connection(topic, "sensor_msgs/msg/MagneticField", typestore=store)
        for ts, f in zip(np.asarray(tm, float), np.asarray(field, float)):
            sec, nsec = divmod(int(round(ts * 1e9)), 1_000_000_000)
            kw = {"seq": 0} if "seq" in Header.__dataclass_fields__ else {}
            msg = Mag(header=Header(stamp=Time(sec=sec, nanosec=nsec), frame_id="mag_link", **kw),
                      magnetic_field=Vec(x=float(f[0]), y=float(f[1]), z=float(f[2])),
                      magnetic_field_covariance=np.zeros(9))
            ns = int(round((ts + latency) * 1e9))
            out.append((ns, conn, ns, bytes(ser(msg, "sensor_msgs/msg/MagneticField"))))
    return sorted(out, key=lambda e: e[0], reverse=True)


def _default_message(store, msgtype: str, ros1: bool) -> bytes:
    """One message of an extra topic: a second IMU (zeros) or a ``std_msgs/msg/String``."""
    if msgtype == "sensor_msgs/msg/Imu":
        msg = _message(store, 0, np.zeros(3), np.zeros(3), "other")
    elif msgtype == "std_msgs/msg/String":
        msg = store.types[msgtype](data="not an IMU")
    else:
        raise AccelcalError(f"extra topics of type {msgtype} are not supported "
                            "(sensor_msgs/msg/Imu, std_msgs/msg/String)")
    return bytes(store.serialize_ros1(msg, msgtype) if ros1 else store.serialize_cdr(msg, msgtype))


__all__ = ["KINDS", "write_imu_bag"]
