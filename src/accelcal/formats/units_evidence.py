"""Units where the file does not state them: what the values decide, and the refusal where nothing does.

A gyro's unit comes from the file (a unit in the header, a format whose spec fixes it:
ROS ``sensor_msgs/Imu``, PX4, ArduPilot are SI), from the user (``--gyro-unit``), or from
evidence that decides it.  rad/s and deg/s differ by 57.3, and the magnitude of the values
does not tell them apart: a quiet deg/s gyro at rest reads less than a rad/s one turning by
hand (the ADIS16405's 2.78 h static record, in deg/s, peaks at 0.5; taken as rad/s its noise
density came out 57x too large).  So the reader decides only what the values prove:

* integers beyond :data:`COUNTS_ABOVE` are raw counts: no physical gyro reports whole
  rad/s or deg/s of that size at rest, and counts are never read as a physical unit (the
  calibration estimates their scale; an export refuses them);
* anything else stays undecided (``Recording.gyro_unit`` None) until the motions of a
  calibration session decide it (:mod:`accelcal.gyro.unit_evidence`: the unit under which
  the integrated rotation carries each rest's gravity direction onto the next).  A use
  that has no motions (the noise analysis of a static record) refuses with one line naming
  ``--gyro-unit``: :func:`require_gyro_unit`.

``--gyro-unit`` also overrides the unit a log's spec fixes (:func:`override_gyro_unit`), for
a file that does not follow it.  The acceleration's unit, when neither the header nor
``--unit`` states it, is the one in which the rests read 1 g (:func:`acceleration_unit_from_rests`):
g, m/s² and mg are 9.8 and 100 apart, and anything else is raw counts, whose scale the
calibration estimates.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import RecordingError
from ..units import ANGULAR_RATE_UNITS, G0, angular_rate_unit

#: Largest |value| above which integer gyro values are raw counts.
COUNTS_ABOVE = 50
#: The ``read:`` note of a gyro whose unit is left to the evidence.
UNDECIDED_NOTE = ("gyro unit: not stated (no unit in the header, no --gyro-unit); decided by the motions between "
                  "rests when calibrating, else pass --gyro-unit")


def gyro_unit_from_values(gyro) -> tuple[str | None, str]:
    """``('counts', how)`` for integer values beyond :data:`COUNTS_ABOVE`, else ``(None, UNDECIDED_NOTE)``."""
    gyro = np.asarray(gyro, float)
    if gyro.size and _all_integers(gyro) and np.abs(gyro).max() > COUNTS_ABOVE:
        return "counts", (f"decided by the values: integers up to {np.abs(gyro).max():.0f}, raw counts; pass "
                          "--gyro-unit if they are not")
    return None, UNDECIDED_NOTE


def _all_integers(x: np.ndarray) -> bool:
    """Every value an integer: the first rows decide a record of fractions without a pass
    over all of it (three passes and a copy of 10⁶ x 3 values)."""
    head = x[:1000]
    return bool(np.all(head == np.round(head))) and bool(np.all(x == np.round(x)))


#: The gyro unit the spec of each format that fixes one writes its values in (the reader converts
#: them to rad/s or keeps counts); ``--gyro-unit`` overrides it for a file that does not follow it.
SPEC_GYRO_UNITS = {"mpu6050": "counts", "imucal": "deg/s", "imucal-annotated": "counts", "ros": "rad/s",
                   "px4": "rad/s", "ardupilot": "rad/s"}


def override_gyro_unit(rec, gyro_unit: str, format_name: str):
    """``rec`` with its gyro in the unit the user states (``--gyro-unit``) instead of the one its
    format's spec fixes (:data:`SPEC_GYRO_UNITS`; a log that does not follow it: deg/s in a
    ``sensor_msgs/Imu``), and the note saying so."""

    user, spec = angular_rate_unit(gyro_unit), SPEC_GYRO_UNITS.get(format_name)
    if spec is None or user == spec:
        return rec, f"--gyro-unit {user}: as the {format_name} format states"
    as_written = rec.gyro / (ANGULAR_RATE_UNITS[spec] or 1.0)  # the file's numbers
    gyro = as_written if user == "counts" else as_written * ANGULAR_RATE_UNITS[user]
    return (replace(rec, gyro=gyro, gyro_unit="counts" if user == "counts" else "rad/s"),
            f"gyro unit: {user} (--gyro-unit, overriding the {format_name} format's {spec}: a file that does not "
            "follow its spec)")


#: |a| at rest in g within which a physical unit is taken: a real accelerometer's scale error and
#: the tilt of a mean stay far inside it; g, m/s^2 and mg are 9.8 and 100 apart.
REST_BAND_G = (0.75, 1.25)
#: Samples per block of the rest magnitude (the quietest half of the blocks are the rests).
REST_BLOCK = 100
#: Blocks whose variances are taken at once (a few MB of temporaries).
_REST_CHUNK = 1000


def rest_magnitude(acc) -> float:
    """Median |a| of the rests: the means of the quietest half of :data:`REST_BLOCK`-sample blocks."""
    acc = np.asarray(acc, float)
    m = len(acc) // REST_BLOCK
    if m < 2:
        return float(np.median(np.linalg.norm(acc, axis=1)))
    # axis by axis, each block's samples contiguous (3-4x faster than over the middle axis of
    # (m, REST_BLOCK, 3), equal to 1e-15: the order of the sums), _REST_CHUNK blocks at a time
    # (no copy of the record)
    var, means = np.empty(m), np.empty((3, m))
    for a in range(0, m, _REST_CHUNK):
        b = min(a + _REST_CHUNK, m)
        blocks = np.ascontiguousarray(acc[a * REST_BLOCK: b * REST_BLOCK].T).reshape(3, b - a, REST_BLOCK)
        with np.errstate(invalid="ignore"):  # an inf: a block of nan variance, left out below
            var[a:b] = blocks.var(axis=2).sum(axis=0)
        means[:, a:b] = blocks.mean(axis=2)
    finite = np.isfinite(var)  # a block with a nan or inf says nothing (the recording's check refuses it)
    if not finite.any():
        return float("nan")
    quiet = finite & (var <= np.median(var[finite]))
    return float(np.median(np.linalg.norm(means[:, quiet], axis=0)))


def acceleration_unit_from_rests(acc) -> tuple[str, str]:
    """The acceleration unit the rests' magnitude decides (|a| = 1 g in g, m/s^2 or mg, within
    :data:`REST_BAND_G`), else raw counts (their scale is estimated, never taken as physical), and how."""
    norm = rest_magnitude(acc)
    integer = _all_integers(np.asarray(acc))
    for u, one_g in (("g", 1.0), ("m/s^2", G0), ("mg", 1000.0)):
        if REST_BAND_G[0] <= norm / one_g <= REST_BAND_G[1] and not (integer and u == "mg"):
            return u, (f"inferred from the median |a| = {norm:.4g} of the rests, {norm / one_g:.3f} g; pass --unit "
                       "if wrong")
    return "counts", (f"inferred from the median |a| = {norm:.4g} of the rests, 1 g in none of g, m/s^2, mg"
                      f"{' (integers)' if integer else ''}: raw counts; pass --unit if wrong")


def require_gyro_unit(rec, use: str) -> None:
    """One-line :class:`RecordingError` when ``rec`` has a gyro whose unit nothing decided.

    ``use`` says what cannot decide it (``'a static record'``): without motions the unit
    has no evidence, and a guess can be wrong by 57x.
    """
    if getattr(rec, "gyro", None) is not None and getattr(rec, "gyro_unit", None) is None:
        raise UndecidedUnitError(f"{rec.source}: the gyro's unit is not stated in the file and {use} cannot decide "
                                 "it (rad/s and deg/s differ by 57x); pass --gyro-unit rad/s, deg/s or counts "
                                 "(or --no-gyro)")


class UndecidedUnitError(RecordingError):
    """A unit that neither the file, the user nor the evidence decides."""


__all__ = ["COUNTS_ABOVE", "REST_BAND_G", "REST_BLOCK", "SPEC_GYRO_UNITS", "UNDECIDED_NOTE", "UndecidedUnitError",
           "acceleration_unit_from_rests", "gyro_unit_from_values", "override_gyro_unit", "require_gyro_unit",
           "rest_magnitude"]
