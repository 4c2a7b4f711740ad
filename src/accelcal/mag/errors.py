"""Typed errors of the magnetometer calibration: one line naming the cause and the fix.

They subclass the core's :class:`accelcal.errors.AccelcalError` family, so the command
line reports them as one ``accelcal: error:`` line with exit status 2.
"""

from __future__ import annotations

from ..errors import AccelcalError, DegeneratePosesError, RecordingError


class MagInputError(RecordingError):
    """Magnetometer samples that cannot be used: a constant or zero column, a saturated
    axis, non-finite values, a shape or time base unlike the accelerometer's."""


class MagDegenerateError(DegeneratePosesError):
    """Rotations that do not determine the ellipsoid (about one axis only, too few directions)."""


class MagDisturbanceError(AccelcalError):
    """The field changes while the device rests: a disturbance, not the sensor's errors."""


class MagFitError(AccelcalError):
    """The samples do not lie on an ellipsoid (the closed form gives no ellipsoid)."""


__all__ = ["MagDegenerateError", "MagDisturbanceError", "MagFitError", "MagInputError"]
