"""Recording files: one module per file format, one registry, one entry point.

>>> from accelcal.formats import read
>>> rec = read("session.csv")                 # any format, guesses stated in rec.notes
>>> rec = read("canonical.csv", strict=True)  # the canonical CSV exactly, nothing guessed

The formats and what each declares (how it is recognised, read and written; whether the
file times its samples, says where the sensor rests, needs an optional extra) are in
:data:`~accelcal.formats.registry.FORMATS`; each format's parser is in its own module.
Robotics logs are formats like the others (ROS 1/2 bags and MCAP files in :mod:`.ros`,
PX4 ULog in :mod:`.px4`, ArduPilot DataFlash in :mod:`.ardupilot`, what they share in
:mod:`.logs`), read with the log options ``topic``, ``instance`` and ``time_source``:

>>> rec = read("rosbag2_2023_08_11-21_37_35")  # a ROS 2 bag folder: acc and gyro of its IMU topic
Importing this package imports no numerical library (``accelcal --help`` lists the
formats from it).
"""

from .dispatch import detect_format, read, write_recording
from .registry import FALLBACK, FORMATS, Format, format_named

__all__ = ["FALLBACK", "FORMATS", "Format", "detect_format", "format_named", "read", "write_recording"]
