"""Typed errors of accelcal. Every user-facing failure is one of these, with a one-line message."""


class AccelcalError(ValueError):
    """Base class: a problem with the user's input that the CLI reports in one line."""

    def __init__(self, message="", *args):
        # Messages quote the user's file (column names, cells); a line break in it would
        # break the one-line contract, so it is shown escaped.
        if isinstance(message, str):
            message = message.replace("\r", "\\r").replace("\n", "\\n")
        super().__init__(message, *args)


class InputShapeError(AccelcalError):
    """Arrays of the wrong shape or dimensionality."""


class NonFiniteError(AccelcalError):
    """NaN or infinite values in the input."""


class TooFewPosesError(AccelcalError):
    """Fewer static poses than the estimator needs (q + 1 for q unknowns)."""


class DegeneratePosesError(AccelcalError):
    """Pose set that does not determine the parameters (coplanar, one axis only...)."""


class NotPositiveDefiniteError(AccelcalError):
    """Estimated S-hat not positive definite, or a non-positive diagonal of M."""


class NotConvergedError(AccelcalError):
    """An iterative solver did not converge."""


class RecordingError(AccelcalError):
    """A recording file that cannot be read or used (columns, values, no rest)."""


class MissingExtraError(RecordingError):
    """An optional dependency (an extra of the package) that a format or a feature needs is not installed."""


class LogFormatError(RecordingError):
    """A robotics log (ROS bag, MCAP, ULog, DataFlash) that is damaged, truncated or not of its format."""


class TopicError(RecordingError):
    """No usable IMU topic in a log: none, several to choose from, the wrong message type, or empty."""


class NotStaticError(AccelcalError):
    """A recording given to the noise analysis that is not static (the sensor moved)."""
