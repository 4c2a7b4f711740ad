"""Serial-monitor block logs: poses as separate blocks of ``x, y, z`` rows (FastAhrs FXOS8700)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..recording import MIN_ROWS, Origin, Recording
from ..units import G0, acceleration_unit

#: Prompt that opens a block of a serial-monitor block log (FastAhrs' FXOS8700 calibration sketch).
_BLOCK_START = re.compile(r">>>\s*Gathering data for\s+([0-9.]+)\s*seconds", re.IGNORECASE)
_UNIT_LINE = re.compile(r"^\s*Type:\s*Acceleration\s*\((.+)\)\s*$", re.IGNORECASE)
#: What recognises a block log anywhere in the first lines (comments included).
_BLOCK_PROMPT = re.compile(r">>>\s*Gathering data for", re.IGNORECASE)
#: Largest relative spread of the per-block sampling rates (rows / stated seconds).
BLOCK_RATE_TOLERANCE = 0.02


def sniff(path: Path, head: str) -> bool:
    """Whether the file's first characters hold a block prompt (``>>> Gathering data for``)."""
    return bool(_BLOCK_PROMPT.search(head))


def read_block_log(path, text: str | None = None) -> Recording:
    """Read a serial-monitor log whose poses are separate blocks of ``x, y, z`` rows.

    Layout (vspruyt/FastAhrs ``data_sample*.csv``, FXOS8700): an optional sensor banner
    (``Type: Acceleration (m/s2)`` gives the unit), a line ``x, y, z``, then per pose the
    prompt lines ``>>> Place accelerometer ...``, ``>>> Type key when ready...``,
    ``>>> Gathering data for 10 seconds...`` followed by rows ``x, y, z``.  Lines starting
    with ``---`` (the monitor's own messages) and blank lines are skipped.

    Each block is one known static interval (the sensor is placed, then logged): the
    recording carries them as :attr:`Recording.intervals`.  The file has no time stamps:
    the rate is the block's rows over its stated seconds (the same for every block, else
    an error), ``t`` is the sample index over that rate, and the unknown time between
    blocks is taken as zero (stated in :attr:`Recording.notes`).
    """
    path = Path(path)
    what = "a block log (>>> Gathering data for N seconds... then x, y, z rows)"
    lines = _text_lines(path, what) if text is None else text.splitlines()
    if not lines:
        raise RecordingError(f"{path}: empty file (expected {what})")
    rows, blocks, seconds, unit, row_lines = _parse_blocks(lines, path)
    rate = _block_rate(blocks, seconds, path)
    acc = np.array(rows, dtype=float)
    t = np.arange(len(acc)) / rate
    notes = [f"no time stamps: t = sample index / {rate:g} Hz (rows per block over its stated seconds); "
             "the time between blocks is unknown and taken as zero",
             f"{len(blocks)} blocks read as known static intervals"]
    canonical = None
    if unit:
        canonical = acceleration_unit(unit)
        if canonical in ("g", "mg"):
            acc = acc * (G0 if canonical == "g" else G0 * 1e-3)
            canonical = "m/s^2"
        notes.append(f"unit from the banner: {unit}")
    return Recording(t, acc, None, str(path), intervals=[(a, b) for a, b, _ in blocks],
                     labels=tuple(f"block{k:02d}" for k in range(len(blocks))), notes=tuple(notes), unit=canonical,
                     origin=Origin("line", numbers=np.array(row_lines, dtype=np.int64), names=(("acc", ("x", "y", "z")),)))


def _parse_blocks(lines: list[str], path):
    """Rows ``x, y, z``; blocks ``[first row, end row, line of the prompt]``; each block's
    stated seconds; the unit of the banner (or None); the line of each row."""
    rows, blocks, seconds, unit, row_lines = [], [], [], None, []
    current = None  # index into blocks of the block being filled, None outside a block
    for no, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("---"):
            continue
        m = _BLOCK_START.search(s)
        if m:
            try:
                seconds.append(float(m.group(1)))
            except ValueError:  # '1.2.3' matches the prompt's pattern and is no number
                raise RecordingError(f"{path}: line {no}: the block's duration {m.group(1)!r} is not a number of "
                                     "seconds") from None
            blocks.append([len(rows), len(rows), no])
            current = len(blocks) - 1
            continue
        if s.startswith(">>>"):
            current = None
            continue
        u = _UNIT_LINE.match(s)
        if u:
            unit = u.group(1).strip()
            continue
        if current is None:
            continue  # banner, header 'x, y, z', anything before the first block
        parts = s.split(",")
        try:
            vals = [float(x) for x in parts]
        except ValueError:
            vals = []
        if len(vals) != 3:  # nan and inf are numbers: checked_recording refuses them, at this line
            raise RecordingError(f"{path}: line {no}: expected three numbers 'x, y, z' in block {current}, "
                                 f"got {s[:40]!r}")
        rows.append(vals)
        row_lines.append(no)
        blocks[current][1] = len(rows)
    return rows, blocks, seconds, unit, row_lines


def _block_rate(blocks, seconds, path) -> float:
    """The sampling rate every block gives (rows over stated seconds); an error if one is short or off."""
    if not blocks:
        raise RecordingError(f"{path}: no '>>> Gathering data for N seconds' block found; not a block log "
                             "(pass --format to choose another reader)")
    empty = [k for k, (a, b, _) in enumerate(blocks) if b - a < MIN_ROWS]
    if empty:
        k = empty[0]
        raise RecordingError(f"{path}: block {k} (line {blocks[k][2]}) has {blocks[k][1] - blocks[k][0]} rows; "
                             f"need at least {MIN_ROWS} (truncated or interrupted log?)")
    rates = np.array([(b - a) / sec if sec > 0 else np.nan for (a, b, _), sec in zip(blocks, seconds)])
    if not np.all(np.isfinite(rates)):
        raise RecordingError(f"{path}: a block states a duration of 0 seconds; cannot infer the sampling rate")
    rate = float(np.median(rates))
    off = np.flatnonzero(np.abs(rates / rate - 1) > BLOCK_RATE_TOLERANCE)
    if off.size:
        k = int(off[0])
        raise RecordingError(f"{path}: block {k} (line {blocks[k][2]}) has {blocks[k][1] - blocks[k][0]} rows for "
                             f"{seconds[k]:g} s where the others give {rate:g} Hz (truncated or interrupted block?)")
    return rate


def _text_lines(path: Path, what: str) -> list[str]:
    """The lines of a text file; a missing, empty or binary file is a one-line RecordingError."""
    if not path.is_file():
        raise RecordingError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    raw = path.read_bytes()
    if not raw:
        raise RecordingError(f"{path}: empty file (expected {what})")
    try:
        return raw.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text file (undecodable bytes), expected {what}") from None
