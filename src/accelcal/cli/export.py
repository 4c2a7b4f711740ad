"""``accelcal export``: a calibration (and a noise report) in the file a consumer loads."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..errors import AccelcalError
from ..export.registry import CONSUMERS, consumers_help
from .common import _positive, fail, warn

EXPORT_HELP = """\
Each file follows its consumer's own equations (docs/export.md cites the source lines).
A term the consumer's model cannot hold (PX4 and ArduPilot have no misalignment, VINS and
ORB-SLAM3 no intrinsics, IMU-TK no g-sensitivity, none the fitted effects) is left out and
the summary says what that costs at the worst orientation (mg, deg/s); --exact refuses
such an export instead. Implausible calibrations are refused (a scale outside 1 +- 20 %,
an offset beyond the sensor's range, a matrix that is not positive definite).
--imutk PREFIX and --imucal FILE are short for --to imutk --out PREFIX, --to imucal --out FILE.

exit status: 0 written; 2 bad input or refused, nothing written; 3 with --strict, the
calibration's fit is untrustworthy (its quality warnings), nothing written.
"""


def add_parser(sub, epilog: str) -> None:
    """The ``export`` subcommand."""
    e = sub.add_parser("export", help="write a calibration for Kalibr, OpenVINS, VINS, ORB-SLAM3, KF-GINS, PX4, "
                                      "ArduPilot, IMU-TK or imucal",
                       description="Write CALIBRATION (accelcal calibrate's JSON) and a noise report in the file a "
                                   "consumer loads.",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog=consumers_help() + "\n\n" + EXPORT_HELP)
    e.add_argument("calibration", type=Path, help="calibration JSON of accelcal calibrate")
    e.add_argument("--to", choices=list(CONSUMERS), metavar="TARGET", help=f"the consumer: {', '.join(CONSUMERS)}")
    e.add_argument("--out", type=Path, metavar="PATH", help="the file to write (IMU-TK: the prefix of its two files)")
    e.add_argument("--noise", type=Path, metavar="JSON", help="noise report of accelcal noise (noise densities, random "
                                                              "walks)")
    e.add_argument("--imutk", metavar="PREFIX", help=argparse.SUPPRESS)
    e.add_argument("--imucal", type=Path, metavar="FILE", help=argparse.SUPPRESS)
    e.add_argument("--exact", action="store_true", help="refuse an export whose consumer cannot hold every term")
    e.add_argument("--strict", action="store_true", help="refuse (exit 3) a calibration whose fit is untrustworthy")
    o = e.add_argument_group("consumer options")
    o.add_argument("--rostopic", default="/imu0", help="Kalibr, OpenVINS: the IMU topic (default /imu0)")
    o.add_argument("--inflate", type=_positive, default=1.0, metavar="F",
                   help="multiply the exported noise densities and random walks by F (OpenVINS advises 10-20)")
    o.add_argument("--model", choices=("kalibr", "rpng"), default="kalibr", help="OpenVINS's intrinsic model")
    o.add_argument("--instance", type=int, default=0, metavar="N", help="PX4, ArduPilot: the sensor slot (default 0)")
    o.add_argument("--device-id", type=int, metavar="ID", help="PX4: CAL_ACCn_ID (default: from the ULog calibrated)")
    o.add_argument("--corr-time", type=_positive, default=1.0, metavar="H",
                   help="KF-GINS: the bias correlation time in hours (default 1)")
    o.add_argument("--acc-range", type=_positive, default=16.0, metavar="G",
                   help="the accelerometer's range in g: a larger offset is refused (default 16)")
    o.add_argument("--gyro-range", type=_positive, default=2000.0, metavar="DPS",
                   help="the gyroscope's range in deg/s: a larger offset is refused (default 2000)")
    e.set_defaults(func=_export)


def _target(args) -> tuple[str, Path]:
    chosen = [(name, path) for name, path in (("imutk", args.imutk), ("imucal", args.imucal)) if path is not None]
    if args.to is not None:
        chosen.append((args.to, args.out))
    if len(chosen) != 1:
        raise AccelcalError("name one target: --to TARGET --out PATH (or --imutk PREFIX, --imucal FILE)")
    name, path = chosen[0]
    if path is None:
        raise AccelcalError(f"--to {name} needs --out PATH (the file to write)")
    return name, Path(path)


def _export(args) -> int:
    from ..calibration import load_calibration
    from ..export.api import ExportInputs, export, output_paths, trust_problems, write_files

    name, path = _target(args)
    cal = load_calibration(args.calibration)
    if args.strict and trust_problems(cal):
        problems = trust_problems(cal)
        return fail(f"--strict: {args.calibration} is untrustworthy ({problems[0]}"
                    + (f"; {len(problems) - 1} more" if len(problems) > 1 else "") + "): nothing written", code=3)
    noise = _noise(args.noise) if args.noise is not None else None
    options = {"source": args.calibration.name, "rostopic": args.rostopic, "inflate": args.inflate,
               "model": args.model, "instance": args.instance, "device_id": args.device_id,
               "corr_time_h": args.corr_time, "acc_range_g": args.acc_range, "gyro_range_dps": args.gyro_range}
    result = export(name, ExportInputs(cal, noise, options), exact=args.exact)
    files = output_paths(name, path, result)
    write_files(files)
    parts = [cal.CAL_TYPE, f"gyroscope {cal.gyro.CAL_TYPE}" if cal.gyro is not None else "no gyroscope"]
    if noise is not None:
        parts.append(f"noise {args.noise.name}")
    lines = [f"export: {args.calibration} ({', '.join(parts)}) for {name}: {', '.join(str(p) for p in files)}"]
    lines += [f"  {x.line()}" for x in result.left_out]
    lines += [f"  note: {n}" for n in result.notes]
    print("\n".join(lines), file=sys.stderr)
    for p in trust_problems(cal):
        warn(f"the calibration is untrustworthy: {p} (--strict refuses it)")
    return 0


def _noise(path: Path) -> dict:
    if not path.is_file():
        raise AccelcalError(f"{path}: no such noise report (accelcal noise RECORDING --out {path.name})")
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise AccelcalError(f"{path}: not a noise report (invalid JSON); write one with accelcal noise") from None
    if not isinstance(d, dict) or d.get("format") != "accelcal-noise":
        raise AccelcalError(f"{path}: not a noise report of accelcal noise (its 'format' is not accelcal-noise)")
    return d


__all__ = ["add_parser"]
