"""IMU-TK ASCII (``xsens_acc.mat``): whitespace-separated time, x, y, z, no header."""

from __future__ import annotations

import numpy as np

from ..recording import Origin, Recording
from ..errors import RecordingError
from .clock import clocked_time
from .parsing import drop_trailing_blank, read_delimited, to_float


def read_imutk_ascii(path, text: str | None = None, clock: str = "auto") -> Recording:
    """Read an IMU-TK ASCII file (e.g. ``xsens_acc.mat``): whitespace-separated time, x, y, z.

    Values are returned as stored (raw counts for the Xsens example; see
    ``nominal_conversion('imutk_xsens')``).  Time: the sensor's clock fitted to the
    stamps (``clock='auto'``), or the stamps as they are (``'stamps'``), as the table reader.
    """
    df = drop_trailing_blank(read_delimited(path, "4 whitespace-separated columns (t x y z)", text,
                                          sep=r"\s+", header=None))
    if df.shape[1] != 4:
        raise RecordingError(f"{path}: {df.shape[1]} columns, expected 4 (t x y z) in an IMU-TK ASCII file")
    t, x, y, z = (to_float(df, i, path, first_line=1, name=n) for i, n in enumerate(("t", "x", "y", "z")))
    t, notes = clocked_time(t, None, counter_name="", mode=clock, timed_by_rate=False,
                            where=lambda i: f"line {i + 1}", path=path)
    return Recording(t, np.column_stack([x, y, z]), None, str(path), notes=tuple(notes),
                     origin=Origin("line", 1, names=(("t", "column 1"), ("acc", ("column 2", "column 3", "column 4")))))
