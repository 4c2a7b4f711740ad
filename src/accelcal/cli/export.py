"""``accelcal export``: a calibration in IMU-TK's ``.calib`` layout or imucal's JSON."""

from __future__ import annotations

import argparse
import sys
from contextlib import ExitStack
from pathlib import Path

from .common import warn

EXPORT_HELP = """\
IMU-TK (--imutk PREFIX): PREFIX_acc.calib and, with a gyroscope, PREFIX_gyro.calib, in
IMU-TK's layout (misalignment T, scale K, bias b; x = T K (raw - b)), the accelerometer
in the raw unit it was calibrated from. IMU-TK's gyro model has no g-sensitivity: a
calibration with one is refused. imucal (--imucal FILE): a FerrarisCalibrationInfo JSON
(imucal's from_json reads it), which needs the gyroscope. Fitted effects (temperature,
drift...) are in neither model: they are left out, with a warning.
"""


def add_parser(sub, epilog: str) -> None:
    """The ``export`` subcommand."""
    e = sub.add_parser("export", help="write a calibration in IMU-TK's .calib layout or imucal's JSON",
                       description="Write CALIBRATION (accelcal calibrate's JSON) in another tool's format.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EXPORT_HELP)
    e.add_argument("calibration", type=Path, help="calibration JSON of accelcal calibrate")
    to = e.add_mutually_exclusive_group(required=True)
    to.add_argument("--imutk", metavar="PREFIX", help="write PREFIX_acc.calib and PREFIX_gyro.calib (IMU-TK)")
    to.add_argument("--imucal", type=Path, metavar="FILE", help="write imucal's calibration JSON")
    e.set_defaults(func=_export)


def _export(args) -> int:
    from ..atomic import atomic_output
    from ..calibration import load_calibration
    from ..gyro.export import calibration_imucal, calibration_imutk, unexported_effects

    cal = load_calibration(args.calibration)
    left_out = unexported_effects(cal)
    if args.imutk is not None:
        texts = calibration_imutk(cal)
        paths = {k: Path(f"{args.imutk}_{k}.calib") for k in texts}
        with ExitStack() as stack:  # both files renamed into place only once both are written
            for k, path in paths.items():
                Path(stack.enter_context(atomic_output(path))).write_text(texts[k])
        written = " and ".join(str(p) for p in paths.values())
    else:
        text = calibration_imucal(cal, comment=f"exported by accelcal from {args.calibration.name}")
        with atomic_output(args.imucal) as tmp:
            Path(tmp).write_text(text)
        written = str(args.imucal)
    print(f"export: {args.calibration} ({cal.CAL_TYPE}" + (f", gyroscope {cal.gyro.CAL_TYPE}" if cal.gyro else
                                                           ", no gyroscope") + f") written to {written}",
          file=sys.stderr)
    if left_out:
        warn(f"the fitted effects {', '.join(left_out)} are not in the exported model (neither IMU-TK's nor imucal's "
             "has them)")
    return 0
