"""Typed errors of the gyroscope calibration: each a one-line message naming the cause and the fix.

They subclass the core's :class:`accelcal.errors.AccelcalError` family, so the command
line's error path (one ``accelcal: error:`` line, exit status 2) reports them as it
reports every other input problem.
"""

from __future__ import annotations

from ..errors import AccelcalError, RecordingError, TooFewPosesError


class GyroInputError(RecordingError):
    """Gyro samples that cannot be used: wrong shape, non-finite, a time base that does
    not match the accelerometer's."""


class NoMotionError(AccelcalError):
    """The sensor does not turn between the rests: nothing determines the gyro's scale."""


class SaturatedGyroError(AccelcalError):
    """The gyro reaches its measuring range in so many motions that too few are left."""


class RotationAngleError(AccelcalError):
    """A rotation of a Ferraris session does not reach the stated angle."""


class TooFewMotionsError(TooFewPosesError):
    """Fewer usable motions between rests (or rotations) than the gyro model needs."""


__all__ = ["GyroInputError", "NoMotionError", "RotationAngleError", "SaturatedGyroError", "TooFewMotionsError"]
