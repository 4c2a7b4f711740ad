"""The magnetometer on the command line: its step in ``accelcal calibrate`` and ``accelcal mag``.

``accelcal calibrate`` calibrates the magnetometer whenever the recording has its columns
(``mx``, ``mag_x``, ``Mag. X``, ``magnetic_field.x`` ...) and ``--no-mag`` is not given,
after the accelerometer, aligned to it from the same rests; a magnetometer that cannot be
calibrated (a zero column, a planar rotation, a disturbance) leaves the accelerometer's
and the gyro's calibration written with one ``warning: magnetometer:`` line.
``accelcal mag`` is for sessions that are about the magnetometer: a magnetometer alone, or
hand rotations without rests (the samples whose specific force is close to g align it).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..atomic import atomic_output, write_json_atomic
from ..errors import AccelcalError
from ..mag.errors import MagInputError
from ..mag.registry import MAG_ESTIMATORS
from .common import _positive, warn

EXPORTS = ("px4", "ardupilot", "magneto")


def add_mag_options(c) -> None:
    names = [e.cli_name for e in MAG_ESTIMATORS.values()]
    g = c.add_argument_group("magnetometer (calibrated whenever the recording has its columns: mx, mag_x, ...)")
    g.add_argument("--mag-method", choices=names, default=names[0], help=f"ellipsoid estimator (default {names[0]})")
    g.add_argument("--location", metavar="LAT,LON[,ALT_KM]",
                   help="where the session was recorded: the field's strength and dip from a geomagnetic model "
                        "(with --date); without it the field is normalised to its fitted strength")
    g.add_argument("--date", metavar="YYYY-MM-DD", help="when the session was recorded (with --location)")


def field_from_args(args):
    """``{'strength', 'unit', 'dip_deg', 'source'}`` from --location/--date, or None."""
    if args.location is None and args.date is None:
        return None
    if args.location is None or args.date is None:
        raise AccelcalError("--location and --date go together (the geomagnetic field depends on both)")
    from ..mag.field import model_field

    return model_field(args.location, args.date)


def wants_mag(args, rec) -> bool:
    return getattr(rec, "mag", None) is not None and not args.no_mag


def note_mag(args, rec) -> str:
    if rec.mag is None:
        return ""
    return "magnetometer columns ignored (--no-mag)" if args.no_mag else ""


def calibrate(args, rec, cal, poses):
    """The magnetometer of ``rec`` aligned to ``cal``, or None with one warning line."""
    from ..mag.calibrate import calibrate_magnetometer

    field = field_from_args(args)  # a bad --location is the user's to fix: an error, not a warning
    try:
        return calibrate_magnetometer(rec.mag, raw_unit=rec.mag_unit or "unknown", acc_cal=cal, poses=poses,
                                      acc=rec.acc, estimator=args.mag_method, field=field, source=str(rec.source))
    except AccelcalError as e:
        warn(f"magnetometer: not calibrated: {e}")
        return None


def add_parser(sub, epilog: str) -> None:
    """The ``mag`` subcommand."""
    c = sub.add_parser("mag", help="calibrate a magnetometer (alone, or with the accelerometer of the same session)",
                       description="Fit the magnetometer's hard and soft iron to RECORDING's field samples, with "
                                   "standard errors from the noise at rest; with accelerometer columns, align it to "
                                   "the accelerometer (rests, or samples whose specific force is close to g) and "
                                   "estimate the dip. Trust lines: coverage, chi2/dof, dip consistency.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog)
    c.add_argument("recording", type=Path, help="a table with mx, my, mz (and ax, ay, az) columns, or a log: a ROS "
                                                "bag or MCAP file with a sensor_msgs/MagneticField topic, a PX4 ULog "
                                                "with sensor_mag, an ArduPilot DataFlash log with MAG")
    c.add_argument("--out", type=Path, required=True, help="magnetometer calibration JSON (written only on success)")
    c.add_argument("--columns", metavar="ROLE=COL,...", help="which column is which (mx=..,my=..,mz=..,ax=..)")
    c.add_argument("--mag-unit", metavar="UNIT", help="magnetometer unit: uT, T, mT, nT, gauss, mG or counts")
    c.add_argument("--unit", metavar="UNIT", help="acceleration unit: m/s2, g, mg or counts")
    c.add_argument("--rate", type=_positive, metavar="HZ", help="sampling rate (files without time)")
    lg = c.add_argument_group("logs (ROS, PX4, ArduPilot): which sensors, which clock")
    lg.add_argument("--topic", metavar="NAME", help="the IMU topic or message (default the only one)")
    lg.add_argument("--instance", type=int, metavar="I", help="the IMU instance (PX4 multi_id, DataFlash I)")
    lg.add_argument("--mag-topic", metavar="NAME", help="ROS: the sensor_msgs/MagneticField topic (default the only one)")
    lg.add_argument("--mag-instance", type=int, metavar="I", help="PX4 sensor_mag multi_id, DataFlash MAG I")
    lg.add_argument("--time-source", choices=("header", "log"), help="the sensors' stamps (header, the default) or the "
                                                                    "times the log recorded the messages (log)")
    c.add_argument("--g-tolerance", type=_positive, default=0.02, metavar="REL",
                   help="without rests: samples whose |specific force| is within REL of its median align the "
                        "magnetometer (default 0.02)")
    c.add_argument("--export", choices=EXPORTS, action="append", default=[],
                   help="also write the parameters for PX4, ArduPilot or Magneto's form beside --out")
    add_mag_options(c)
    c.set_defaults(func=_mag)


def _mag(args) -> int:
    from ..mag.calibrate import calibrate_magnetometer

    field = field_from_args(args)
    tab = _read_session(args)
    acc_cal, poses, how = _accelerometer(tab, args)
    mcal = calibrate_magnetometer(tab.mag, raw_unit=tab.mag_unit, acc_cal=acc_cal, poses=poses, acc=tab.acc,
                                  estimator=args.mag_method, field=field, source=str(args.recording),
                                  g_tolerance=args.g_tolerance)
    doc = {"format": "accelcal-magnetometer", "format_version": 1, "recording": str(args.recording),
           "accelerometer": how, "magnetometer": mcal.to_dict()}

    outputs = _exports(mcal, args)  # every export made (or refused) before anything is written
    write_json_atomic(args.out, json.loads(json.dumps(doc, default=_plain)))
    for path, text in outputs:
        with atomic_output(path) as tmp:
            Path(tmp).write_text(text)
    for n in tab.notes:
        print(f"read: {n}", file=sys.stderr)
    print(f"accelerometer: {how}", file=sys.stderr)
    print(mcal.summary(written_to=", ".join([str(args.out), *(str(p) for p, _ in outputs)])), file=sys.stderr)
    return 0


LOG_FORMATS = ("ros", "px4", "ardupilot")


def _read_session(args):
    """The magnetometer (and accelerometer) of a table, or of a log's IMU and magnetometer (one
    line naming the cause and the option when the log's magnetometer cannot be read)."""
    from ..formats import detect_format, read
    from ..formats.mag_logs import mag_problem
    from ..formats.mag_table import MagTable, read_mag_table

    path = args.recording
    if not path.exists() or detect_format(path) not in LOG_FORMATS:
        return read_mag_table(path, columns=args.columns, mag_unit=args.mag_unit, unit=args.unit, rate=args.rate)
    rec = read(path, topic=args.topic, instance=args.instance, time_source=args.time_source,
               mag_topic=args.mag_topic, mag_instance=args.mag_instance)
    if rec.mag is None:
        why = mag_problem(rec) or "no magnetometer in this log (no sensor_msgs/MagneticField topic, sensor_mag or MAG)"
        for tail in (", or pass --no-mag", "; pass --no-mag", " (or --no-mag)"):  # calibrate's option, not this one's
            why = why.removesuffix(tail)
        raise MagInputError(f"{path}: {why}")
    return MagTable(rec.t, rec.mag, rec.mag_unit, rec.acc, rec.unit, rec.notes)


def _plain(x):
    import numpy as np

    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(type(x).__name__)


def _accelerometer(tab, args):
    """The accelerometer's calibration and rests when the table has them, else None and why."""
    if tab.acc is None:
        return None, None, "none (a magnetometer alone: the ellipsoid only, no alignment or dip)"
    from ..calibration import calibrate_recording
    from ..recording import Recording

    rec = Recording(tab.t, tab.acc, None, str(args.recording), unit=tab.acc_unit)
    try:  # standard gravity: the alignment uses directions only, never the magnitude
        cal, poses = calibrate_recording(rec, 9.80665, "full_lls", search=True)
        return cal, poses, f"calibrated from {len(poses.means)} rests (full-lls): the rests align the magnetometer"
    except AccelcalError as e:
        return None, None, (f"not calibrated ({str(e).split(';')[0]}): the raw samples whose |specific force| is "
                            f"within {100 * args.g_tolerance:g} % of its median align the magnetometer")


def _exports(mcal, args):
    from ..mag import export

    out = []
    for kind in args.export:
        text = {"px4": export.px4_params, "ardupilot": export.ardupilot_params,
                "magneto": export.magneto_text}[kind](mcal.model)
        out.append((args.out.with_name(f"{args.out.stem}.{kind}.txt"), text))
    return out


__all__ = ["add_mag_options", "add_parser", "calibrate", "field_from_args", "note_mag", "wants_mag"]
