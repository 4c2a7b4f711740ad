"""A table whose magnetometer is the point: with or without accelerometer columns.

``accelcal mag`` reads sessions of a magnetometer alone (``Fs,50`` / ``mx,my,mz``: the
QMC5883L of tomisuarez2/MagnetometerCalibration) as well as accelerometer + magnetometer
tables; :func:`accelcal.formats.read` needs the accelerometer.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import RecordingError
from .inference import resolve_acceleration_unit, time_seconds
from .magnetic import MAG_ROLES, resolve_mag_unit
from .parsing import parse_numbers
from .columns import ACC_ROLES, map_columns, parse_columns
from .table import _split_table
from .text import load_text


class MagTable(NamedTuple):
    """Time [s], field (µT or counts), its unit, the accelerometer (m/s² or counts, or None), notes."""

    t: np.ndarray
    mag: np.ndarray
    mag_unit: str
    acc: np.ndarray | None
    acc_unit: str | None
    notes: tuple[str, ...]


def read_mag_table(path, *, columns=None, mag_unit: str | None = None, unit: str | None = None,
                   rate: float | None = None, time_unit: str | None = None) -> MagTable:
    """Read the magnetometer (and the accelerometer, when the table has one) of a text table."""
    path = Path(path)
    text, notes = load_text(path)
    tab = _split_table(text, path)
    if tab.names is None and not columns:
        raise RecordingError(f"{path}: no header: name the magnetometer columns with --columns mx=..,my=..,mz=..")
    roles, units = map_columns(tab.names, tab.k, parse_columns(columns), path, required=MAG_ROLES)
    floats = tab.numbers
    if floats is None and not tab.dc and _numeric(tab):
        floats = list(np.array(tab.data, dtype=float).T)

    def numbers(role):
        if floats is not None:
            return floats[roles[role]]
        return parse_numbers(tab.column(roles[role]), tab.dc, path, role, tab.names, roles[role], tab.lines)

    mag, mu, note = resolve_mag_unit(np.column_stack([numbers(r) for r in MAG_ROLES]), units.get("mag_units", {}),
                                     mag_unit, path)
    notes = list(notes) + [note]
    acc, acc_unit = None, None
    if all(r in roles for r in ACC_ROLES):
        acc, acc_unit, anote = resolve_acceleration_unit(np.column_stack([numbers(r) for r in ACC_ROLES]), units,
                                                         unit, path)
        notes.append(anote)
    try:
        t, tnote = time_seconds(tab.column(roles["t"]) if "t" in roles else None, rate, time_unit, units.get("t"),
                                tab.names, roles, tab.dc, path, tab.lines, tab.preamble)
    except RecordingError:
        if "t" in roles:
            raise
        # the fit takes the samples in order and never their time: the index stands for it
        t, tnote = np.arange(len(mag), dtype=float), "no time column and no rate: samples by index (--rate HZ)"
    notes.append(tnote)
    return MagTable(t, mag, mu, acc, acc_unit, tuple(n for n in notes if n))


def _numeric(tab) -> bool:
    try:
        np.array(tab.data, dtype=float)
    except ValueError:
        return False
    return True


__all__ = ["MagTable", "read_mag_table"]
