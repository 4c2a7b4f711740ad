"""``accelcal apply``: a calibration applied to a recording, written as a table."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..atomic import atomic_output
from ..errors import AccelcalError
from . import apply_log
from .common import _read, _reader_options, warn
from .correct import check_source, corrected

APPLY_HELP = """\
CALIBRATION is the JSON of `accelcal calibrate` or the report of `accelcal
discrepancy` (its base model plus the named effects, e.g. a temperature term).
RECORDING is read with the same readers and options as for calibrate (a table, or
the IMU topic of a ROS bag, MCAP file, PX4 ULog or DataFlash log), in the unit the
calibration was made from. The output CSV keeps the time column as it was recorded
(e.g. header_stamp_ns of a bag, timestamp_sample_us of a ULog) and writes the
calibrated ax, ay, az in m/s^2; when the calibration has a gyroscope and the recording
a gyro (its columns, its log topic or --gyro FILE), the calibrated gx, gy, gz in rad/s
in the accelerometer's frame; a gyro the calibration does not correct is written as
recorded, as gx_raw, gy_raw, gz_raw; when the calibration has a magnetometer and the
recording its columns, the calibrated mx, my, mz (unit field, or uT with --location, in
the accelerometer's frame; uncorrected: mx_raw, my_raw, mz_raw); and temp, if present.

Calibrated logs: a ROS 1 bag, ROS 2 bag (folder, or its .db3 file) or MCAP file is
written back as a log of the same kind when --out is not a .csv (OUT.bag, a new folder,
OUT.db3, OUT.mcap): its sensor_msgs/Imu topic calibrated, every other topic copied
verbatim, and with --noise NOISE.json (accelcal noise) the linear_acceleration and
angular_velocity covariances filled with the per-sample white-noise variance N^2 f_s.
Other logs (PX4 ULog, DataFlash) are written as tables only.
Data already calibrated by an autopilot (PX4 sensor_combined) are refused unless
--already-calibrated says that the calibration was fitted to them; a calibration made
on another unit (its device id differs from the log's) is warned.
"""


def add_parser(sub, epilog: str) -> None:
    """The ``apply`` subcommand."""
    a = sub.add_parser("apply", help="apply a calibration to a recording",
                       description="Apply CALIBRATION to RECORDING: calibrated specific force in m/s^2.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=APPLY_HELP)
    a.add_argument("calibration", type=Path, help="calibration JSON (accelcal calibrate, or a discrepancy report)")
    a.add_argument("recording", type=Path, help="the recording to correct")
    a.add_argument("--out", type=Path, required=True,
                   help="output: a .csv table, or for a ROS bag / MCAP file a calibrated log of the same kind "
                        "(written only on success)")
    a.add_argument("--no-effects", action="store_true", help="apply the base model only, not the fitted effects")
    a.add_argument("--noise", type=Path, metavar="JSON",
                   help="noise report (accelcal noise): fills the covariances of a calibrated ROS log")
    a.add_argument("--already-calibrated", action="store_true",
                   help="apply to data an autopilot calibrated already (PX4 sensor_combined): only when the "
                        "calibration was fitted to such data")
    _reader_options(a)
    a.set_defaults(func=_apply)


def _apply(args) -> int:
    from ..calibration import load_calibration

    cal = load_calibration(args.calibration)
    if apply_log.writes_log(args):
        return apply_log.apply_to_log(args, cal)
    if args.noise is not None:
        warn("--noise fills the covariances of a calibrated ROS log; a table has none: not used")
    rec = _read(args)
    check_source(cal, rec, args)
    x, w, effects, gyro_note = corrected(cal, rec, args)
    m = _mag(cal, rec, args)
    _write_corrected(args.out, rec, x, w, m)
    names = ", ".join(e.id for e in effects) or "none"
    written = "ax, ay, az in m/s^2" + (", gx, gy, gz in rad/s" if w is not None else
                                       ", gx_raw, gy_raw, gz_raw as recorded" if rec.gyro is not None else "")
    if m is not None:
        written += f", mx, my, mz ({cal.mag.model.strength_unit})"
    print(f"apply: {rec.n} samples of {args.recording} calibrated with {args.calibration} ({cal.CAL_TYPE}; "
          f"effects applied: {names}); {written} written to {args.out}", file=sys.stderr)
    if gyro_note:
        print(f"  {gyro_note}", file=sys.stderr)
    return 0


def _mag(cal, rec, args):
    """The calibrated field (or None when the calibration or the recording has no magnetometer)."""
    if getattr(cal, "mag", None) is None or rec.mag is None or args.no_mag:
        return None
    made = cal.mag.model.raw_unit
    have = rec.mag_unit or "unknown"
    if made != have:
        raise AccelcalError(f"the recording's magnetometer is read as {have} but {args.calibration}'s magnetometer "
                            f"was made from {made}: pass --mag-unit {made}")
    return cal.mag.apply(rec.mag)


def _write_corrected(path: Path, rec, x, w=None, m=None) -> None:
    import pandas as pd

    time_name, time_values = rec.time_column if rec.time_column is not None else ("t", rec.t)
    data = {time_name: time_values, "ax": x[:, 0], "ay": x[:, 1], "az": x[:, 2]}
    if w is not None:
        data.update(gx=w[:, 0], gy=w[:, 1], gz=w[:, 2])
    elif rec.gyro is not None:  # not corrected: named apart, so that nobody takes it for calibrated
        data.update(gx_raw=rec.gyro[:, 0], gy_raw=rec.gyro[:, 1], gz_raw=rec.gyro[:, 2])
    if m is not None:
        data.update(mx=m[:, 0], my=m[:, 1], mz=m[:, 2])
    elif rec.mag is not None:
        data.update(mx_raw=rec.mag[:, 0], my_raw=rec.mag[:, 1], mz_raw=rec.mag[:, 2])
    if rec.temp is not None:
        data["temp"] = rec.temp
    with atomic_output(path) as tmp, open(tmp, "w", newline="") as f:
        pd.DataFrame(data).to_csv(f, index=False)
