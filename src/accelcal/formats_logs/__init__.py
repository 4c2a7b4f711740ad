"""Robotics logs: ROS 1/2 bags and MCAP files, PX4 ULog, ArduPilot DataFlash.

Each format is a module with ``sniff(path, head) -> bool`` (from the path and the
file's first bytes, without importing its optional extra) and
``read(path, *, topic=None, time_source='header', instance=None, progress=None)``
returning a :class:`~accelcal.recording.Recording` with ``acc`` [m/s²], ``gyro`` [rad/s]
and the notes of what was assumed.  :data:`LOG_FORMATS` declares them for the format
registry: what each one defines (time stamps, yes; known static intervals and a
nominal rate, no) and the extra it needs.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from ..errors import LogFormatError

#: Bytes of a file's head that the sniffers look at.
HEAD_BYTES = 64


@dataclass(frozen=True)
class LogFormat:
    """One log format: its reader module, the extra it needs, what its files define."""

    name: str
    module: str
    extra: str
    description: str
    suffixes: tuple[str, ...]
    defines_time: bool = True
    defines_intervals: bool = False
    defines_rate: bool = False

    def load(self):
        return importlib.import_module(f"accelcal.formats.{self.module}")

    def sniff(self, path, head: bytes) -> bool:
        return self.load().sniff(path, head)

    def read(self, path, **kw):
        return self.load().read(path, **kw)


LOG_FORMATS = {f.name: f for f in (
    LogFormat("ros", "ros", "ros", "ROS 1 bag, ROS 2 bag (folder, .db3, .mcap) or bare MCAP file, sensor_msgs/Imu",
              (".bag", ".db3", ".mcap", ".yaml", "")),
    LogFormat("px4", "px4", "px4", "PX4 ULog (sensor_accel/sensor_gyro raw, or sensor_combined)", (".ulg",)),
    LogFormat("ardupilot", "ardupilot", "ardupilot", "ArduPilot DataFlash log (IMU messages)", (".bin",)),
)}


def file_head(path) -> bytes:
    """The first :data:`HEAD_BYTES` bytes of a file (empty for a folder or an unreadable path)."""
    p = Path(path)
    if not p.is_file():
        return b""
    with open(p, "rb") as f:
        return f.read(HEAD_BYTES)


def detect_log(path) -> str | None:
    """The name of the log format of ``path``, or None when it is not a log this package reads."""
    head = file_head(path)
    for f in LOG_FORMATS.values():
        if f.sniff(path, head):
            return f.name
    return None


def read_log(path, *, format: str | None = None, **kw):
    """Read a log with the reader of ``format`` (default: detected); keywords as the readers'."""
    if not Path(path).exists():
        raise LogFormatError(f"{path}: no such file or folder")
    name = format or detect_log(path)
    if name is None:
        raise LogFormatError(f"{path}: not a ROS bag, MCAP, ULog or DataFlash log")
    if name not in LOG_FORMATS:
        raise LogFormatError(f"unknown log format {name!r}; known: {', '.join(LOG_FORMATS)}")
    return LOG_FORMATS[name].read(path, **kw)


__all__ = ["HEAD_BYTES", "LOG_FORMATS", "LogFormat", "detect_log", "file_head", "read_log"]
