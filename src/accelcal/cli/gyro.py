"""The gyroscope in ``accelcal calibrate``: its options and its step after the accelerometer.

Whenever the recording has a gyro (its own columns, or ``--gyro FILE``) and ``--no-gyro``
is not given, the gyro is calibrated from the same session: from the motions between the
accelerometer's rests (:func:`accelcal.gyro.calibrate.calibrate_gyro`, the estimator of
``--gyro-method``), or, when the file marks rotations of known angle (imucal's ``*_rot``
sections), from those (:func:`accelcal.gyro.ferraris.calibrate_ferraris_session`,
``--rotation-angle``).  Every refusal is one line naming the cause and the option (the
typed errors of :mod:`accelcal.gyro.errors`); nothing is written then.
"""

from __future__ import annotations

import math

from ..errors import AccelcalError
from ..registry import estimators


def add_gyro_options(c) -> None:
    """The calibrate subcommand's gyro options (reading the gyro: :func:`.common._reader_options`)."""
    names = [e.cli_name for e in estimators("gyroscope")]
    g = c.add_argument_group("gyroscope (calibrated whenever the recording has a gyro: its own columns or --gyro FILE)")
    g.add_argument("--gyro-method", choices=names, default=None,
                   help="gyro estimator (default: by the data: gyro-ferraris where the file marks rotations of known "
                        "angle, else gyro-iterative from the motions between rests; an estimator of other data is "
                        "refused)")
    g.add_argument("--gyro-sensitivity", metavar="S[/dps|/rad/s]",
                   help="nominal sensitivity of raw gyro counts, counts per deg/s (default) or per rad/s: the start "
                        "and the reference of the scale factors (without it, a scalar search)")
    g.add_argument("--gyro-range", metavar="LO,HI", help="the gyro's measuring range in its raw unit (saturation)")
    g.add_argument("--gyro-g-sensitivity", choices=("auto", "on", "off"), default="auto",
                   help="fit a bias proportional to the specific force: auto (when the rest means show one, F test), "
                        "on, off (IMU-TK's model has none; default auto)")
    g.add_argument("--rotation-angle", metavar="DEG[,DEG,DEG]",
                   help="rotations of known angle: the angle of each, one for all or one per axis x,y,z (or one per "
                        "rotation in time order). Ferraris sessions (rotations marked *_rot): default 360; a gyro "
                        "without accelerometer (its rotations found in it, each run with its own bias): required")
    g.add_argument("--rotation-angle-std", type=float, default=0.0, metavar="DEG",
                   help="uncertainty of each stated angle [deg] (default 0), carried into the standard errors")


def _numbers(text: str, what: str, count: tuple[int, ...]) -> list[float]:
    try:
        v = [float(x) for x in str(text).split(",")]
    except ValueError:
        v = []
    if len(v) not in count or not all(math.isfinite(x) for x in v):
        raise AccelcalError(f"{what} must be {' or '.join(map(str, count))} number(s) separated by commas, "
                            f"got {text!r}")
    return v


def nominal_sensitivity(text: str | None) -> float | None:
    """``--gyro-sensitivity`` as raw counts per rad/s (None if not given)."""
    if text is None:
        return None
    value, per = (text.split("/", 1) + ["dps"])[:2]
    per = per.strip().lower().replace(" ", "")
    factors = {"dps": 180.0 / math.pi, "deg/s": 180.0 / math.pi, "rad/s": 1.0, "rads": 1.0}
    if per not in factors:
        raise AccelcalError(f"--gyro-sensitivity: counts per deg/s (dps) or per rad/s, got per {per!r}")
    s = _numbers(value, "--gyro-sensitivity", (1,))[0]
    if not s > 0:
        raise AccelcalError("--gyro-sensitivity must be positive")
    return s * factors[per]


def note_gyro(args, rec) -> str:
    """The ``read:`` line on the gyro (what was found, or why it is not calibrated)."""
    if rec.gyro is None:
        return "no gyro columns: the accelerometer alone (a gyro in a file of its own: --gyro FILE)"
    if args.no_gyro:
        return "gyro columns ignored (--no-gyro): the accelerometer alone"
    return ""


def wants_gyro(args, rec) -> bool:
    return rec.gyro is not None and not args.no_gyro


def calibrate(args, rec, cal, poses):
    """The gyro of ``rec``, calibrated with the accelerometer calibration ``cal`` on its ``poses``."""
    from ..gyro.recording import calibrate_recording_gyro

    rng = None if args.gyro_range is None else _numbers(args.gyro_range, "--gyro-range", (2,))
    if rng is not None and not rng[0] < rng[1]:
        raise AccelcalError(f"--gyro-range must be LO,HI with LO < HI, got {args.gyro_range!r}")
    angles = _angles(args)
    if angles is not None and rec.rotations and len(angles) not in (1, 3):
        raise AccelcalError(f"--rotation-angle must be 1 or 3 number(s) separated by commas, got {args.rotation_angle!r}")
    return calibrate_recording_gyro(rec, cal, poses, estimator=args.gyro_method,
                                    nominal_sensitivity=nominal_sensitivity(args.gyro_sensitivity), gyro_range=rng,
                                    g_sensitivity={"auto": "auto", "on": True, "off": False}[args.gyro_g_sensitivity],
                                    rotation_angles=angles, angle_std_deg=args.rotation_angle_std)


def _angles(args):
    if args.rotation_angle is None:
        return None
    angles = _numbers(args.rotation_angle, "--rotation-angle", tuple(range(1, 100)))
    if not all(0 < a <= 3600 for a in angles):
        raise AccelcalError(f"--rotation-angle: angles in degrees, positive, got {args.rotation_angle!r}")
    if not (math.isfinite(args.rotation_angle_std) and args.rotation_angle_std >= 0):
        raise AccelcalError(f"--rotation-angle-std must be >= 0 degrees, got {args.rotation_angle_std}")
    return angles


def calibrate_gyro_only(args, rec):
    """The gyro of a recording without accelerometer, from the rotations of known angle found in it
    (:func:`accelcal.gyro.rotations.calibrate_rotations`: each run with its own bias)."""
    from ..gyro.rotations import calibrate_rotations

    if args.no_gyro:
        raise AccelcalError(f"{args.recording}: --no-gyro, but the recording has no accelerometer: nothing to "
                            "calibrate")
    angles = _angles(args)
    if angles is None:
        raise AccelcalError(f"{args.recording}: a gyro without accelerometer is calibrated from rotations of known "
                            "angle: give their angles with --rotation-angle DEG[,DEG,DEG] (one per axis x, y, z)")
    # a section list (--intervals) gives the rotations' windows (*_rot) and the rests; else they are found
    windows = None if not rec.rotations else sorted(rec.rotations.values())
    return calibrate_rotations(rec.t, rec.gyro, angles_deg=angles, runs=rec.runs, raw_unit=rec.gyro_unit or "rad/s",
                               nominal_sensitivity=nominal_sensitivity(args.gyro_sensitivity),
                               angle_std_deg=args.rotation_angle_std, source=str(args.recording), windows=windows,
                               rest_intervals=rec.intervals)


def search_line(cal) -> str | None:
    """The line saying which detection settings the search chose, if it ran."""
    s = (cal.provenance.get("static") or {}).get("search")
    if not s:
        return None
    return (f"  static: the default detection found {s['defaults_found']} poses; {s['description']} "
            "(the most precise full-model fit; --threshold, --window, --min-duration to choose yourself)")


__all__ = ["add_gyro_options", "calibrate", "calibrate_gyro_only", "nominal_sensitivity", "note_gyro", "search_line",
           "wants_gyro"]
