"""Pre-registered screen of a real noise record for transients: the windows a real profile may use.

A real record can hold transients (a bump of the table, a disturbance of a few seconds
on every axis), and a window that holds one is not effect-free: it is a disturbed pose.
Before any window is used, :func:`transient_scan` compares the means of 1 s and 5 s
blocks of each axis with the running median of the 1 s means within ±60 s (a bump, a
spike) and with the block before (a step, which a running median follows), and flags a
block beyond 5 robust standard deviations (1.4826 MAD of all such values of that length
on that axis; config ``discrepancy.benchmark.record_screen``); every window that
overlaps a flagged block is left out (:func:`clean_windows`).  The criterion sees the
record only, never the loop or its detections.  On the ADIS16405 record it finds seven
bumps (near 1408, 2152–2177, 2578, 6818–6825, 7027–7047, 8795–8803 and 9560 s of the
record), mostly simultaneous on two or three axes, 1.4–4 mg for 5–25 s, and one step of
2 mg on two axes (7840–7850 s), and leaves out 7 of the 39 windows (5, 8, 10, 27, 31,
34, 37): 32 remain.  The table of events is written beside the profiles
(``record_screen.csv``).

The benchmark's real profiles (:mod:`.profiles`) draw their noise from the clean
windows only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accelcal.errors import AccelcalError


class RecordScreenError(AccelcalError):
    """A screen setting or a noise record the screen cannot use."""


def record_windows(n_record: int, n: int) -> int:
    """Disjoint windows of ``n`` samples in a record of ``n_record``."""
    return n_record // n


@dataclass(frozen=True)
class RecordScreen:
    """Pre-registered screen of a real noise record for transients (config
    ``discrepancy.benchmark.record_screen``; :func:`transient_scan`).

    Attributes
    ----------
    block_s : tuple of float
        Lengths of the blocks whose means are scanned [s]: about a pose's rest finds what
        shifts a pose mean, about a second shorter bumps.  Not single samples: a real
        record's quantised, heavy-tailed samples pass 5 robust standard deviations hundreds
        of times (the ADIS16405: 370 isolated samples over every window, each moving a
        5 s mean by less than a fifth of its white scatter), and a spike that matters for a
        pose mean shows in the block means.
    reference_s : float
        Half-width of the running median of 1 s block means that is each block's local
        reference [s]: long enough that a bump of one block cannot move it, short against
        the record's slow wander.
    z : float
        Flag a block whose deviation from its reference exceeds ``z`` robust standard
        deviations (1.4826 MAD of all the blocks of its length on that axis), or
        differs from the block before it by as much (a step).
    """

    block_s: tuple = (1.0, 5.0)
    reference_s: float = 60.0
    z: float = 5.0

    def __post_init__(self):
        if not self.block_s or min(self.block_s) <= 0 or not self.reference_s > 0 or not self.z > 0:
            raise RecordScreenError(f"record screen needs block_s > 0, reference_s > 0 and z > 0; got {self}")

    @classmethod
    def from_config(cls, cfg: dict) -> RecordScreen:
        return cls(tuple(float(b) for b in cfg["block_s"]), float(cfg["reference_s"]), float(cfg["z"]))


def _block_means(c: np.ndarray, b: int, offset: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts and means of the disjoint blocks of ``b`` samples from ``offset`` (``c``: cumulative sum, (n+1,))."""
    starts = np.arange(offset, len(c) - b, b)
    return starts, (c[starts + b] - c[starts]) / b


def _local_reference(x: np.ndarray, fs: float, reference_s: float) -> np.ndarray:
    """Per sample: the running median of the 1 s block means within ±``reference_s`` of its second."""
    from scipy.ndimage import median_filter

    sec = max(int(round(fs)), 1)
    m = x[: len(x) // sec * sec].reshape(-1, sec).mean(axis=1)
    ref = median_filter(m, size=2 * int(round(reference_s)) + 1, mode="nearest")
    return np.pad(np.repeat(ref, sec), (0, len(x) - len(ref) * sec), mode="edge")  # the last partial second


def transient_scan(record: np.ndarray, fs: float, screen: RecordScreen) -> list[dict]:
    """Transients (spikes, bumps, steps) of a real noise record, found from the record alone.

    Every axis is compared with its own local level (:func:`_local_reference`) in blocks of
    each length of ``screen.block_s``, on two grids offset by half a block (so that a bump
    straddling a block edge is seen whole); a block is flagged when its deviation from the
    local level (``level``), or the difference between it and the block before it
    (``step``), exceeds ``screen.z`` robust standard deviations of all such values of its
    length on that axis.
    The criterion knows nothing of the loop or of the sessions cut from the record: it is
    fixed before the windows are used, so it cannot be tuned to the loop's detections.

    Parameters
    ----------
    record : ndarray, shape (n, 3)
    fs : float
        Sampling rate [Hz].
    screen : RecordScreen

    Returns
    -------
    list of dict
        One per run of overlapping flagged blocks of one axis, block length and test:
        ``axis``, ``block_s``, ``kind`` (``level`` or ``step``), ``start``, ``stop``
        (samples, ``[start, stop)``), ``z`` (the largest signed deviation in robust standard
        deviations) and ``deviation`` (record unit).
    """
    x = np.asarray(record, float)
    if x.ndim != 2 or x.shape[1] != 3 or not np.all(np.isfinite(x)):
        raise RecordScreenError(f"a noise record must be finite with shape (n, 3); got shape {x.shape}")
    longest = max(max(int(round(b * fs)) for b in screen.block_s), int(round(fs)))
    if len(x) < 2 * longest:  # fewer than two blocks: no scatter to compare a block with
        raise RecordScreenError(f"record screen: {len(x)} samples are fewer than two blocks of {longest}")
    events = []
    for a in range(3):
        ref = _local_reference(x[:, a], fs, screen.reference_s)
        c_level = np.concatenate([[0.0], np.cumsum(x[:, a] - ref)])
        c_raw = np.concatenate([[0.0], np.cumsum(x[:, a])])
        for block_s in screen.block_s:
            b = max(int(round(block_s * fs)), 1)
            starts, m = _half_grid(c_level, b)
            _, r = _half_grid(c_raw, b)
            # level: the block against its local reference; step: the next block against the
            # previous one, in the record itself (a running median follows a step, so the
            # reference would hide it)
            for kind, st, span, d in (("level", starts, b, m), ("step", starts[:-2], 2 * b, r[2:] - r[:-2])):
                events += _flag(d, st, span, screen.z, {"axis": a, "block_s": block_s, "kind": kind},
                                f"axis {a} has no scatter in blocks of {block_s} s")
    return events


def _half_grid(c: np.ndarray, b: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts and means of the blocks of ``b`` samples every ``b/2`` (two disjoint grids interleaved), in order."""
    grids = [_block_means(c, b, off) for off in sorted({0, b // 2})]
    starts = np.concatenate([s for s, _ in grids])
    order = np.argsort(starts, kind="stable")
    return starts[order], np.concatenate([m for _, m in grids])[order]


def _flag(d: np.ndarray, starts: np.ndarray, span: int, z: float, labels: dict, what: str) -> list[dict]:
    """Runs of overlapping spans ``[start, start + span)`` whose ``d`` exceeds ``z`` robust standard deviations."""
    s = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    if not s > 0:
        raise RecordScreenError(f"record screen: {what}")
    out = []
    for i in np.flatnonzero(np.abs(d) > z * s):
        st, zi = int(starts[i]), float(d[i] / s)
        if out and st <= out[-1]["stop"]:  # overlaps the last flagged span: one event
            ev = out[-1]
            ev["stop"] = max(ev["stop"], st + span)
            if abs(zi) > abs(ev["z"]):
                ev["z"], ev["deviation"] = zi, zi * s
        else:
            out.append({**labels, "start": st, "stop": st + span, "z": zi, "deviation": zi * s})
    return out


def clean_windows(n_record: int, n: int, events) -> tuple[int, ...]:
    """Indices of the disjoint windows of ``n`` samples that hold no event of :func:`transient_scan`."""
    bad = set()
    for ev in events:
        bad.update(range(ev["start"] // n, (ev["stop"] - 1) // n + 1))
    return tuple(k for k in range(record_windows(n_record, n)) if k not in bad)



__all__ = ["RecordScreen", "RecordScreenError", "clean_windows", "record_windows", "transient_scan"]
