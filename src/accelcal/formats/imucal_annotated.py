"""imucal's annotated session (``part, samples, acc_*, gyr_*``, raw counts, grouped by section)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..recording import Origin, Recording, checked_recording, intervals_from_labels
from .imucal import IMUCAL_RATE_HZ
from .parsing import (check_counter, columns_named, drop_trailing_blank, read_delimited, require_columns,
                      to_float)
from .text import content_lines, header_fields

#: Columns whose presence in the header recognises an annotated session.
_SIGNATURE = {"part", "samples", "acc_x", "acc_y", "acc_z"}


def sniff(path: Path, head: str) -> bool:
    """Whether the header names ``part``, ``samples`` and ``acc_*``."""
    lines = content_lines(head)
    return bool(lines) and _SIGNATURE <= header_fields(lines[0])


def read_annotated_session(path, text: str | None = None, rate: float = IMUCAL_RATE_HZ) -> Recording:
    """The annotated session with its static parts (all but ``*_rot``) as known static intervals
    (made from the samples: checked first as every recording is, so that a short or damaged
    file is refused with its line, not as a part too short to be a rest)."""
    rec, parts = read_imucal_annotated(path, rate, text=text)
    rec = checked_recording(rec)
    static = np.array([p if not p.endswith("_rot") else "" for p in parts])
    iv, labels = intervals_from_labels(static)
    turns, names = intervals_from_labels(np.array([p if p.endswith("_rot") else "" for p in parts]))
    rotations = None if turns is None else dict(zip(names, map(tuple, turns)))
    return replace(rec, intervals=iv, labels=labels, rotations=rotations,
                   notes=rec.notes + ("imucal annotated session: its static parts (not *_rot) are the known "
                                      "static intervals, its *_rot parts rotations",))


def read_imucal_annotated(csv_path, rate: float = IMUCAL_RATE_HZ,
                          text: str | None = None) -> tuple[Recording, np.ndarray]:
    """Read imucal's annotated session (``part, samples, acc_*, gyr_*``, raw counts).

    The file is grouped by section, not in time order; rows are sorted by the
    ``samples`` counter, which must be unique integers.  ``t = samples / rate``.

    Returns
    -------
    rec : Recording
        Time-ordered acceleration and gyro in raw counts (no documented nominal scale).
    parts : ndarray of str, shape (n,)
        Section label of each sample (``x_p``, ..., ``z_rot``), in time order.
    """
    cols = ("part", "samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
    df = drop_trailing_blank(read_delimited(csv_path, "an imucal annotated session CSV", text))
    require_columns(df, cols, csv_path)
    v = {c: to_float(df, c, csv_path, first_line=2) for c in cols[1:]}
    s = v["samples"]
    order = np.argsort(s, kind="stable")
    check_counter(s, "samples", csv_path)
    parts = df["part"].str.strip().to_numpy(dtype=str)[order]
    if (parts == "").any():
        raise RecordingError(f"{csv_path}: empty 'part' label at line {2 + int(order[np.flatnonzero(parts == '')[0]])}")
    acc = np.column_stack([v["acc_x"], v["acc_y"], v["acc_z"]])[order]
    gyro = np.column_stack([v["gyr_x"], v["gyr_y"], v["gyr_z"]])[order]
    t = s[order] / rate  # a repeated sample number: time that repeats (checked_recording: its line)
    names = columns_named(t="samples", acc=("acc_x", "acc_y", "acc_z"), gyro=("gyr_x", "gyr_y", "gyr_z"))
    return Recording(t, acc, None, str(csv_path), unit="counts", gyro=gyro, gyro_unit="counts",
                     origin=Origin("line", numbers=order + 2, names=names),
                     notes=(f"imucal annotated session: t = samples / {rate:g} Hz (the file has no rate; --rate "
                            "to change)",)), parts
