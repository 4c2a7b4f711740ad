"""Recording files: one module per file format, one registry, one entry point.

>>> from accelcal.formats import read
>>> rec = read("session.csv")                 # any format, guesses stated in rec.notes
>>> rec = read("canonical.csv", strict=True)  # the canonical CSV exactly, nothing guessed

The formats and what each declares (how it is recognised, read and written; whether the
file times its samples, says where the sensor rests, needs an optional extra) are in
:data:`~accelcal.formats.registry.FORMATS`; each format's parser is in its own module.
Importing this package imports no numerical library (``accelcal --help`` lists the
formats from it).
"""

from .dispatch import detect_format, read, write_recording
from .registry import FALLBACK, FORMATS, Format, format_named

__all__ = ["FALLBACK", "FORMATS", "Format", "detect_format", "format_named", "read", "write_recording"]
