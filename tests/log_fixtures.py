"""Writers of small robotics logs for the log-reader tests: DataFlash (ArduPilot) and ULog (PX4).

ROS bags and MCAP files are written with rosbags' own writers
(:func:`tests.ros_synthetic.write_imu_bag`); pyulog and pymavlink have no
writers, so the two binary formats are written here from their published layouts
(ArduPilot's DataFlash: 0xA3 0x95 headers and FMT messages; PX4's ULog file format:
header, definitions, subscriptions and data messages).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

IMU_FORMAT = ("IMU", "QBffffffIIfBBHH", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz")
MAG_FORMAT = ("MAG", "QBhhhhhhhhhBI", "TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOX,MOY,MOZ,Health,S")
PARM_FORMAT = ("PARM", "QNf", "TimeUS,Name,Value")
_DF_STRUCT = {"Q": "Q", "B": "B", "f": "f", "I": "I", "H": "H", "h": "h", "n": "4s", "N": "16s", "Z": "64s"}


def _df_fmt(type_id: int, name: str, fmt: str, cols: str) -> bytes:
    length = 3 + struct.calcsize("<" + "".join(_DF_STRUCT[c] for c in fmt))
    return b"\xa3\x95\x80" + struct.pack("<BB4s16s64s", type_id, length, name.encode(), fmt.encode(), cols.encode())


def write_dataflash(path, t_us, acc, gyro, *, instances=(0,), temp=25.0, names=("IMU",), mag=None,
                    params=None) -> Path:
    """A DataFlash log with one IMU message per sample and instance (``I`` field), or old-style names;
    ``mag``: rows ``(TimeUS, I, MagX, MagY, MagZ, OfsX, OfsY, OfsZ, MOX, MOY, MOZ, Health, S)`` written
    as MAG messages among the IMU's by time; ``params``: {name: value} as PARM messages at the start."""
    path = Path(path)
    out = bytearray()
    for k, (name, fmt, cols) in enumerate((MAG_FORMAT, PARM_FORMAT) if mag is not None or params else ()):
        out += _df_fmt(0x30 + k, name, fmt, cols)
    for name, value in (params or {}).items():
        out += b"\xa3\x95\x31" + struct.pack("<Q16sf", 0, name.encode(), float(value))
    pending = sorted(mag or [], key=lambda r: r[0], reverse=True)
    ids = {}
    for k, name in enumerate(names):
        ids[name] = 0x40 + k
        out += _df_fmt(ids[name], name, IMU_FORMAT[1], IMU_FORMAT[2])
    layout = "<" + "".join(_DF_STRUCT[c] for c in IMU_FORMAT[1])
    mag_layout = "<" + "".join(_DF_STRUCT[c] for c in MAG_FORMAT[1])
    for i, tu in enumerate(np.asarray(t_us, dtype=np.int64)):
        while pending and pending[-1][0] <= tu:
            out += b"\xa3\x95\x30" + struct.pack(mag_layout, *[int(v) for v in pending.pop()])
        for name in names:
            for inst in instances:
                out += b"\xa3\x95" + bytes([ids[name]]) + struct.pack(
                    layout, int(tu), inst, *map(float, gyro[i]), *map(float, acc[i]), 0, 0, float(temp), 1, 1,
                    400, 400)
    path.write_bytes(bytes(out))
    return path


def _ulog_msg(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path, topics: dict, *, params: dict | None = None) -> Path:
    """A ULog file.  ``topics``: {(name, multi_id): {field: array}} with fields in ULog type order
    (``timestamp`` first); floats are written as float, ints as uint64 (timestamps) or uint32."""
    path = Path(path)
    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", 0))
    out += _ulog_msg(b"B", bytes(8) + bytes(8) + struct.pack("<QQQ", 0, 0, 0))  # flag bits
    formats = {}
    for (name, _), fields in topics.items():
        if name in formats:
            continue
        parts, codes = [], []
        for f, v in fields.items():
            v = np.asarray(v)
            typ = "uint64_t" if f.startswith("timestamp") else ("float" if v.dtype.kind == "f" else "uint32_t")
            parts.append(f"{typ} {f}")
            codes.append({"uint64_t": "Q", "float": "f", "uint32_t": "I"}[typ])
        formats[name] = "<" + "".join(codes)
        out += _ulog_msg(b"F", f"{name}:{';'.join(parts)};".encode())
    for k, v in (params or {}).items():
        key = f"float {k}".encode() if isinstance(v, float) else f"int32_t {k}".encode()
        out += _ulog_msg(b"P", bytes([len(key)]) + key + (struct.pack("<f", v) if isinstance(v, float)
                                                            else struct.pack("<i", v)))
    for msg_id, ((name, multi), fields) in enumerate(topics.items()):
        out += _ulog_msg(b"A", struct.pack("<BH", multi, msg_id) + name.encode())
    rows = []
    for msg_id, ((name, multi), fields) in enumerate(topics.items()):
        cols = [np.asarray(v) for v in fields.values()]
        for i in range(len(cols[0])):
            payload = struct.pack("<H", msg_id) + struct.pack(formats[name], *[c[i].item() for c in cols])
            rows.append((int(cols[0][i]), msg_id, _ulog_msg(b"D", payload)))
    for _, _, m in sorted(rows, key=lambda r: (r[0], r[1])):
        out += m
    path.write_bytes(bytes(out))
    return path
