"""``accelcal calibrate``: estimate the errors from a recording's static poses and say whether to trust them."""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from ..atomic import write_json_atomic
from ..errors import AccelcalError, RecordingError, TooFewPosesError
from ..registry import estimators, min_gyro_rests
from . import gyro, mag
from .common import (STANDARD_GRAVITY, _gravity, _nominal, _provenance, _rate_hint, _read, _reader_options,
                     _search_static, _static_options, _static_settings, _step, fail)


def add_parser(sub, epilog: str) -> None:
    """The ``calibrate`` subcommand."""
    c = sub.add_parser("calibrate", help="estimate bias, scale factors and non-orthogonality from a recording",
                       description="Find the static poses of RECORDING, estimate the accelerometer errors and say "
                                   "whether the fit can be trusted (residuals against the noise measured at the rests).",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog)
    c.add_argument("recording", type=Path, help="the recording (see 'input' below)")
    c.add_argument("--g", type=_gravity, default=None,
                   help=f"local gravity magnitude [m/s^2] (default {STANDARD_GRAVITY}, standard gravity)")
    c.add_argument("--method", choices=[e.cli_name for e in estimators("accelerometer")], default="full-lls",
                   help="estimator (default full-lls)")
    c.add_argument("--out", type=Path, required=True, help="calibration JSON (written only on success)")
    c.add_argument("--figures", type=Path, default=None, metavar="DIR",
                   help="also draw calibration_coverage (.png, .pdf): the pose directions on the sphere")
    _reader_options(c)
    n = c.add_argument_group("raw counts to m/s^2 before the fit (the bias-only models need it)")
    n.add_argument("--sensitivity", metavar="S[,S,S][/g|/m/s2]",
                   help="the data sheet's sensitivity, counts per g (default) or per m/s2; then M is the gain "
                        "relative to it and b is in m/s^2")
    n.add_argument("--zero", metavar="C[,C,C]", help="the output at zero specific force [counts] (default 0)")
    _static_options(c)
    gyro.add_gyro_options(c)
    c.add_argument("--strict", action="store_true",
                   help="exit 3 when the fit is untrustworthy (its quality warnings; the file is still written), so "
                        "that a script can tell")
    mag.add_mag_options(c)
    c.set_defaults(func=_calibrate)


def _calibrate(args) -> int:
    from ..calibration.summary import STANDARD_GRAVITY_SOURCE

    t0 = time.perf_counter()
    rec = _read(args, accelerometer=False)
    if rec.acc is None:
        return _calibrate_gyro_only(args, rec, t0)
    rec = replace(rec, notes=rec.notes + (gyro.note_gyro(args, rec), mag.note_mag(args, rec)))
    mag.field_from_args(args)  # a bad --location or --date is refused before any work
    cal, poses = _calibrate_accelerometer(args, rec)
    if gyro.wants_gyro(args, rec):
        with _step("calibrating the gyroscope"):
            cal = replace(cal, gyro=gyro.calibrate(args, rec, cal, poses))
    if mag.wants_mag(args, rec):
        with _step("calibrating the magnetometer"):
            cal = replace(cal, mag=mag.calibrate(args, rec, cal, poses))
    prov = {**_provenance(args, t0), "g_source": "--g" if args.g is not None else STANDARD_GRAVITY_SOURCE}
    if rec.device_id is not None:  # apply warns when the calibration reaches another unit
        prov["device_id"] = rec.device_id
    cal = _with_provenance(cal, prov)
    _write_and_report(cal, poses, rec, args)
    return _strict_status(cal, args)


def _calibrate_accelerometer(args, rec):
    """The static poses and the accelerometer's calibration; a refusal says what the reader
    guessed or read that may be its cause."""
    from ..calibration import calibrate_recording

    g = STANDARD_GRAVITY if args.g is None else args.g
    static = _static_settings(args, rec)
    method = args.method
    # the defaults first; too few poses for the method (or the gyro's rests): the candidates' best
    search = _search_static(args)
    with _step(f"detecting static poses and estimating {method} from {rec.n} samples"):
        try:
            return calibrate_recording(rec, g, method, static=static, conversion=_nominal(args, rec), search=search,
                                       min_poses=min_gyro_rests() if gyro.wants_gyro(args, rec) else 0)
        except RecordingError as e:
            hint = " (the magnetometer without rests: accelcal mag RECORDING)" if mag.wants_mag(args, rec) else ""
            raise RecordingError(f"{e}{_rate_hint(rec)}{hint}{_source_hint(rec)}") from None
        except TooFewPosesError as e:  # unnamed columns taken for ax, ay, az may be another sensor's
            guess = next((n for n in rec.notes if n.startswith("no header: columns read as")), None)
            if guess is not None:
                raise TooFewPosesError(f"{e} [{guess.split(' (')[0]}: if they are a gyro's, pass --columns "
                                       "gx=..,gy=..,gz=..]") from None
            if not rec.precalibrated:
                raise
            raise type(e)(f"{e}{_source_hint(rec)}") from None
        except AccelcalError as e:
            if not rec.precalibrated:
                raise
            raise type(e)(f"{e}{_source_hint(rec)}") from None


def _write_and_report(cal, poses, rec, args) -> None:
    """The figures drawn (before anything is written: a failure leaves no file), the
    calibration and the figures written, the summaries printed."""
    figures = []
    if args.figures is not None:
        from ..calibration_figures import coverage_figure

        with _step("drawing figures"):
            figures = [("calibration_coverage", coverage_figure(cal, title=args.recording.name))]
    cal.save(args.out)
    if figures:
        from ..plotting import save_figure

        for name, fig in figures:
            save_figure(fig, Path(args.figures) / name)
    if gyro.search_line(cal):
        print(gyro.search_line(cal), file=sys.stderr)
    _summary(cal, poses, rec, args)
    if cal.gyro is not None:
        print(cal.gyro.summary(), file=sys.stderr)
    if cal.mag is not None:
        print(cal.mag.summary(), file=sys.stderr)


def _strict_status(cal, args) -> int:
    """0, or 3 with --strict when the calibration's fit is untrustworthy (one line saying why)."""
    from ..export.api import trust_problems

    problems = trust_problems(cal) if args.strict else []
    if not problems:
        return 0
    return fail(f"--strict: the calibration is untrustworthy ({problems[0]}" +
                (f"; {len(problems) - 1} more" if len(problems) > 1 else "") + f"); it is written to {args.out}",
                code=3)


def _source_hint(rec) -> str:
    """What the reader read, when it was data someone had calibrated already (a PX4 flight log's sensor_combined)."""
    if not rec.precalibrated:
        return ""
    return (f" [the data were read from {rec.precalibrated}: a flight log, not a calibration session; calibrate from "
            "static poses with the raw sensor_accel logged (PX4's logger profile: sensor comparison or thermal "
            "calibration)]")


def _calibrate_gyro_only(args, rec, t0) -> int:
    """A recording without accelerometer: the gyro from its rotations of known angle, written
    as a calibration file's ``gyroscope`` object (format 2) without the accelerometer's."""
    from ..calibration.base import FORMAT_VERSION
    from ..jsonsafe import json_safe

    if args.figures is not None or args.sensitivity is not None or args.zero is not None:
        raise AccelcalError("--figures, --sensitivity and --zero concern the accelerometer; this recording has none "
                            "(a gyro alone)")
    with _step("finding the rotations and calibrating the gyroscope"):
        cal = gyro.calibrate_gyro_only(args, rec)
    out = {"format_version": FORMAT_VERSION, "sensor": "gyroscope", "accelerometer": None,
           "gyroscope": cal.to_dict(), "notes": list(rec.notes), **_provenance(args, t0)}
    write_json_atomic(args.out, json_safe(out))
    lines = [f"read: {n}" for n in rec.notes if n]
    print("\n".join(lines + [cal.summary(written_to=args.out)]), file=sys.stderr)  # the Summary's own text
    return 0


def _with_provenance(cal, extra: dict):
    return replace(cal, provenance={**cal.provenance, **extra})


def _summary(cal, poses, rec, args) -> None:
    """The calibration's own summary, with the initial rest's length and the output path."""
    rest_s = rec.t[poses.init_rest[1] - 1] - rec.t[0] if poses.reference == "initial_rest" else None
    print(cal.summary(init_rest_s=rest_s, written_to=args.out), file=sys.stderr)
