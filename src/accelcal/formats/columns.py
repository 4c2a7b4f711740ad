"""Which column of a table is which: roles (time, acceleration, gyro, magnetometer,
temperature, pose, counter) found by the header's names (:data:`ALIASES`) or given with
``--columns``, and the units the names state.  Shared by the table readers
(:mod:`.table`, :mod:`.gyro_file`, :mod:`.mag_table`).
"""

from __future__ import annotations

import re

from ..errors import RecordingError
from ..units import unit_in_name
from .clock import is_counter_name
from .magnetic import MAG_ROLES, mag_axis, mag_unit_in_name
from .parsing import norm_name

ROLES = ("t", "ax", "ay", "az", "gx", "gy", "gz", "mx", "my", "mz", "temp", "pose", "counter")
ACC_ROLES, GYRO_ROLES = ("ax", "ay", "az"), ("gx", "gy", "gz")

#: Column names (lower case, without unit, separators removed) for each role.
_ACC = re.compile(r"^(?:field)?(?:imu)?(?:linear)?(?:acc|accel|accl|acceleration|accelerometer|acceleromter|a)"
                  r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_ACC_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:acc|accel|acceleration|a)$")
_GYRO = re.compile(r"^(?:field)?(?:imu)?(?:g|gyr|gyro|gyroscope|w|omega|angularvelocity|angvel|angularrate|rate)"
                   r"(?:raw|meas|measured)?(?P<axis>[xyz])$")
_GYRO_AXIS_FIRST = re.compile(r"^(?P<axis>[xyz])(?:gyr|gyro|g|w)$")
_TIME = {"t", "time", "times", "timestamp", "timestamps", "ts", "stamp", "sec", "secs", "seconds", "elapsed",
         "elapsedtime", "datetime", "date", "clock", "millis", "micros", "nanos", "tsec", "fieldheaderstamp",
         "headerstamp", "%time", "timeus", "timems", "timens", "zeit", "zeitstempel", "tiempo", "temps", "tempo"}
_TIME_UNIT_BY_NAME = {"millis": "ms", "micros": "us", "nanos": "ns", "timems": "ms", "timeus": "us", "timens": "ns"}
_TEMP = {"temp", "temperature", "imutemp", "dietemp", "temperaturec", "tempc", "thermometer"}
_POSE = {"pose", "poseid", "staticpose", "posename"}
#: Documented for the CLI's help: what each role is found by.
ALIASES = {
    "t": "t, time, timestamp, ts, stamp, seconds, elapsed, datetime, millis, micros, %time, field.header.stamp",
    "ax, ay, az": "ax, acc_x, accX, AX, accel_x, Accel. X, a_x, x_acc, acceleration_x, accelerometer_x, "
                  "linear_acceleration.x (x, y, z alone when nothing else matches)",
    "gx, gy, gz": "gx, gyr_x, gyro_x, gyroX, Gyro. X, wx, omega_x, angular_velocity.x (optional: the "
                  "gyroscope)",
    "mx, my, mz": "mx, mag_x, magX, Mag. X, magnetometer_x, compass_x, magnetic_field.x (optional: the "
                  "magnetometer; units uT, T, mT, nT, gauss, mG or counts)",
    "temp": "temp, temperature, imu_temp, die_temp",
    "pose": "pose, pose_id (label of the known static pose of each sample; empty between poses)",
    "counter": "INDEX, seq, counter, sample, n_samples, field.header.seq ... (a sample counter: the clock's "
               "sample numbers, accelcal.formats.clock)",
}


def parse_columns(spec) -> dict:
    """``'t=time,ax=AccX,...'`` (or a dict) → ``{role: name or 0-based index}``.

    Numbers are 1-based column positions (as a user counts them); names match the header
    with its whitespace stripped, case-insensitively.
    """
    if spec is None:
        return {}
    items = spec.items() if isinstance(spec, dict) else (
        (p.split("=", 1) if "=" in p else (p, None)) for p in str(spec).split(",") if p.strip())
    out = {}
    for role, col in items:
        role = str(role).strip().lower()
        if role not in ROLES or col is None or str(col).strip() == "":
            raise RecordingError(f"--columns: expected ROLE=COLUMN with ROLE in {', '.join(ROLES)} "
                                 f"(e.g. t=time,ax=AccX,ay=AccY,az=AccZ), got {role!r}")
        col = str(col).strip()
        if col.isdigit():
            if int(col) < 1:
                raise RecordingError(f"--columns: column numbers start at 1, got {role}={col}")
            out[role] = int(col) - 1
        else:
            out[role] = col
    return out


def map_columns(names, k: int, given: dict, path, required=ACC_ROLES) -> tuple[dict, dict]:
    """``{role: column index}`` and ``{role: unit found in the header}``; the ``required``
    roles must be found."""
    units = {}
    roles = _headerless_roles(k, given, path) if names is None else _header_roles(names, k, given, path)
    if "counter" in given:
        units["counter_given"] = True
    found = ", ".join(n.strip() for n in names)[:150] if names is not None else f"{k} unnamed columns"
    missing = [r for r in required if r not in roles]
    if missing and required == ACC_ROLES and not any(r in roles for r in ACC_ROLES) and \
            all(r in roles for r in GYRO_ROLES):
        missing = []  # a gyro-only table (rate-table rotations): the gyro columns named, no accelerometer
    if missing:
        raise RecordingError(f"{path}: no column for {', '.join(missing)} (found: {found}); "
                             "name them with --columns t=TIME,ax=X,ay=Y,az=Z (a gyro alone: gx=..,gy=..,gz=..)")
    _drop_partial_triads(names, roles, given, units, path)
    used = {}
    for role, i in roles.items():
        if i in used:
            raise RecordingError(f"{path}: column {i + 1} given for both {used[i]} and {role}")
        used[i] = role
    if names is not None:
        _header_units(names, roles, units)
    return roles, units


def _headerless_roles(k: int, given: dict, path) -> dict:
    """The roles of a table without header: ``--columns`` by number, else by the column count."""
    if any(isinstance(v, str) for v in given.values()):
        raise RecordingError(f"{path}: the file has no header, so --columns needs column numbers "
                             "(e.g. t=1,ax=2,ay=3,az=4)")
    default = {4: ("t", "ax", "ay", "az"), 3: ("ax", "ay", "az"), 5: ("t", "ax", "ay", "az", "temp")}
    if not given and k not in default:
        raise RecordingError(f"{path}: no header and {k} columns: say which is which with --columns "
                             "(e.g. t=1,ax=2,ay=3,az=4)")
    return dict(given) if given else {r: i for i, r in enumerate(default[k])}


def _header_roles(names, k: int, given: dict, path) -> dict:
    """The roles of a table with a header: ``--columns`` (by number or name), the rest by the aliases."""
    roles = {}
    stripped = [n.strip() for n in names]
    for role, col in given.items():
        if isinstance(col, int):
            if col >= k:
                raise RecordingError(f"{path}: --columns {role}={col + 1}: the table has {k} columns")
            roles[role] = col
        else:
            hits = [i for i, n in enumerate(stripped) if n.lower() == col.lower()]
            if not hits:
                raise RecordingError(f"{path}: --columns {role}={col}: no such column "
                                     f"(found: {', '.join(stripped)[:150]})")
            roles[role] = hits[0]
    _find_roles(stripped, roles, path)
    return roles


def _drop_partial_triads(names, roles: dict, given: dict, units: dict, path) -> None:
    """A gyro or magnetometer with a column for only some axes: refused when ``--columns``
    named it, else not read (the gyro with a note in ``units``)."""
    gyro = [r for r in GYRO_ROLES if r in roles]
    if 0 < len(gyro) < 3:
        if any(r in given for r in GYRO_ROLES):
            raise RecordingError(f"{path}: --columns names a gyro column for {', '.join(gyro)} but none for "
                                 f"{', '.join(r for r in GYRO_ROLES if r not in roles)}: name all three "
                                 "(gx=..,gy=..,gz=..)")
        which = ", ".join(names[roles[r]].strip() for r in gyro)
        units["gyro_note"] = (f"gyro: a column for {', '.join(gyro)} only ({which}): not read (name all three with "
                              "--columns gx=..,gy=..,gz=..)")
        for r in gyro:
            del roles[r]
    mag = [r for r in MAG_ROLES if r in roles]
    if 0 < len(mag) < 3:
        if any(r in given for r in MAG_ROLES):
            raise RecordingError(f"{path}: --columns names a magnetometer column for {', '.join(mag)} only: name "
                                 "all three (mx=..,my=..,mz=..)")
        for r in mag:
            del roles[r]


def _header_units(names, roles: dict, units: dict) -> None:
    """The units the header's names state (``acc_x [g]``, ``time_ms``...), into ``units``."""
    for role in (r for r in MAG_ROLES if r in roles):
        u = mag_unit_in_name(names[roles[role]].strip())[1]
        if u is not None:
            units.setdefault("mag_units", {})[role] = u
    for role, i in roles.items():
        if role in MAG_ROLES:
            continue
        kind = {"t": "time", "temp": "temperature", "pose": None, "counter": None}.get(
            role, "angular_rate" if role in GYRO_ROLES else "acceleration")
        if kind:
            base, u = unit_in_name(names[i].strip(), kind)
            if role == "t" and u is None:
                u = _TIME_UNIT_BY_NAME.get(norm_name(base))
            if u is not None:
                units.setdefault(role, u)
                if role in ACC_ROLES:
                    units.setdefault("acc_units", {})[role] = u
                if role in GYRO_ROLES:
                    units.setdefault("gyro_units", {})[role] = u


def _find_roles(names, roles: dict, path) -> None:
    """Fill ``roles`` (in place) from the header by the aliases, for roles not given."""
    cand = {r: [] for r in ROLES}
    for i, n in enumerate(names):
        if i in roles.values():
            continue
        for kind in ("acceleration", "angular_rate", "time", "temperature"):
            base, _ = unit_in_name(n, kind)
            key = norm_name(base)
            m = _ACC.match(key) or _ACC_AXIS_FIRST.match(key)
            mg = _GYRO.match(key) or _GYRO_AXIS_FIRST.match(key)
            if kind == "acceleration" and m:
                cand["a" + m.group("axis")].append(i)
            elif kind == "angular_rate" and mg:
                cand["g" + mg.group("axis")].append(i)
            elif kind == "time" and (key in _TIME or key in _TIME_UNIT_BY_NAME):
                cand["t"].append(i)
            elif kind == "temperature" and key in _TEMP:
                cand["temp"].append(i)
        axis = mag_axis(norm_name(mag_unit_in_name(n)[0]))
        if axis is not None:
            cand["m" + axis].append(i)
        if norm_name(n) in _POSE:
            cand["pose"].append(i)
        if is_counter_name(n):
            cand["counter"].append(i)
    if not any(cand[a] for a in ("ax", "ay", "az")) and not any(r in roles for r in ("ax", "ay", "az")):
        for i, n in enumerate(names):  # plain x, y, z columns (FastAhrs 'x, y, z')
            if norm_name(n) in ("x", "y", "z") and i not in roles.values():
                cand["a" + norm_name(n)].append(i)
    for role, hits in cand.items():
        hits = sorted(set(hits))
        if role in roles or not hits:
            continue
        if role == "t" and len(hits) > 1 and {norm_name(names[i]) for i in hits} == {"%time", "fieldheaderstamp"}:
            # rostopic echo -p: %time is when the message was received, the header stamp
            # when the sensor sampled it
            hits = [i for i in hits if norm_name(names[i]) == "fieldheaderstamp"]
        if role == "counter":
            hits = hits[:1]  # the first counter; --columns counter=NAME chooses another
        if len(hits) > 1:
            raise RecordingError(f"{path}: {len(hits)} columns could be {role} ({', '.join(names[i] for i in hits)}); "
                                 f"choose one with --columns {role}=NAME")
        roles[role] = hits[0]
