"""Recording files: one module per file format and one entry point, :func:`read`."""

from .canonical import read_recording, write_recording
from .dispatch import FORMATS, detect_format, read

__all__ = ["FORMATS", "detect_format", "read", "read_recording", "write_recording"]
