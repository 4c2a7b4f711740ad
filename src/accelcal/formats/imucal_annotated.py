"""imucal's annotated session (``part, samples, acc_*, gyr_*``, raw counts, grouped by section)."""

from __future__ import annotations

import numpy as np

from ..errors import RecordingError
from ..recording import Recording
from .imucal import IMUCAL_RATE_HZ
from .parsing import check_counter, check_time, drop_trailing_blank, read_delimited, require_columns, to_float


def read_imucal_annotated(csv_path, rate_hz: float = IMUCAL_RATE_HZ,
                          text: str | None = None) -> tuple[Recording, np.ndarray]:
    """Read imucal's annotated session (``part, samples, acc_*, gyr_*``, raw counts).

    The file is grouped by section, not in time order; rows are sorted by the
    ``samples`` counter, which must be unique integers.  ``t = samples / rate_hz``.

    Returns
    -------
    rec : Recording
        Time-ordered acceleration in raw counts (no documented nominal scale).
    parts : ndarray of str, shape (n,)
        Section label of each sample (``x_p``, ..., ``z_rot``), in time order.
    """
    cols = ("part", "samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
    df = drop_trailing_blank(read_delimited(csv_path, "an imucal annotated session CSV", text))
    require_columns(df, cols, csv_path)
    v = {c: to_float(df, c, csv_path, first_line=2) for c in cols[1:]}
    s = v["samples"]
    order = np.argsort(s, kind="stable")
    check_counter(s[order], "samples", csv_path, first_line=None)
    parts = df["part"].str.strip().to_numpy(dtype=str)[order]
    if (parts == "").any():
        raise RecordingError(f"{csv_path}: empty 'part' label at line {2 + int(np.flatnonzero(parts == '')[0])}")
    acc = np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]])[order]
    t = s[order] / rate_hz
    check_time(t, csv_path, first_line=2)
    return Recording(t, acc, None, str(csv_path), unit="counts"), parts
