"""The MPU-6050 logger of tomisuarez2/ImuCalibration (``Fs,100`` lines, then ``ax,ay,az,gx,gy,gz``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..recording import Origin, Recording
from .parsing import columns_named, drop_trailing_blank, read_delimited, require_columns, to_float
from .text import content_lines


def sniff(path: Path, head: str) -> bool:
    """Whether the first lines are ``Fs,<rate>``, three metadata lines and ``ax,ay,az,gx,gy,gz``."""
    lines = content_lines(head)
    return (bool(lines) and lines[0].replace(" ", "").lower().startswith("fs,") and len(lines) > 4
            and lines[4].replace(" ", "").lower().startswith("ax,ay,az,gx,gy,gz"))


def read_mpu6050_csv(path, text: str | None = None) -> Recording:
    """Read the MPU-6050 calibration CSV of tomisuarez2/ImuCalibration.

    Layout: four ``key,value`` lines (``Fs,100``, ``Logging Type,0``,
    ``Initialization time,36.5``, ``Waiting time,3``), a header ``ax,ay,az,gx,gy,gz``
    and raw int16 counts (accelerometer and gyro).  ``t = row / Fs``.  See
    ``nominal_conversion('mpu6050')``.
    """
    path = Path(path)
    meta = read_delimited(path, "an MPU-6050 CSV (Fs line, 3 metadata lines, header ax,ay,az,...)", text,
                       header=None, nrows=4, names=["key", "value"])
    if len(meta) < 4 or meta.iloc[0, 0].strip() != "Fs":
        raise RecordingError(f"{path}: expected 4 metadata lines starting with 'Fs,<rate>'")
    try:
        fs = float(meta.iloc[0, 1])
    except ValueError:
        fs = float("nan")
    if not np.isfinite(fs) or fs <= 0:
        raise RecordingError(f"{path}: invalid sampling rate Fs={meta.iloc[0, 1]!r}")
    df = drop_trailing_blank(read_delimited(path, "an MPU-6050 CSV", text, skiprows=4))
    cols = ("ax", "ay", "az", "gx", "gy", "gz")
    require_columns(df, cols, path)
    if len(df) == 0:
        raise RecordingError(f"{path}: header but no data rows")
    v = {c: to_float(df, c, path, first_line=6) for c in cols}  # gyro checked: catches truncation
    acc = np.column_stack([v["ax"], v["ay"], v["az"]])
    gyro = np.column_stack([v["gx"], v["gy"], v["gz"]])
    t = np.arange(len(df)) / fs
    names = columns_named(acc=("ax", "ay", "az"), gyro=("gx", "gy", "gz"))
    return Recording(t, acc, None, str(path), unit="counts", gyro=gyro, gyro_unit="counts",
                     origin=Origin("line", 6, names=names),
                     notes=(f"MPU-6050 log: t = row / Fs = {fs:g} Hz",))
