"""The ``sensor_msgs/MagneticField`` topic beside a bag's IMU topic (ROS 1 bags, ROS 2 sqlite3
and MCAP bags, bare MCAP files): read with the IMU (:func:`accelcal.formats.ros.read`).

The message (``sensor_msgs/msg/MagneticField.msg``, common_interfaces; ROS 1's is the same):
``std_msgs/Header header``, ``geometry_msgs/Vector3 magnetic_field`` — "x, y, and z
components of the field vector in Tesla.  If your sensor does not output 3 axes, put NaNs in
the components not reported." — and ``float64[9] magnetic_field_covariance``.  Messages
with a NaN are left out by the fit (:func:`accelcal.mag.trust.prepare`); an axis NaN in
every message cannot be calibrated (one warning note).  The field is read in tesla and converted to µT (x 1e6) as the
table reader converts a column in T (:data:`accelcal.formats.magnetic.MAG_UNITS`).

Chosen like the IMU topic: the only ``MagneticField`` topic, or ``--mag-topic`` when there are
several (without it: the accelerometer and gyro are read, the magnetometer is not, with
one ``warning: magnetometer:`` note naming the topics and the option).  Timed by the IMU's
clock rule (``header.stamp``, or the bag's record time with ``--time-source log``) and put on
the IMU's rows by :mod:`accelcal.formats.mag_logs`.

Decoding: the header's one variable-length field (``frame_id``) fixes the layout, as for the
IMU (:mod:`accelcal.formats.ros`); every message is checked to have the standard length and
the first one is deserialised by ``rosbags`` too and compared.
"""

from __future__ import annotations

import struct

import numpy as np

from ..errors import LogFormatError, TopicError
from .logs import choose
from .mag_logs import MagSkipped, attach, check_offsets, skipped

MAG_TYPE = "sensor_msgs/msg/MagneticField"
#: tesla -> µT (the message's unit; ``MAG_UNITS['T']``).
TESLA_TO_UT = 1e6
#: Bytes after the header: magnetic_field (3 doubles) and its covariance (9).
_BODY = 12 * 8
_FIX = "use the bag's record time for both (--time-source log), or pass --no-mag"


def add_magnetometer(rec, reader, conns, path, kind: str, ros1: bool, typestore, mag_topic: str | None,
                     time_source: str, imu_ns: np.ndarray):
    """``rec`` with the bag's magnetometer on its rows (or a warning note); ``imu_ns``: the IMU rows'
    (header stamp, record time) [ns], shape (n, 2), in the rows' order."""
    mags = {c.topic: f"{c.msgcount} messages" for c in conns if c.msgtype == MAG_TYPE}
    if not mags and mag_topic is None:
        return rec
    everything = {c.topic: f"{c.msgtype}, {c.msgcount} messages" for c in conns}
    try:
        name = choose(path, mags, mag_topic, everything, kind="sensor_msgs/MagneticField topic",
                      option="--mag-topic")
    except TopicError as e:
        if mag_topic is not None:  # the user's own choice is wrong: an error, not a warning
            raise
        return skipped(rec, f"{str(e).split(': ', 1)[-1]} (or --no-mag)")
    mine = [c for c in conns if c.topic == name]
    try:
        head, log, field, frames = _decode(reader, mine, path, name, ros1, typestore)
    except (LogFormatError, MagSkipped) as e:  # the IMU is whole: its calibrations can still be made
        return skipped(rec, f"{str(e).split(': ', 1)[-1]}; pass --no-mag")
    except Exception as e:  # a damaged chunk or page in the magnetometer's messages
        return skipped(rec, f"topic {name} is damaged ({' '.join(str(e).split())[:100]}); pass --no-mag")
    what = f"magnetometer topic {name} (sensor_msgs/MagneticField, frame {frames}, tesla converted to uT)"
    if time_source == "header":
        if np.all(head == 0):
            return skipped(rec, f"topic {name}: every header stamp is zero; {_FIX}")
        try:
            check_offsets(float(np.median(imu_ns[:, 0] - imu_ns[:, 1])) * 1e-9,
                          float(np.median(head - log)) * 1e-9, what, _FIX)
        except MagSkipped as e:
            return skipped(rec, str(e))
    col = 0 if time_source == "header" else 1
    stamps = head if col == 0 else log
    t0 = imu_ns[0, col]
    return attach(rec, (imu_ns[:, col] - t0) * 1e-9, (stamps - t0) * 1e-9, field * TESLA_TO_UT, what, _FIX)


def _decode(reader, conns, path, topic, ros1: bool, typestore):
    """Header stamps, record times [ns], field [T] (n, 3) and the frame ids of the topic's messages."""
    heads, logs, rows, frames = [], [], [], set()
    for k, (_, log_ns, raw) in enumerate(reader.messages(connections=conns)):
        raw = bytes(raw)
        body, order, flen = _layout(raw, path, topic, ros1, k)
        if k == 0:
            _compare(raw, body, order, path, topic, ros1, typestore)
        sec, nsec = struct.unpack_from(order + ("II" if ros1 else "iI"), raw, 4)
        heads.append(sec * 1_000_000_000 + nsec)
        logs.append(log_ns)
        rows.append(struct.unpack_from(order + "3d", raw, body))
        frames.add(raw[16:16 + flen].rstrip(b"\0").decode("utf-8", "replace") or "''")
    if not rows:
        raise MagSkipped(f"topic {topic} has no messages")
    field = np.array(rows, dtype=float)
    silent = [a for k, a in enumerate("xyz") if not np.isfinite(field[:, k]).any()]
    if silent:  # MagneticField.msg: "If your sensor does not output 3 axes, put NaNs in the components not reported"
        raise LogFormatError(f"{path}: topic {topic}: magnetic_field.{'/'.join(silent)} is NaN in every message (a "
                             "sensor that does not report it); a 3-axis calibration needs all three")
    return np.array(heads, np.int64), np.array(logs, np.int64), field, ", ".join(sorted(frames))


def _layout(raw: bytes, path, topic, ros1: bool, k: int) -> tuple[int, str, int]:
    """(offset of magnetic_field, byte order, frame id length) of one message; checks its length."""
    n = len(raw)
    if n < 16:
        raise LogFormatError(f"{path}: topic {topic}: message {k} has {n} bytes (truncated)")
    if ros1:
        order = "<"
        flen = struct.unpack_from("<I", raw, 12)[0]
        body = 16 + flen
    else:
        if raw[0] != 0 or raw[1] not in (0, 1):
            raise LogFormatError(f"{path}: topic {topic}: message {k} is not plain CDR (encapsulation {raw[:2].hex()})")
        order = "<" if raw[1] == 1 else ">"
        flen = struct.unpack_from(order + "I", raw, 12)[0]
        body = 4 + -(-(12 + flen) // 8) * 8
    if n != body + _BODY:
        raise LogFormatError(f"{path}: topic {topic}: message {k} has {n} bytes where a standard "
                             f"sensor_msgs/MagneticField with its frame id has {body + _BODY} (truncated or not the "
                             "standard type)")
    return body, order, flen


def _compare(raw, body, order, path, topic, ros1: bool, typestore) -> None:
    """The first message deserialised by rosbags must give the same field as the layout."""
    try:
        msg = typestore.deserialize_ros1(raw, MAG_TYPE) if ros1 else typestore.deserialize_cdr(raw, MAG_TYPE)
    except Exception as e:
        raise LogFormatError(f"{path}: topic {topic}: the first message does not deserialise as "
                             f"sensor_msgs/MagneticField ({' '.join(str(e).split())[:120]})") from None
    f = msg.magnetic_field
    if struct.unpack_from(order + "3d", raw, body) != (f.x, f.y, f.z):
        raise LogFormatError(f"{path}: topic {topic}: the message layout is not the standard sensor_msgs/MagneticField")


__all__ = ["MAG_TYPE", "TESLA_TO_UT", "add_magnetometer"]
