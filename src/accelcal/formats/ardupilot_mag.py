"""ArduPilot's compass, the DataFlash ``MAG`` messages, beside the log's IMU (:func:`accelcal.formats.ardupilot.read`).

What is logged (``libraries/AP_Compass/LogStructure.h``: ``MAG``, format ``QBhhhhhhhhhBI``,
``TimeUS,I,MagX,MagY,MagZ,OfsX,OfsY,OfsZ,MOX,MOY,MOZ,Health,S``, units ``G``, multiplier
``C`` = 1e-3: milligauss; old logs name instances ``MAG``, ``MAG2``, ``MAG3``):
``Compass::Write_Compass_instance`` (``AP_Compass_Logging.cpp``) writes ``(int16_t)
get_field(i)`` — the *corrected* field — with ``get_offsets(i)`` and the motor offsets.
``AP_Compass_Backend::correct_field`` (``AP_Compass_Backend.cpp``) made it from the rotated
raw sample: ``mag += offsets; if (have_scale_factor) mag *= scale_factor; mag = mat * mag;
mag += motor_offset`` with ``mat`` symmetric from ``COMPASS_DIA*`` (diagonal) and
``COMPASS_ODI*`` (x: xy, y: xz, z: yz).  So the logged field has the offsets *and* the soft
iron applied: it is undone here, ``raw = mat⁻¹ (MagX − MOX) / scale − OfsX``, with the
offsets and motor offsets of each message and ``mat`` and ``scale`` from the log's ``PARM``
messages (``COMPASS_DIA_X`` ... for the first compass, ``COMPASS_DIA2_X`` ... for the
second).  Refused (one ``warning: magnetometer:`` note, the accelerometer and gyro read):
parameters absent or changed during the log, a ``COMPASS_SCALE`` in the band one firmware
version applies and another ignores (``COMPASS_MIN/MAX_SCALE_FACTOR``: 0.85–1.4 in older
``CompassCalibrator.h``, 1/1.5–1.5 in newer), and non-zero motor offsets (older firmware added
them *before* ``mat``, newer after: the order cannot be told from the log).

The logged field is the mean of the samples accumulated since the last read
(``drain_accumulated_samples``) truncated to whole milligauss (0.1 µT, a bias toward zero of
at most that), and a message is written at the logging rate whether or not the compass
updated: repeats of one sample (the same ``S``, the sample's time) are dropped.  Time:
``TimeUS``, the clock of the IMU's ``TimeUS``.  Milligauss converted to µT (x 0.1).
"""

from __future__ import annotations

import numpy as np

from ..errors import TopicError
from .logs import choose
from .mag_logs import attach, skipped

MAG_NAMES = ("MAG", "MAG2", "MAG3")
#: milligauss -> µT (``MAG_UNITS['mG']``).
MILLIGAUSS_TO_UT = 0.1
#: COMPASS_SCALE values every firmware version applies (the narrower of CompassCalibrator.h's ranges) ...
SCALE_APPLIED = (0.85, 1.4)
#: ... and outside of which every version ignores it.
SCALE_IGNORED = (1 / 1.5, 1.5)
_FIX = "pass --no-mag"


def add_magnetometer(rec, log, path, instance: int | None):
    """``rec`` with the log's compass (raw, µT) on its rows, or with one warning note (module docstring)."""
    rows = _messages(log)
    if not rows["t"]:
        return rec if instance is None else skipped(rec, "no MAG messages in this log")
    inst = np.array(rows["i"])
    cands = {str(i): f"{int(np.sum(inst == i))} messages" for i in sorted(set(rows["i"]))}
    try:
        chosen = int(choose(path, cands, None if instance is None else str(instance), cands,
                            kind="MAG instance", option="--mag-instance"))
    except TopicError as e:
        if instance is not None:
            raise
        return skipped(rec, f"{str(e).split(': ', 1)[-1]} (or --no-mag)")
    sel = inst == chosen
    a = {k: np.array(v, dtype=float)[sel] for k, v in rows.items() if k not in ("i", "parm")}
    try:
        mat, scale = _soft_iron(rows["parm"], chosen)
        raw_mg = _undo(a, mat, scale, chosen)
    except ValueError as e:
        return skipped(rec, f"MAG instance {chosen}: {e}; {_FIX}")
    fresh = np.r_[True, np.diff(a["S"]) != 0]  # the same sample logged again: once
    what = (f"MAG instance {chosen}: milligauss converted to uT, ArduPilot's COMPASS_OFS/DIA/ODI"
            f"{'/SCALE' if scale != 1.0 else ''} undone (raw = mat^-1 (MagX - MOX) / scale - OfsX)")
    notes = () if fresh.all() else (f"MAG instance {chosen}: {int((~fresh).sum())} repeated samples (the same S) "
                                    "left out",)
    imu_us = np.asarray(rec.time_column[1], dtype=np.int64)
    return attach(rec, (imu_us - imu_us[0]) * 1e-6, (a["t"][fresh] - imu_us[0]) * 1e-6,
                  raw_mg[fresh] * MILLIGAUSS_TO_UT, what, _FIX, extra_notes=notes)


def _messages(log) -> dict:
    """Every MAG message's time, instance, field, offsets, motor offsets and S; and the PARM values in order."""
    rows = {"t": [], "i": [], "m": [], "o": [], "mo": [], "S": [], "parm": []}
    log.rewind()
    while True:
        msg = log.recv_match(type=[*MAG_NAMES, "PARM"])
        if msg is None:
            return rows
        d = msg.to_dict()
        name = msg.get_type()
        if name == "PARM":
            if str(d.get("Name", "")).startswith("COMPASS_"):
                rows["parm"].append((d["Name"], float(d["Value"])))
            continue
        rows["t"].append(d["TimeUS"])
        rows["i"].append(int(d.get("I", MAG_NAMES.index(name))))
        rows["m"].append((d["MagX"], d["MagY"], d["MagZ"]))
        rows["o"].append((d.get("OfsX", 0), d.get("OfsY", 0), d.get("OfsZ", 0)))
        rows["mo"].append((d.get("MOX", 0), d.get("MOY", 0), d.get("MOZ", 0)))
        rows["S"].append(d.get("S", d["TimeUS"]))


def _soft_iron(parm: list, inst: int) -> tuple[np.ndarray, float]:
    """``mat`` and the applied scale of compass ``inst`` from the log's PARM values (ValueError: why not)."""
    n = "" if inst == 0 else str(inst + 1)
    seen: dict[str, set] = {}
    for name, value in parm:
        seen.setdefault(name, set()).add(value)

    def one(key, default=None):
        vals = seen.get(key)
        if vals is None:
            if default is None:
                raise ValueError(f"the log has no {key} parameter, so the soft iron ArduPilot applied is unknown")
            return default
        if len(vals) > 1:
            raise ValueError(f"{key} changes during the log ({', '.join(f'{v:g}' for v in sorted(vals))})")
        return vals.pop() if len(vals) == 1 else default

    prio, dev = seen.get(f"COMPASS_PRIO{inst + 1}_ID"), seen.get(f"COMPASS_DEV_ID{n}")
    if prio and dev and prio != dev:  # MAG's I counts by priority; the parameters are per stored compass
        raise ValueError(f"COMPASS_PRIO{inst + 1}_ID is not COMPASS_DEV_ID{n} (priorities reordered): which "
                         "parameters this compass used cannot be told")
    dia = [one(f"COMPASS_DIA{n}_{a}") for a in "XYZ"]
    if all(v == 0 for v in dia):  # correct_field: zero diagonals are taken as 1
        dia = [1.0, 1.0, 1.0]
    xy, xz, yz = (one(f"COMPASS_ODI{n}_{a}") for a in "XYZ")
    mat = np.array([[dia[0], xy, xz], [xy, dia[1], yz], [xz, yz, dia[2]]])
    s = one(f"COMPASS_SCALE{n}", 0.0)
    if SCALE_APPLIED[0] <= s <= SCALE_APPLIED[1]:
        return mat, s
    if SCALE_IGNORED[0] <= s <= SCALE_IGNORED[1]:
        raise ValueError(f"COMPASS_SCALE{n}={s:g} is applied by some firmware versions and ignored by others")
    return mat, 1.0


def _undo(a: dict, mat: np.ndarray, scale: float, inst: int) -> np.ndarray:
    """The raw (rotated, uncorrected) field [milligauss] from the logged corrected one."""
    if np.any(a["mo"] != 0):
        raise ValueError("motor compensation (MOX/MOY/MOZ) is applied, before the soft iron in older firmware and "
                         "after it in newer: it cannot be undone from the log (record with COMPASS_MOTCT=0)")
    if abs(np.linalg.det(mat)) < 1e-6:
        raise ValueError("COMPASS_DIA/ODI give a singular matrix")
    return np.linalg.solve(mat, a["m"].T).T / scale - a["o"]


__all__ = ["MAG_NAMES", "MILLIGAUSS_TO_UT", "add_magnetometer"]
