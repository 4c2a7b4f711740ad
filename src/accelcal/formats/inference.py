"""What the table reader infers when the file does not say: the acceleration and angular-rate units and the time.

Acceleration comes out in m/s² or raw counts (:mod:`accelcal.units`): a unit in the
header (``acc_x [g]``, ``ax_mg``), ``unit=`` (which wins), or, failing both, the
magnitude of the rests (median ``|a|`` within 25 % of 1 g in g, m/s² or mg; anything
else raw counts, whose scale the calibration estimates: :mod:`.units_evidence`).  Angular rate
comes out in rad/s or raw counts, its unit from the header (``gyr_x [deg/s]``,
``gx_dps``) or ``gyro_unit=``; without either, integers are raw counts and anything else
is left undecided (``gyro_unit`` None) for the motions to decide: the magnitude of the
values cannot tell rad/s from deg/s (:mod:`.units_evidence`).  Time comes out
in seconds from the first sample: its unit from ``time_unit=``, the header
(``time_ms``), or the values (epoch magnitudes; integer steps → the unit that makes the
rate nearest 100 Hz), ISO 8601 date-times parsed, or ``rate=`` (time from the sample
index).  Every guess is a note.
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from ..errors import RecordingError
from ..recording import Recording
from ..units import ANGULAR_RATE_UNITS, G0, acceleration_unit, angular_rate_unit, time_unit
from .parsing import DECIMAL_COMMA, NON_FINITE, NUMBER, norm_name, parse_numbers
from .units_evidence import acceleration_unit_from_rests, gyro_unit_from_values

#: Canonical sampling rate the time-unit inference aims at [Hz] (typical IMU logging).
TYPICAL_RATE_HZ = 100.0


def convert_acc(acc, u: str, how: str, own: bool = False):
    """``acc`` in m/s² (or counts) and the note; ``own``: ``acc`` is the caller's fresh array,
    converted in place (a 10⁶-row triad is 24 MB, part of a table reading's peak memory)."""
    if u in ("g", "mg"):
        f = G0 if u == "g" else G0 * 1e-3
        return _scaled(acc, f, own), f"unit: {u} ({how}), converted to m/s^2 with standard gravity {G0} m/s^2 per g"
    return acc, f"unit: {u} ({how})"


def resolve_acceleration_unit(acc, units: dict, unit: str | None, path, own: bool = False):
    """Acceleration in m/s² or counts, its unit name, and a note saying where the unit came from
    (``own``: ``acc`` is the caller's fresh array, converted in place)."""
    header = units.get("acc_units", {})
    if unit is not None:
        u, how = acceleration_unit(unit), "--unit"
        if header and set(header.values()) != {u}:
            how = f"--unit, overriding the header's {'/'.join(sorted(set(header.values())))}"
    elif header:
        if len(header) < 3 and set(header.values()) != {"counts"}:
            pass
        if len(set(header.values())) > 1:
            raise RecordingError(f"{path}: the acceleration columns are in different units "
                                 f"({', '.join(f'{r}: {v}' for r, v in sorted(header.items()))}); "
                                 "convert them to one unit or pass --unit")
        u, how = next(iter(header.values())), "from the header"
    else:
        return infer_acceleration_unit(acc, path, own)
    acc, note = convert_acc(acc, u, how, own)
    return acc, "counts" if u == "counts" else "m/s^2", note


def infer_acceleration_unit(acc, path, own: bool = False):
    u, how = acceleration_unit_from_rests(acc)  # the rests' magnitude decides (units_evidence)
    acc, note = convert_acc(acc, u, how, own)
    return acc, "counts" if u == "counts" else "m/s^2", note


def _scaled(a, f: float, own: bool):
    """``a * f``: in place when ``own`` (the same bits)."""
    return np.multiply(a, f, out=a) if own else a * f


def convert_gyro(gyro, u: str, how: str, own: bool = False):
    """:func:`convert_acc` of a gyroscope: rad/s (or counts)."""
    if u == "deg/s":
        return _scaled(gyro, ANGULAR_RATE_UNITS["deg/s"], own), f"gyro unit: deg/s ({how}), converted to rad/s"
    return gyro, f"gyro unit: {u} ({how})"


def resolve_gyro_unit(gyro, units: dict, gyro_unit: str | None, path, own: bool = False):
    """Angular rate in rad/s or counts, its unit name and a note saying where the unit came from; the raw
    values, unit None, when nothing but the motions can decide it (:mod:`.units_evidence`).  ``own``:
    ``gyro`` is the caller's fresh array, converted in place."""
    header = units.get("gyro_units", {})
    if gyro_unit is not None:
        u = angular_rate_unit(gyro_unit)
        if u is None:
            raise RecordingError(f"unknown gyro unit {gyro_unit!r}; use rad/s, deg/s or counts (--gyro-unit)")
        how = "--gyro-unit" + (f", overriding the header's {'/'.join(sorted(set(header.values())))}"
                               if header and set(header.values()) != {u} else "")
    elif header:
        if len(set(header.values())) > 1:
            raise RecordingError(f"{path}: the gyro columns are in different units "
                                 f"({', '.join(f'{r}: {v}' for r, v in sorted(header.items()))}); "
                                 "convert them to one unit or pass --gyro-unit")
        u, how = next(iter(header.values())), "from the header"
    else:
        u, how = gyro_unit_from_values(gyro)
        if u is None:  # left to the evidence of the motions (units_evidence)
            return gyro, None, how
    gyro, note = convert_gyro(gyro, u, how, own)
    return gyro, "counts" if u == "counts" else "rad/s", note


def with_inferred_unit(rec: Recording) -> Recording:
    acc, u, note = infer_acceleration_unit(rec.acc, rec.source)
    return replace(rec, acc=acc, unit=u, notes=rec.notes + (note,))


_RATE_KEYS = {"fs", "rate", "samplerate", "samplingrate", "samplingfrequency", "frequency", "hz", "odr",
              "samplingratehz", "ratehz", "fshz"}


def _preamble_rate(preamble) -> tuple[float | None, str]:
    for no, r in preamble:
        if len(r) >= 2 and norm_name(r[0]) in _RATE_KEYS:
            try:
                fs = float(r[1].replace(",", "."))
            except ValueError:
                continue
            if np.isfinite(fs) and fs > 0:
                return fs, f"t = sample index / {fs:g} Hz (rate from the line {no} '{r[0]}')"
    return None, ""


def time_seconds(values, rate, tu, header_unit, names, roles, dc, path, lines, preamble, parsed=None, counter=None):
    """Time [s] from the first sample, and a note on how it was obtained (``parsed``: the
    column already converted to floats, when the table reader has it; ``counter``: the
    sample counter's label, when the table has one, for the hint of a missing time)."""
    n = len(lines)
    if rate is not None:
        ignored = " (time column ignored)" if values is not None else ""
        return np.arange(n) / rate, f"t = sample index / {rate:g} Hz (--rate){ignored}"
    if values is None:
        fs, note = _preamble_rate(preamble)
        if fs is None:
            found = ", ".join(names)[:150] if names is not None else "none"
            by = f"by their {counter}" if counter else "by their index"
            raise RecordingError(f"{path}: no time column (found: {found}); pass --rate HZ (the sensor's rate) to "
                                 f"time the samples {by}, or --columns t=NAME")
        return np.arange(n) / fs, note
    # the first 1000 values decide what the column is; the whole column is looked at (a
    # second of 10^6 strings) only where that needs it: date-times, integers
    head = np.char.strip(np.asarray(values[:1000]).astype(str))
    label = f"time (column {names[roles['t']].strip()!r})" if names is not None else "time"
    if not all(NUMBER.match(v) or (dc and DECIMAL_COMMA.match(v)) or NON_FINITE.match(v) for v in head):
        return _datetime_time(np.char.strip(values.astype(str, copy=False)), path, label, lines)
    integer, exact = all(re.fullmatch(r"[+-]?\d+", v) for v in head), False
    if integer:
        s = np.char.strip(values.astype(str, copy=False))
        if dc:
            s = np.char.replace(s, ",", ".")
        digits = np.strings.slice(s, np.isin(np.strings.slice(s, 0, 1), ("+", "-")).astype(int), None)  # sign off
        integer = bool(np.all(np.strings.isdecimal(digits)))
        exact = integer and bool(np.all(np.strings.str_len(digits) < 19))
    if exact:
        ti = s.astype(np.int64)
        rel = (ti - ti[0]).astype(float)  # exact in int64, then float: epoch ns keep their digits
        x = ti.astype(float)
        t0 = float(ti[0])
    else:
        x = parsed if parsed is not None else parse_numbers(values, dc, path, "t", names, roles["t"], lines)
        t0 = float(x[0])
        rel = x - x[0]
    if tu is not None:
        unit, how = time_unit(tu), "--time-unit"
    elif header_unit is not None:
        unit, how = header_unit, "from the header"
    else:
        unit, how = _infer_time_unit(rel, t0, integer)
    f = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[unit]
    epoch = abs(t0) * f >= 1e6  # clock or epoch time: seconds from the first sample keep the digits
    t = rel * f if epoch else x * f
    del rel  # not beside the steps: 8 MB of a 10⁶-row table at the reading's peak
    rate_hz = 1.0 / _median_step(t)
    note = f"time unit: {unit} ({how}): {rate_hz:.4g} Hz over {t[-1] - t[0]:.4g} s"
    if how.startswith("inferred") or not 1.0 <= rate_hz <= 20000.0:
        note += "; pass --time-unit if wrong"
    if epoch:
        note += f"; counted from the first sample (t0 = {t0:.17g} {unit})"
    return t, note


def _infer_time_unit(rel, t0: float, integer: bool) -> tuple[str, str]:
    """The time unit from the values: epoch magnitude first, else the sampling rate."""
    factors = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
    if abs(t0) >= 1e8:  # an epoch time stamp: its magnitude names the unit (years 1973-2286)
        for u, f in factors.items():
            if 1e8 <= abs(t0) * f < 1e10:
                return u, f"inferred from the epoch time stamp {t0:.6g}"
    dt = _median_step(rel)  # of the steps forward: a batch's repeated stamps (with a counter) are no step
    cands = ("ms", "us", "ns", "s") if integer else ("s", "ms")
    best = min(cands, key=lambda u: abs(np.log10(1.0 / (dt * factors[u]) / TYPICAL_RATE_HZ)))
    why = "integer steps" if integer else "fractional values"
    return best, f"inferred: {why} of median {dt:.4g} give {1 / (dt * factors[best]):.4g} Hz in {best}"


def _datetime_time(s, path, label, lines):
    import pandas as pd

    try:
        ts = pd.to_datetime(pd.Series(s), format="ISO8601", utc=True)
    except (ValueError, TypeError):
        ts = None
    if ts is None or ts.isna().any():
        bad = 0 if ts is None else int(np.flatnonzero(ts.isna().to_numpy())[0])
        if ts is None:
            for i, v in enumerate(s):
                try:
                    pd.to_datetime(v, format="ISO8601")
                except (ValueError, TypeError):
                    bad = i
                    break
        raise RecordingError(f"{path}: {label}: {s[bad][:30]!r} at line {lines[bad]} is neither a number nor an "
                             "ISO 8601 date-time; pass --rate HZ to time the samples by their index")
    ns = ts.dt.tz_localize(None).to_numpy().astype("datetime64[ns]").astype(np.int64)
    t = (ns - ns[0]).astype(float) * 1e-9
    rate_hz = 1.0 / _median_step(t)
    return t, (f"time: ISO 8601 date-times from {ts.iloc[0].isoformat()} (UTC): {rate_hz:.4g} Hz, {t[-1]:.4g} s")


def _median_step(t) -> float:
    """The median of the positive steps of ``t`` (nan when there is none: time that does not
    increase is refused later, with its line, by :func:`accelcal.recording.checked_recording`)."""
    steps = np.diff(t)
    steps = steps if steps.size and steps.min() > 0 else steps[steps > 0]
    return float(np.median(steps, overwrite_input=True)) if steps.size else float("nan")  # a temporary: no copy
