"""imucal's Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s², no rate in the file)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..recording import Recording
from .parsing import check_counter, check_time, drop_trailing_blank, read_delimited, require_columns, to_float
from .text import content_lines, header_fields

#: Sampling rate of the imucal example sessions (imucal's examples and tests use it).
IMUCAL_RATE_HZ = 204.8
#: Columns whose presence in the header recognises a session.
_SIGNATURE = {"n_samples", "acc_x", "acc_y", "acc_z", "gyr_x"}


def sniff(path: Path, head: str) -> bool:
    """Whether the header names ``n_samples``, ``acc_*`` and ``gyr_x``."""
    lines = content_lines(head)
    return bool(lines) and _SIGNATURE <= header_fields(lines[0])


def read_imucal_session(csv_path, rate: float = IMUCAL_RATE_HZ, text: str | None = None) -> Recording:
    """Read an imucal Ferraris session CSV (``n_samples, gyr_*, acc_*``; acc in m/s²).

    ``n_samples`` is the sample counter (0, 1, 2, ... in the example: checked to be
    integer and strictly increasing), so ``t = n_samples / rate``.  The gyro
    columns are validated but not returned.
    """
    cols = ("n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z")
    df = drop_trailing_blank(read_delimited(csv_path, "an imucal session CSV", text))
    require_columns(df, cols, csv_path)
    # Gyro columns are checked too: a damaged gyro field means a damaged file.
    v = {c: to_float(df, c, csv_path, first_line=2) for c in cols}
    check_counter(v["n_samples"], "n_samples", csv_path, first_line=2)
    t = v["n_samples"] / rate
    check_time(t, csv_path, first_line=2)
    return Recording(t, np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]]), None, str(csv_path), unit="m/s^2",
                     notes=(f"imucal session: t = n_samples / {rate:g} Hz (the file has no rate)",))
