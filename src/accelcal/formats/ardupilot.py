"""ArduPilot DataFlash binary logs (``.bin``): the ``IMU`` messages, read through ``pymavlink``.

``pymavlink`` is LGPL-3: it is the ``ardupilot`` extra, imported only here and only when
a DataFlash log is read, never by the core; accelcal does not ship or modify it.

What is read: ``IMU`` messages (``TimeUS`` [µs], ``GyrX/Y/Z`` [rad/s], ``AccX/Y/Z``
[m/s²], ``T`` [°C]); one instance per physical IMU, numbered by the field ``I`` in
current firmware and by the message name (``IMU``, ``IMU2``, ``IMU3``) in old logs.
ArduPilot logs them *after* its own calibration (``INS_ACCOFFS``/``INS_ACCSCAL`` and the
board rotation applied), so, as with PX4's ``sensor_combined``, a calibration fitted to
them corrects what the autopilot's left; the notes say so.  The message has one time
stamp (``TimeUS``): it serves both ``time_source`` values.

``pymavlink`` indexes the whole file when it opens it (a list of offsets per message
type) and prints damaged-header warnings on stderr, which are captured: a log it found
damaged bytes in is refused (its samples cannot be trusted).
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..errors import LogFormatError
from .ardupilot_mag import add_magnetometer
from .logs import (ColumnBuffer, Progress, check_time_source, choose, make_recording, microseconds, require_extra,
                   stamps_to_time, topic_origin)

#: A DataFlash log starts with the FMT message's header: 0xA3 0x95 0x80 (FMT describes itself).
DATAFLASH_MAGIC = b"\xa3\x95\x80"
_NAMES = ("IMU", "IMU2", "IMU3")
_CHUNK = 8192


def _short_format(path: Path) -> int | None:
    """The offset of an FMT message that declares a message length below 3 bytes, or None.

    pymavlink advances by the declared length minus the 3-byte header: a length of 0, 1 or
    2 sends it back over the same bytes forever (a damaged log seen to hang the reader).
    Every ``A3 95 80`` (the FMT message's header) is checked, including any that the data
    happen to contain: such a coincidence with a length below 3 is a few in 10^9 per byte."""
    d = np.fromfile(path, dtype=np.uint8)
    if d.size < 5:
        return None
    hit = (d[:-4] == 0xA3) & (d[1:-3] == 0x95) & (d[2:-2] == 0x80) & (d[4:] < 3)
    where = np.flatnonzero(hit)
    return int(where[0]) if where.size else None


def sniff(path, head: bytes) -> bool:
    """True for a DataFlash binary log (it opens with the FMT message of FMT)."""
    return head.startswith(DATAFLASH_MAGIC)


def read(path, *, topic: str | None = None, time_source: str = "header", instance: int | None = None,
         progress=None, mag_instance: int | None = None):
    """Read one IMU of an ArduPilot DataFlash log.

    Parameters
    ----------
    topic : {'IMU', 'IMU2', 'IMU3'}, optional
        The message name (old logs name instances so); default ``IMU``.
    instance : int, optional
        The ``I`` field of the IMU messages; needed when several IMUs are logged.
    time_source : {'header', 'log'}
        Both are ``TimeUS`` (the message's one stamp).
    progress : None, False or callable
    mag_instance : int, optional
        The compass (``MAG``'s ``I``) when several are logged (:mod:`.ardupilot_mag`).

    Returns
    -------
    Recording
        ``acc`` [m/s²], ``gyro`` [rad/s], ``temp`` [°C], ``mag`` [µT] (ArduPilot's
        correction undone) where ``MAG`` is logged.
    """
    check_time_source(time_source)
    path = Path(path)
    require_extra("ardupilot", path)
    from pymavlink import DFReader

    if not path.is_file():
        raise LogFormatError(f"{path}: no such file")
    bad = _short_format(path)
    if bad is not None:
        raise LogFormatError(f"{path}: the DataFlash log has damaged bytes (an FMT message at byte {bad} declares a "
                             "message shorter than its own header); its samples cannot be trusted: download the log "
                             "again")
    with _captured_output() as chatter:
        try:
            log = DFReader.DFReader_binary(str(path), zero_time_base=True)
        except Exception as e:
            log = e
    said = "".join(chatter)
    if isinstance(log, Exception):
        raise LogFormatError(f"{path}: not a readable DataFlash log ({_why(log)}); download it again")
    if "bad header" in said or "unknown msg type" in said:
        raise LogFormatError(f"{path}: the DataFlash log has damaged bytes ({_why(said)}); its samples "
                             "cannot be trusted: download the log again")
    try:
        counts = {name: int(log.counts[log.name_to_id[name]]) for name in _NAMES if name in log.name_to_id}
    except Exception as e:
        raise LogFormatError(f"{path}: cannot index the DataFlash log ({_why(e)})") from None
    everything = {name: f"{n} messages" for name, n in counts.items()}
    present = {k: v for k, v in everything.items() if counts[k] > 0}
    name = choose(path, present, topic, everything, kind="DataFlash IMU message", option="--topic")
    rows = _stream(log, path, name, counts[name], progress)
    inst = rows[:, 1].astype(int)
    present = sorted(set(inst.tolist()))
    cands = {str(i): f"{int(np.sum(inst == i))} samples" for i in present}
    chosen = int(choose(path, cands, None if instance is None else str(instance), cands,
                        kind=f"{name} instance", option="--instance"))
    rec = _recording(path, name, chosen, rows[inst == chosen], time_source)
    return add_magnetometer(rec, log, path, mag_instance)


@contextlib.contextmanager
def _captured_output():
    """Capture stdout and stderr at the file-descriptor level: pymavlink's compiled indexer writes
    its warnings there, past ``sys.stderr``."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    said: list[str] = []
    with tempfile.TemporaryFile(mode="w+") as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            with contextlib.redirect_stdout(f), contextlib.redirect_stderr(f):
                yield said
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            f.seek(0)
            said.append(f.read())


def _why(e) -> str:
    return (" ".join(str(e).split()) or type(e).__name__)[:120]


def _stream(log, path, name: str, count: int, progress) -> np.ndarray:
    """TimeUS, I, acc (3), gyro (3), T of every message ``name``, streamed into one array."""
    out = ColumnBuffer(count, 9)
    report = Progress(f"{path} {name}", count or None, progress)
    block = []
    try:
        while True:
            m = log.recv_match(type=name)
            if m is None:
                break
            d = m.to_dict()
            block.append((d["TimeUS"], d.get("I", 0), d["AccX"], d["AccY"], d["AccZ"], d["GyrX"], d["GyrY"],
                          d["GyrZ"], d.get("T", np.nan)))
            if len(block) == _CHUNK:
                out.extend(np.array(block, dtype=np.float64))
                block.clear()
                report(out.n)
        if block:
            out.extend(np.array(block, dtype=np.float64))
    except KeyError as e:
        raise LogFormatError(f"{path}: {name} messages lack the field {e} (not ArduPilot's IMU message)") from None
    except Exception as e:
        raise LogFormatError(f"{path}: damaged {name} message after {out.n + len(block)} ({_why(e)})") from None
    return out.result()


def _recording(path, name: str, inst: int, rows: np.ndarray, time_source: str):
    label = f"{name} instance {inst}"
    us = microseconds(rows[:, 0], path, f"{label}: TimeUS")
    t = stamps_to_time(us * 1000)
    acc, gyro, temp = rows[:, 2:5], rows[:, 5:8], rows[:, 8]
    steps = np.diff(t)
    rate = 1.0 / float(np.median(steps)) if len(steps) and np.all(steps > 0) else float("nan")
    notes = [f"ArduPilot DataFlash, {label}: {len(rows)} samples at {rate:.4g} Hz; AccX/Y/Z [m/s^2] and GyrX/Y/Z "
             "[rad/s] as logged, after ArduPilot's own calibration (INS_ACCOFFS/INS_ACCSCAL): a calibration fitted "
             "to them corrects what the autopilot's calibration left"]
    if time_source == "log":
        notes.append("the IMU message has one time stamp (TimeUS): used for --time-source log too")
    origin = topic_origin(label, time="TimeUS", time_fix="the log's stamps are not in order (a damaged log?)",
                          acc=("AccX", "AccY", "AccZ"), gyro=("GyrX", "GyrY", "GyrZ"))
    return make_recording(path, t=t, acc=acc, gyro=gyro, notes=notes, time_name="TimeUS", time_values=us,
                          temp=temp if np.any(np.isfinite(temp)) else None, origin=origin)  # no T field: nan


__all__ = ["read", "sniff"]
