"""``accelcal apply`` onto a ROS bag or MCAP file, written back as a log of the same kind
(:mod:`accelcal.formats.ros_write`), and the one-line refusal for logs that cannot be."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..errors import AccelcalError
from .common import _step, warn
from .correct import check_source, corrected

#: Suffixes of log files: an --out with one of them asks for a log, which only ROS logs can be.
LOG_SUFFIXES = (".bag", ".mcap", ".db3", ".ulg", ".bin", ".tlog", ".log")
#: Reader options that only tables and gyro files take; a log names its own units and time.
_TABLE_OPTIONS = ("columns", "unit", "time_unit", "rate", "intervals", "gyro", "gyro_unit", "instance")
#: Relative difference of the noise report's rate from the log's above which the covariance is warned.
RATE_MISMATCH = 0.05


def writes_log(args) -> bool:
    """True when ``--out`` asks for a calibrated log and the recording is a ROS log; a one-line error
    when it asks for a log the recording cannot be written back as."""
    from ..formats import ros

    out, src = Path(args.out), Path(args.recording)
    if out.name.lower().endswith((".csv", ".csv.gz")) or not src.exists():
        return False  # a table; or a missing recording, which the reader names in its one line
    head = b""
    if src.is_file():
        with open(src, "rb") as f:
            head = f.read(16)
    if src.exists() and ros.sniff(src, head):
        return True
    if out.suffix.lower() in LOG_SUFFIXES:
        raise AccelcalError(f"{src} is {_kind(src, head)}, which accelcal cannot write back as a log (it writes ROS 1 "
                            "and ROS 2 bags and MCAP files); write the calibrated table: --out NAME.csv")
    return False


def _kind(src: Path, head: bytes) -> str:
    from ..formats import px4

    if px4.sniff(src, head):
        return "a PX4 ULog"
    if head[:2] == b"\xa3\x95":
        return "an ArduPilot DataFlash log"
    return "not a ROS bag or MCAP file"


def apply_to_log(args, cal) -> int:
    """Read the IMU topic, calibrate it, and write the log again with it corrected."""
    from ..formats import ros, ros_write

    given = [f"--{k.replace('_', '-')}" for k in _TABLE_OPTIONS if getattr(args, k, None) is not None]
    if given or args.format not in ("auto", "ros"):
        raise AccelcalError(f"{args.recording} is a ROS log written back as one: {', '.join(given) or '--format'} "
                            "does not apply (the log names its units, time and gyro)")
    ros_write.check_output(args.recording, ros._locate(Path(args.recording))[1], args.out)
    noise = _noise_report(args.noise) if args.noise is not None else None
    with _step(f"reading {args.recording}"):
        got = ros.read_topic(args.recording, topic=args.topic, time_source=args.time_source or "header")
    rec = got.recording
    check_source(cal, rec, args)
    x, w, effects, gyro_note = corrected(cal, rec, args)
    acc_cov, gyro_cov, cov_note = _covariances(noise, rec.rate, args)
    bag_x = x.copy()
    bag_x[got.order] = x
    bag_w = None
    if w is not None:
        bag_w = w.copy()
        bag_w[got.order] = w
    with _step(f"writing {args.out}"):
        counts = ros_write.write_calibrated(args.recording, args.out, topic=got.topic, stamps_ns=got.header_ns,
                                            acc=bag_x, gyro=bag_w, acc_cov=acc_cov, gyro_cov=gyro_cov,
                                            recovered=got.recovered)
    names = ", ".join(e.id for e in effects) or "none"
    fields = "linear_acceleration" + (" and angular_velocity" if w is not None else "")
    print(f"apply: {counts['corrected']} messages of {got.topic} in {args.recording} ({got.kind}) calibrated with "
          f"{args.calibration} ({cal.CAL_TYPE}; effects applied: {names}): {fields} replaced; "
          f"{counts['messages'] - counts['corrected']} other messages of {counts['topics'] - 1} other topics copied "
          f"verbatim; written to {args.out}", file=sys.stderr)
    for note in rec.notes:
        if note.startswith("warning: "):  # a damaged bag read up to its damage, clocks that disagree
            warn(note[len("warning: "):])
    for line in (cov_note, gyro_note):
        if line:
            print(f"  {line}", file=sys.stderr)
    return 0


def _noise_report(path: Path) -> dict:
    try:
        d = json.loads(Path(path).read_text())
    except OSError as e:
        raise AccelcalError(f"--noise {path}: {e.strerror or e}") from None
    except ValueError:
        raise AccelcalError(f"--noise {path}: not JSON (give the report of accelcal noise --out)") from None
    if not isinstance(d, dict) or d.get("format") != "accelcal-noise":
        raise AccelcalError(f"--noise {path}: not a noise report of accelcal noise (its format is "
                            f"{d.get('format') if isinstance(d, dict) else type(d).__name__!r})")
    return d


def _covariances(noise: dict | None, rate: float, args):
    """Per-axis per-sample variances N^2 f_s of the accelerometer and gyroscope (None: keep the recorded ones)."""
    if noise is None:
        return None, None, "covariances copied as recorded (--noise NOISE.json fills them)"
    out, said = [], []
    for sensor, unit, field in (("accelerometer", "m/s^2", "linear_acceleration"),
                                ("gyroscope", "rad/s", "angular_velocity")):
        s = (noise.get("sensors") or {}).get(sensor)
        if s is None:
            out.append(None)
            said.append(f"{field}_covariance copied as recorded (the noise report has no {sensor})")
            continue
        if s.get("unit") != unit:
            raise AccelcalError(f"--noise {args.noise}: the {sensor}'s noise is in {s.get('unit')}, the log's "
                                f"{field} in {unit}: measure the noise from data in {unit}")
        n = [float(s["axes"][a]["noise_density"]["value"]) for a in "xyz"]
        out.append([v * v * rate for v in n])
        said.append(f"{field}_covariance diag " + ", ".join(f"{v:.3g}" for v in out[-1]) + f" ({unit})^2")
    fs = float(noise.get("fs_hz") or rate)
    if abs(fs - rate) > RATE_MISMATCH * rate:
        warn(f"--noise {args.noise} was measured at {fs:.4g} Hz and this log's IMU runs at {rate:.4g} Hz: the "
             "variance N^2 f_s assumes the same sensor filter at both rates")
    return out[0], out[1], (f"covariances from {args.noise} (white noise N^2 f_s, f_s = {rate:.4g} Hz): "
                            + "; ".join(said))


__all__ = ["LOG_SUFFIXES", "apply_to_log", "writes_log"]
