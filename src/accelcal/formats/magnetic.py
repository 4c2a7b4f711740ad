"""Magnetometer columns of a table: their names, their unit, and its conversion.

Names: ``mx``, ``mag_x``, ``magX``, ``Mag. X``, ``magnetometer_x``, ``compass_x``,
``magnetic_field.x`` (ROS ``sensor_msgs/MagneticField`` echoed by rostopic), ``x_mag``.
Units: from the name (``mx_uT``, ``MagX [gauss]``, ``mag_x (mT)``), ``--mag-unit``, or the
values (an Earth field is 25–65 µT: integers above 100 are counts, a median |m| of
0.05–2 is gauss, 5–200 µT, 1e-6–1e-3 tesla).  Physical units are converted to µT when read;
counts stay counts.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import RecordingError

MAG_ROLES = ("mx", "my", "mz")
_MAG = re.compile(r"^(?:field)?(?:imu)?(?:m|mag|magn|magnet|magnetometer|magneticfield|magfield|compass|hmc)"
                  r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_MAG_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:m|mag|magn)$")
#: Factors to µT; counts stay as they are.
MAG_UNITS = {"uT": 1.0, "µT": 1.0, "microtesla": 1.0, "T": 1e6, "tesla": 1e6, "mT": 1e3, "nT": 1e-3,
             "gauss": 100.0, "G": 100.0, "Ga": 100.0, "mG": 0.1, "mgauss": 0.1, "milligauss": 0.1}
_COUNTS = {"counts", "count", "lsb", "raw", "adc"}
_BRACKETED = re.compile(r"^(?P<base>.*?)\s*[\[\(\{<](?P<unit>[^\]\)\}>]*)[\]\)\}>]\s*$")
_SUFFIXED = re.compile(r"^(?P<base>.+?)[_\s.\-](?P<unit>[^_\s.\-]+)$")


def mag_unit(text: str | None) -> str | None:
    """Canonical magnetometer unit of ``text`` (``'uT'``, ``'gauss'``, ``'counts'``...), or None."""
    if text is None:
        return None
    t = text.strip()
    if t.lower() in _COUNTS:
        return "counts"
    for k in MAG_UNITS:
        if t == k or (len(k) > 2 and t.lower() == k.lower()) or (t.lower() in ("ut", "microt") and k == "uT"):
            return k if k not in ("µT", "microtesla") else "uT"
    return None


def mag_unit_in_name(name: str) -> tuple[str, str | None]:
    """Base of a column name and the magnetometer unit it names, if any."""
    for pat in (_BRACKETED, _SUFFIXED):
        m = pat.match(name.strip())
        if m:
            u = mag_unit(m.group("unit"))
            if u is not None:
                return m.group("base").strip(), u
    return name.strip(), None


def mag_axis(key: str) -> str | None:
    """``'x'``, ``'y'`` or ``'z'`` when the normalised name ``key`` is a magnetometer column."""
    m = _MAG.match(key) or _MAG_AXIS_FIRST.match(key)
    return m.group("axis") if m else None


def infer_mag_unit(m) -> tuple[str, str]:
    """The unit from the values, and how it was found (module docstring)."""
    m = np.asarray(m, float)
    ok = np.all(np.isfinite(m), axis=1) & ~np.all(m == 0, axis=1)
    med = float(np.median(np.linalg.norm(m[ok], axis=1))) if ok.any() else 0.0
    if np.all(m[ok] == np.round(m[ok])) and med > 100:
        return "counts", "inferred: integer values; pass --mag-unit if wrong"
    for lo, hi, u in ((0.05, 2.0, "gauss"), (5.0, 200.0, "uT"), (1e-6, 1e-3, "T")):
        if lo <= med <= hi:
            return u, f"inferred from the median |m| = {med:.3g}; pass --mag-unit if wrong"
    return "counts", f"median |m| = {med:.3g} is no Earth field in gauss, µT or T: taken as counts (--mag-unit)"


def resolve_mag_unit(m, header: dict, given: str | None, path) -> tuple[np.ndarray, str, str]:
    """``(field, 'uT' or 'counts', note)``: the unit from ``--mag-unit``, the header or the values."""
    if given is not None:
        u = mag_unit(given)
        if u is None:
            raise RecordingError(f"unknown magnetometer unit {given!r}; use uT, T, mT, nT, gauss, mG or counts "
                                 "(--mag-unit)")
        how = "--mag-unit"
    elif header:
        found = set(header.values())
        if len(found) > 1:
            raise RecordingError(f"{path}: the magnetometer columns are in different units ({', '.join(sorted(found))}):"
                                 " convert them to one unit or pass --mag-unit")
        u, how = found.pop(), "from the header"
    else:
        u, how = infer_mag_unit(m)
    if u == "counts":
        return np.asarray(m, float), "counts", f"magnetometer unit: counts ({how})"
    note = f"magnetometer unit: {u} ({how})" + ("" if u == "uT" else ", converted to uT")
    return np.asarray(m, float) * MAG_UNITS[u], "uT", note


__all__ = ["MAG_ROLES", "MAG_UNITS", "infer_mag_unit", "mag_axis", "mag_unit", "mag_unit_in_name",
           "resolve_mag_unit"]
