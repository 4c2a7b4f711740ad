"""Units of acceleration, angular rate, time and temperature: names people write, and conversions.

accelcal works in two acceleration units only: **m/s²** (physical) and **counts** (raw
sensor output, whose sensitivity the full model estimates).  Data in ``g`` or ``mg`` are
converted to m/s² when read, with standard gravity ``G0 = 9.80665 m/s²`` — the
definition of the unit ``g`` in data sheets, not the local gravity (``--g``), which is a
property of the site.  Angular rate is **rad/s** or **counts** (deg/s converted when
read).  Time is always seconds.

:func:`acceleration_unit`, :func:`angular_rate_unit`, :func:`time_unit` and :func:`temperature_unit` turn what a
header or an option says (``m/s^2``, ``m/s²``, ``mps2``, ``G``, ``milli-g``, ``LSB``,
``ms``, ``µs``, ``degC`` ...) into a canonical name, or None when the text names no unit
of that kind.  :func:`unit_in_name` finds a unit written into a column name
(``acc_x [g]``, ``AccX (m/s^2)``, ``ax_mg``, ``time_ms``).

This module imports only the standard library (it is used by ``accelcal --help``'s
import path).
"""

from __future__ import annotations

import math
import re

#: Standard gravity [m/s²]: the unit ``g`` of data sheets (CGPM 1901).
G0 = 9.80665

#: Canonical acceleration units and the factor to m/s² (None: raw counts, no factor).
ACCELERATION_UNITS = {"m/s^2": 1.0, "g": G0, "mg": G0 * 1e-3, "counts": None}
#: Canonical angular-rate units and the factor to rad/s (None: raw counts).
ANGULAR_RATE_UNITS = {"rad/s": 1.0, "deg/s": math.pi / 180.0, "counts": None}
#: Canonical time units and the factor to seconds.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
TEMPERATURE_UNITS = ("degC", "K", "degF")

_ACC_SPELLINGS = {
    "m/s^2": ("m/s^2", "m/s2", "m/s**2", "m/s²", "ms^-2", "ms-2", "m*s^-2", "m s^-2", "m s-2", "mps2", "ms2",
              "m_s2", "m_s^2", "m/sec^2", "m/sec2", "meters/s^2", "mpss", "m/ss", "si"),
    "g": ("g", "gs", "g0", "gee", "g_n", "gn"),
    "mg": ("mg", "millig", "milli-g", "milli_g", "mgee"),
    "counts": ("counts", "count", "cnt", "cnts", "lsb", "lsbs", "raw", "adc", "digits", "digit", "ticks", "dn"),
}
_RATE_SPELLINGS = {
    "rad/s": ("rad/s", "rad/sec", "rads", "rad_s", "radps", "rad s^-1", "rad*s^-1"),
    "deg/s": ("deg/s", "deg/sec", "dps", "degps", "deg_s", "°/s", "º/s", "degrees/s", "degree/s", "degs"),
    "counts": _ACC_SPELLINGS["counts"],
}
_TIME_SPELLINGS = {
    "s": ("s", "sec", "secs", "second", "seconds"),
    "ms": ("ms", "msec", "msecs", "millis", "millisecond", "milliseconds"),
    "us": ("us", "µs", "μs", "usec", "usecs", "micros", "microsecond", "microseconds"),
    "ns": ("ns", "nsec", "nsecs", "nanos", "nanosecond", "nanoseconds"),
}
_TEMP_SPELLINGS = {
    "degC": ("c", "°c", "degc", "deg_c", "degrees_c", "celsius", "deg c", "ºc"),
    "K": ("k", "kelvin"),
    "degF": ("f", "°f", "degf", "deg_f", "fahrenheit"),
}


def _lookup(text: str, table: dict) -> str | None:
    key = text.strip().lower().replace(" ", "")
    for name, spellings in table.items():
        if key in (s.replace(" ", "") for s in spellings):
            return name
    return None


def acceleration_unit(text: str) -> str | None:
    """Canonical acceleration unit (``'m/s^2'``, ``'g'``, ``'mg'``, ``'counts'``) named by ``text``, else None.

    ``G`` and ``g`` both mean the unit g; case is otherwise ignored.
    """
    return _lookup(text, _ACC_SPELLINGS)


def angular_rate_unit(text: str) -> str | None:
    """Canonical angular-rate unit (``'rad/s'``, ``'deg/s'``, ``'counts'``) named by ``text``, else None."""
    return _lookup(text, _RATE_SPELLINGS)


def time_unit(text: str) -> str | None:
    """Canonical time unit (``'s'``, ``'ms'``, ``'us'``, ``'ns'``) named by ``text``, else None."""
    return _lookup(text, _TIME_SPELLINGS)


def temperature_unit(text: str) -> str | None:
    """``'degC'``, ``'K'`` or ``'degF'`` named by ``text``, else None."""
    return _lookup(text, _TEMP_SPELLINGS)


def to_celsius(values, unit: str):
    """Temperatures in ``unit`` (``'degC'``, ``'K'``, ``'degF'``) converted to °C."""
    if unit == "K":
        return values - 273.15
    if unit == "degF":
        return (values - 32.0) * (5.0 / 9.0)
    return values


def acceleration_factor(unit: str) -> float | None:
    """Factor from ``unit`` to m/s² (None for counts)."""
    return ACCELERATION_UNITS[unit]


#: A unit written into a column name: in brackets, or as the last ``_``/space/``.``
#: separated token (``acc_x [m/s^2]``, ``AccX (g)``, ``ax_mg``, ``time_ms``, ``t.us``).
_BRACKETED = re.compile(r"^(?P<base>.*?)\s*[\[\(\{<](?P<unit>[^\]\)\}>]*)[\]\)\}>]\s*$")
_SUFFIXED = re.compile(r"^(?P<base>.+?)[_\s.\-](?P<unit>[^_\s.\-]+)$")


def unit_in_name(name: str, kind: str) -> tuple[str, str | None]:
    """Split a column name into its base and the unit of ``kind`` it names, if any.

    Parameters
    ----------
    name : str
        Column header as written.
    kind : {'acceleration', 'angular_rate', 'time', 'temperature'}

    Returns
    -------
    base : str
        The name without the unit (``'acc_x'`` for ``'acc_x [g]'``); the whole name if
        no unit of that kind is found.
    unit : str or None
        Canonical unit, or None.
    """
    parse = {"acceleration": acceleration_unit, "angular_rate": angular_rate_unit, "time": time_unit,
             "temperature": temperature_unit}[kind]
    m = _BRACKETED.match(name)
    if m:
        u = parse(m.group("unit"))
        return m.group("base").strip(), u
    m = _SUFFIXED.match(name.strip())
    if m:
        u = parse(m.group("unit"))
        if u is not None:
            return m.group("base"), u
    return name.strip(), None


__all__ = ["ACCELERATION_UNITS", "ANGULAR_RATE_UNITS", "G0", "TEMPERATURE_UNITS", "TIME_UNITS", "acceleration_factor",
           "acceleration_unit", "angular_rate_unit", "temperature_unit", "time_unit", "to_celsius", "unit_in_name"]
