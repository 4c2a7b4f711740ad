"""imucal's Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s², gyro in deg/s, no rate in the file)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..recording import Origin, Recording
from .parsing import (check_counter, columns_named, drop_trailing_blank, read_delimited, require_columns,
                      to_float)
from .text import content_lines, header_fields

#: Sampling rate of imucal's example session: its example script (``examples/basic_ferraris.py``)
#: says 102.4 Hz since commit 278a2c3 ("Fixed wrong samplingrate in example"), the commit of the
#: stored data; at the 204.8 Hz it said before, each 360 deg rotation integrates to about 180 deg.
IMUCAL_RATE_HZ = 102.4
#: Columns whose presence in the header recognises a session.
_SIGNATURE = {"n_samples", "acc_x", "acc_y", "acc_z", "gyr_x"}


def sniff(path: Path, head: str) -> bool:
    """Whether the header names ``n_samples``, ``acc_*`` and ``gyr_x``."""
    lines = content_lines(head)
    return bool(lines) and _SIGNATURE <= header_fields(lines[0])


def read_imucal_session(csv_path, rate: float = IMUCAL_RATE_HZ, text: str | None = None) -> Recording:
    """Read an imucal Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s²).

    ``n_samples`` is the sample counter (0, 1, 2, ... in the example: checked to be
    integer and strictly increasing), so ``t = n_samples / rate``.  The gyro (deg/s,
    imucal's unit) is returned in rad/s.
    """
    cols = ("n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z")
    df = drop_trailing_blank(read_delimited(csv_path, "an imucal session CSV", text))
    require_columns(df, cols, csv_path)
    # Gyro columns are checked too: a damaged gyro field means a damaged file.
    v = {c: to_float(df, c, csv_path, first_line=2) for c in cols}
    check_counter(v["n_samples"], "n_samples", csv_path)
    t = v["n_samples"] / rate
    gyro = np.deg2rad(np.column_stack([v["gyr_x"], v["gyr_y"], v["gyr_z"]]))
    return Recording(t, np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]]), None, str(csv_path), unit="m/s^2",
                     gyro=gyro, gyro_unit="rad/s",
                     origin=Origin("line", 2, names=columns_named(t="n_samples", acc=("acc_x", "acc_y", "acc_z"),
                                                                  gyro=("gyr_x", "gyr_y", "gyr_z"))),
                     notes=(f"imucal session: t = n_samples / {rate:g} Hz (the file has no rate; --rate to change), "
                            "gyro in deg/s converted to rad/s",))
