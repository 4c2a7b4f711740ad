"""``accelcal apply``: a calibration applied to a recording, written as a table."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..effects import TIME, effect
from ..errors import AccelcalError
from .common import _read, _reader_options, recording_sha256, warn

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
"""


def add_parser(sub, epilog: str) -> None:
    """The ``apply`` subcommand."""
    a = sub.add_parser("apply", help="apply a calibration to a recording",
                       description="Apply CALIBRATION to RECORDING: calibrated specific force in m/s^2.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=APPLY_HELP)
    a.add_argument("calibration", type=Path, help="calibration JSON (accelcal calibrate, or a discrepancy report)")
    a.add_argument("recording", type=Path, help="the recording to correct")
    a.add_argument("--out", type=Path, required=True, help="output CSV (written only on success)")
    a.add_argument("--no-effects", action="store_true", help="apply the base model only, not the fitted effects")
    _reader_options(a)
    a.set_defaults(func=_apply)


def _apply(args) -> int:
    from dataclasses import replace

    from ..calibration import load_calibration

    cal = load_calibration(args.calibration)
    rec = _read(args)
    expected = cal.input_unit or cal.unit
    if expected is not None and rec.unit != ("counts" if expected == "counts" else "m/s^2"):
        raise AccelcalError(f"{args.recording} is read as {rec.unit} but {args.calibration} was made from "
                            f"{expected}: pass --unit {'counts' if expected == 'counts' else 'm/s2 (or g, mg)'}")
    effects = () if args.no_effects else cal.effects
    # a term in time runs on the calibration session's clock: it describes that session only
    drift = [e.id for e in effects if effect(e.id).covariate == TIME]
    if drift and cal.provenance.get("recording_sha256") != recording_sha256(args.recording):
        warn(f"the calibration's {', '.join(drift)} term describes the drift during its own session; it is not "
              "applied to another recording")
        effects = tuple(e for e in effects if e.id not in drift)
    cal = replace(cal, effects=effects)
    x = cal.apply(rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit)
    w, gyro_note = _gyro(cal, rec, args)
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


def _gyro(cal, rec, args):
    """The calibrated rate [rad/s] (or None) and a line on why the gyro was not corrected."""
    if cal.gyro is None:
        return None, "" if rec.gyro is None else "gyro not corrected: the calibration has no gyroscope"
    if rec.gyro is None or args.no_gyro:
        return None, "the calibration's gyroscope not applied: the recording has no gyro (--gyro FILE)"
    import numpy as np

    from ..units import ANGULAR_RATE_UNITS

    made = cal.gyro.model.raw_unit
    have = rec.gyro_unit or "rad/s"
    if (made == "counts") != (have == "counts"):
        raise AccelcalError(f"the recording's gyro is read as {have} but {args.calibration}'s gyroscope was made from "
                            f"{made}: pass --gyro-unit {made}")
    raw = rec.gyro if made == have else np.asarray(rec.gyro) * (ANGULAR_RATE_UNITS[have] / ANGULAR_RATE_UNITS[made])
    return cal.apply_gyro(raw, rec.acc, t=rec.t, temp=rec.temp, unit=rec.unit), ""


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

    from ..atomic import atomic_output

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
