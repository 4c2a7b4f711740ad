"""A record in one orientation, recognised before pose detection walks it: a static record is not a calibration.

A calibration needs rests in several orientations (4 for the bias-only models, 10 for the
full ones, :func:`accelcal.quality.distinct_orientations`: 10 deg apart).  Pose detection
and the search of its settings walk the whole record, many times over (a 2.78 h static
record: 70 s and 750 MB to say "1 static pose"); the 1 s means of the specific force say
it at once.  In m/s² every 1 s mean within :data:`MAX_ANGLE_DEG` (half the distinct-orientation
angle) of their median direction means no two rests can be distinct orientations.  Raw
counts carry an offset that makes directions meaningless, so there the means' largest
departure from their median is compared with the sample noise: within
:data:`COUNTS_SIGMAS` of it, where a turn by 10 deg moves them by 40-200 noise standard
deviations on the sensors in ``../shared/data``.  Anything less clear falls through to the
detection, which then gives its own verdict.
"""

from __future__ import annotations

import numpy as np

from .errors import RecordingError
from .quality import RULES

#: Length of the blocks whose means are compared [s].
BLOCK_S = 1.0
#: Largest angle [deg] of every 1 s mean from their median direction for one orientation (m/s²).
MAX_ANGLE_DEG = RULES["distinct_deg"] / 2.0
#: Largest departure of the 1 s means from their median, in sample noise standard deviations (counts).
COUNTS_SIGMAS = 10.0


class OneOrientationError(RecordingError):
    """A record the sensor spends in one orientation: no calibration, its noise instead."""


def one_orientation(t, acc, unit: str | None) -> str | None:
    """How the record stays in one orientation (a phrase for the message), or None if it may not."""
    t, acc = np.asarray(t, float), np.asarray(acc, float)
    if t.size < 4:
        return None
    rate = 1.0 / float(np.median(np.diff(t[: min(t.size, 100_000)])))
    k = max(2, int(round(rate * BLOCK_S)))
    m = t.size // k
    if m < 2 or not np.all(np.isfinite(acc)):
        return None
    blocks = acc[: m * k].reshape(m, k, 3)
    means = blocks.mean(axis=1)
    med = np.median(means, axis=0)
    span = f"over {(t[-1] - t[0]) / 3600:.3g} h" if t[-1] - t[0] >= 3600 else f"over {t[-1] - t[0]:.3g} s"
    if unit == "m/s^2":
        u = means / np.linalg.norm(means, axis=1, keepdims=True)
        c = med / np.linalg.norm(med)
        angle = float(np.rad2deg(np.arccos(np.clip(u @ c, -1.0, 1.0))).max())
        if angle <= MAX_ANGLE_DEG:
            return f"its {m} means of {BLOCK_S:g} s stay within {angle:.2g} deg of one direction {span}"
        return None
    sigma = float(np.linalg.norm(np.median(blocks.std(axis=1), axis=0)))
    dep = float(np.linalg.norm(means - med, axis=1).max())
    if sigma > 0 and dep <= COUNTS_SIGMAS * sigma:
        return (f"its {m} means of {BLOCK_S:g} s stay within {dep / sigma:.2g} noise standard deviations of one "
                f"value {span}")
    return None


def check_several_orientations(rec, min_poses: int, what: str) -> None:
    """One-line :class:`OneOrientationError` when ``rec`` stays in one orientation (module docstring).

    ``what`` names what needs ``min_poses`` orientations (``'full-lls'``).
    """
    how = one_orientation(rec.t, rec.acc, rec.unit)
    # a gyro of no stated unit: a static record cannot decide it (formats.units_evidence)
    unit_option = " --gyro-unit UNIT" if rec.gyro is not None and rec.gyro_unit is None else ""
    if how is not None:
        raise OneOrientationError(f"{rec.source}: the sensor keeps one orientation for the whole record ({how}): "
                                  f"{what} needs rests in at least {min_poses} orientations; for the noise of a "
                                  f"static record run: accelcal noise {rec.source}{unit_option}")


__all__ = ["BLOCK_S", "COUNTS_SIGMAS", "MAX_ANGLE_DEG", "OneOrientationError", "check_several_orientations",
           "one_orientation"]
