"""Typed errors of the Tereshkov subpackage (all :class:`accelcal.errors.AccelcalError`).

Shape and finiteness problems raise the package-wide :class:`~accelcal.errors.InputShapeError`
and :class:`~accelcal.errors.NonFiniteError`; a parameter outside its meaningful range
(a negative time constant, a gate that cannot be satisfied...) raises
:class:`InvalidParameterError`.
"""

from __future__ import annotations

from ..errors import AccelcalError, InputShapeError, NonFiniteError


class InvalidParameterError(AccelcalError):
    """A simulation or estimator parameter outside its meaningful range."""


__all__ = ["InvalidParameterError", "InputShapeError", "NonFiniteError"]
