"""What the subcommands share: the reading and static-detection options, option types,
the one-line error and warning, the progress line, provenance."""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from .. import __version__
from ..atomic import sha256_file
from ..errors import AccelcalError
from ..formats.registry import FORMATS, TIME_SOURCES
from ..registry import estimators
from ..units import G0

STANDARD_GRAVITY = 9.80665

MODEL_HELP = """\
model (Burkhard et al. 2024, eq. 1):  z = M x + b + e
  z  measured specific force of a static pose (mean of the rest interval)
  x  true specific force, |x| = g at rest
  b  bias;  M lower triangular, row i = (1 + s_i) u_i with scale factors s and
     non-orthogonality angles (theta_xy, theta_zx, theta_zy), see accelcal.model

methods:
{methods}

input: a table with time and three acceleration columns, e.g. a CSV with header
  t,ax,ay,az[,temp]; columns are found by their usual names (time, timestamp,
  acc_x, accX, AX, Accel. X, ...) or named with --columns t=...,ax=...,ay=...,az=...;
  comma, semicolon, tab or whitespace separated, decimal comma, # comments, gzip.
  temp      optional temperature column [degC]
  gyro      optional gyroscope columns (gx, gyr_x, wx, angular_velocity.x ...; rad/s,
            deg/s or counts: from the header, --gyro-unit, or decided by the motions),
            or --gyro FILE: calibrated from the same session
{formats}
units: acceleration in m/s^2, g, mg or raw counts (from the header, --unit, or the
  data's magnitude); g and mg are converted to m/s^2. --g is the local gravity in
  m/s^2. For raw counts the full models' M carries the sensitivity (counts per
  m/s^2) and b is in counts; the bias-only models need physical units.
  Time in s, ms, us, ns or ISO 8601 date-times (from the header, --time-unit, or
  the values), or --rate HZ when there is none.
clock: the samples are timed by the sensor's clock, fitted to the stamps against a
  sample counter (INDEX, seq, counter, sample, n_samples, header.seq; --columns
  counter=NAME) or the row index: host receive times that jitter or arrive in
  batches give the sensor's rate, and a gap only where samples are missing (the
  counter, or stamps shifted for good); rate, jitter and drift are in the read:
  lines; --clock stamps keeps the stamps as written. A gyro in a file of its own is
  aligned to the accelerometer by the motions both see (offset stated, applied).
logs: ROS 1/2 bags and MCAP files, PX4 ULog, ArduPilot DataFlash; the IMU topic is
  found (--topic, --instance when there are several), timed by the sensor's stamps
  (--time-source log: the log's clock); the gyroscope comes along.
exit status: 0 done; 2 bad input, refused (one line, nothing written); 3 with
  --strict (calibrate, export), the calibration's fit is untrustworthy (its quality
  warnings; calibrate still writes it, export writes nothing); 4 an internal error.
rests: the recording should start at rest (its noise sets the detection threshold,
  as in IMU-TK); if it does not, the quietest 2 s stretch is used, and said so.
  Known rests can be given with --intervals (imucal section list, CSV start,end).
"""

def _methods_help() -> str:
    return "\n".join(f"  {e.cli_name:<10} {e.description}, >= {e.min_poses} poses" for e in estimators("accelerometer"))


def fail(message: str, code: int = 2) -> int:
    print(f"accelcal: error: {message.splitlines()[0] if message else 'failed'}", file=sys.stderr)
    return code


def warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v != v or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _gravity(text: str) -> float:
    v = _positive(text)
    if not 9.7 <= v <= 9.9:
        raise argparse.ArgumentTypeError(f"{text} is not a gravity magnitude in m/s^2 (9.78-9.83 on the Earth's "
                                         "surface; data in g are converted, pass --unit g)")
    return v


def _reader_options(p) -> None:
    r = p.add_argument_group("reading the recording")
    # the reader checks the name (one error line, as for every input), so no argparse choices
    names = ", ".join(["auto", *FORMATS])
    r.add_argument("--format", default="auto", metavar="FMT", help=f"file format ({names}; default auto)")
    r.add_argument("--columns", metavar="SPEC",
                   help="which column is which: t=NAME,ax=NAME,ay=NAME,az=NAME[,gx=..,gy=..,gz=..][,temp=NAME]"
                        "[,counter=NAME] "
                        "(names or 1-based numbers)")
    r.add_argument("--unit", metavar="UNIT", help="acceleration unit: m/s2, g, mg or counts (overrides the header)")
    r.add_argument("--time-unit", metavar="UNIT", help="unit of the time column: s, ms, us or ns")
    r.add_argument("--rate", type=_positive, metavar="HZ", help="sampling rate: time from the sample index")
    r.add_argument("--clock", choices=("auto", "stamps"),
                   help="tables: time the samples by the sensor's clock fitted to the stamps against the sample "
                        "counter or the row index (auto, the default: host receive times jitter), or by the stamps as "
                        "they are (stamps)")
    r.add_argument("--intervals", type=Path, metavar="FILE",
                   help="known static intervals: imucal section list (JSON), JSON [[start, end], ...] in s, "
                        "or CSV with start,end columns (s, or start_index,end_index in samples)")
    r.add_argument("--variable", metavar="NAME[,NAME...]",
                   help="MATLAB and R files: the variable that is the recording (default the only one); several: runs "
                        "of one session recorded apart, each with its own rest and bias")
    r.add_argument("--gyro", type=Path, metavar="FILE",
                   help="the gyroscope in a file of its own, sampled with the accelerometer (IMU-TK's t x y z)")
    r.add_argument("--gyro-unit", metavar="UNIT", help="gyro unit: rad/s, deg/s or counts (overrides the header)")
    r.add_argument("--no-gyro", action="store_true", help="leave the gyroscope out (the accelerometer alone)")
    r.add_argument("--mag-unit", metavar="UNIT", help="magnetometer unit: uT, T, mT, nT, gauss, mG or counts "
                                                      "(overrides the header)")
    r.add_argument("--no-mag", action="store_true", help="leave the magnetometer out")
    # logs hold several sensors and two clocks; None: the reader's default, and refused by a table
    r.add_argument("--topic", metavar="NAME", help="logs: the IMU topic (ROS), sensor_accel or sensor_combined "
                                                   "(PX4), the IMU message (DataFlash); default the only one")
    r.add_argument("--instance", type=int, metavar="I", help="logs: the sensor instance (PX4 multi_id, DataFlash I)")
    r.add_argument("--mag-topic", metavar="NAME", help="ROS logs: the sensor_msgs/MagneticField topic (default the only "
                                                       "one)")
    r.add_argument("--mag-instance", type=int, metavar="I", help="PX4 and DataFlash logs: the magnetometer instance "
                                                               "(sensor_mag multi_id, MAG I) when several are logged")
    r.add_argument("--time-source", choices=TIME_SOURCES, help="logs: the sensor's stamps (header, the default) or "
                                                               "the times the log recorded the messages (log)")


def _static_options(p) -> None:
    s = p.add_argument_group("static detection (ignored with known intervals)")
    s.add_argument("--init-rest", default="auto", metavar="auto|none|SECONDS",
                   help="noise reference: auto (the initial rest, or the quietest 2 s if the recording does not start "
                        "at rest), none (the quietest 2 s), or the initial rest's length in s (default auto)")
    s.add_argument("--window", type=_positive, metavar="S", help="moving-variance window [s] (default 1)")
    s.add_argument("--threshold", type=_positive, metavar="K",
                   help="static if the window variance is below K x the reference's (default 6)")
    s.add_argument("--min-duration", type=float, metavar="S", help="shortest pose kept [s] (default 1)")
    s.add_argument("--trim", type=float, metavar="S", help="cut from each end of a pose that borders motion [s] "
                                                           "(default 0.25)")


@contextmanager
def _step(what: str, after_s: float = 2.0):
    """Announce ``what`` on stderr only if it is still running after ``after_s`` seconds and
    stderr is a terminal, so that quick runs print nothing but their summary (or their
    one-line error), and what a script reads does not depend on how loaded the machine is."""
    if not sys.stderr.isatty():
        yield
        return
    timer = threading.Timer(after_s, lambda: print(f"accelcal: {what} ...", file=sys.stderr, flush=True))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def _read(args, *, accelerometer: bool = True, time_column: bool = True):
    """The recording of ``args``; ``accelerometer``: the command needs one (a gyro alone is
    refused in one line); ``time_column``: keep the time column as written (what ``apply``
    writes back; a table's is cut from the file's text, which it keeps alive: 45 MB of a
    10⁶-row CSV that a command without it lets go while reading)."""
    from ..formats import read

    with _step(f"reading {args.recording}"):
        rec = read(args.recording, format=args.format, columns=args.columns, unit=args.unit,
                   time_unit=args.time_unit, rate=args.rate, intervals=args.intervals,
                   gyro=None if args.no_gyro else args.gyro, gyro_unit=args.gyro_unit, topic=args.topic,
                   instance=args.instance, time_source=args.time_source, clock=args.clock, variable=args.variable,
                   mag_unit=args.mag_unit, mag_topic=getattr(args, "mag_topic", None),
                   mag_instance=getattr(args, "mag_instance", None), time_column=time_column)
    if getattr(args, "no_mag", False):  # a log's magnetometer left out: no warning about it either
        from ..formats.mag_logs import MAG_WARNING

        rec = dataclasses.replace(rec, notes=tuple(n for n in rec.notes if not n.startswith(MAG_WARNING)))
    if accelerometer and rec.acc is None:
        raise AccelcalError(f"{args.recording}: no accelerometer in this recording (a gyro alone), which "
                            f"'accelcal {args.command}' needs; name its columns with --columns ax=..,ay=..,az=..")
    return rec


def _search_static(args) -> bool:
    """Search the detection settings (when the defaults find too few poses) unless the user set one."""
    return not any(getattr(args, k) is not None for k in ("window", "threshold", "min_duration", "trim"))


def _static_settings(args, rec) -> dict:
    """Keyword arguments of accelcal.static.detect_static from the options."""
    kw = {}
    init = str(args.init_rest).strip().lower()
    if init == "none":
        kw["noise_reference"] = "quietest"
    elif init != "auto":
        try:
            kw["init_duration"] = float(init)
        except ValueError:
            raise AccelcalError(f"--init-rest must be auto, none or a duration in s, got {args.init_rest!r}") from None
        if not kw["init_duration"] > 0:
            raise AccelcalError(f"--init-rest must be a positive duration in s, got {args.init_rest!r}")
        kw["noise_reference"] = "initial"
    for opt, key in (("window", "window"), ("threshold", "threshold_factor"), ("min_duration", "min_duration"),
                     ("trim", "trim")):
        v = getattr(args, opt)
        if v is not None:
            kw[key] = v
    if "threshold_factor" in kw and kw["threshold_factor"] <= 1:
        raise AccelcalError(f"--threshold must exceed 1 (a multiple of the reference variance), got {args.threshold}")
    for key in ("min_duration", "trim"):
        if key in kw and not kw[key] >= 0:
            raise AccelcalError(f"--{key.replace('_', '-')} must be >= 0, got {kw[key]}")
    return kw


def _nominal(args, rec):
    """The --sensitivity/--zero conversion of raw counts to m/s^2, or None."""
    if args.sensitivity is None:
        if args.zero is not None:
            raise AccelcalError("--zero needs --sensitivity (counts per g or per m/s2)")
        return None
    if rec.unit != "counts":
        raise AccelcalError(f"--sensitivity converts raw counts, but the data are read as {rec.unit} "
                            "(pass --unit counts if they are counts)")
    import numpy as np

    from ..nominal import NominalConversion

    def triple(text, what):
        try:
            v = np.array([float(x) for x in text.split(",")])
        except ValueError:
            raise AccelcalError(f"{what} must be one or three numbers separated by commas, got {text!r}") from None
        if v.size not in (1, 3) or not np.all(np.isfinite(v)):
            raise AccelcalError(f"{what} must be one or three numbers separated by commas, got {text!r}")
        return np.broadcast_to(v, (3,)).astype(float)

    text, per = args.sensitivity, "g"
    if "/" in text:
        text, per = text.split("/", 1)
    per = per.strip().lower().replace("²", "2").replace("^", "")
    if per not in ("g", "m/s2"):
        raise AccelcalError(f"--sensitivity: counts per g or per m/s2, got per {per!r}")
    sens = triple(text, "--sensitivity")
    if not np.all(sens > 0):
        raise AccelcalError("--sensitivity must be positive")
    cpu = sens / G0 if per == "g" else sens
    zero = np.zeros(3) if args.zero is None else triple(args.zero, "--zero")
    return NominalConversion(zero, cpu, None, f"--sensitivity {args.sensitivity}" +
                             (f" --zero {args.zero}" if args.zero else ""))


def _rate_hint(rec) -> str:
    rate = rec.rate
    if 1.0 <= rate <= 20000.0:
        return ""
    return (f" (the sampling rate is {rate:.4g} Hz from the time column: if its unit is not what was assumed, "
            "pass --time-unit s|ms|us|ns)")


def _provenance(args, t0: float) -> dict:
    return {"accelcal_version": __version__, "recording": str(args.recording),
            "recording_sha256": recording_sha256(args.recording), "elapsed_s": time.perf_counter() - t0}


def recording_sha256(path) -> str:
    """Hex sha256 of a recording: its file, or for a folder (a ROS 2 bag) its files' relative
    names and contents in name order."""
    path = Path(path)
    if not path.is_dir():
        return sha256_file(path)
    h = hashlib.sha256()
    for f in sorted(p for p in path.rglob("*") if p.is_file()):
        h.update(f.relative_to(path).as_posix().encode() + b"\0" + sha256_file(f).encode())
    return h.hexdigest()
