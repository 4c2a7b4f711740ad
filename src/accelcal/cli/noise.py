"""``accelcal noise``: noise densities and random walks of a static recording, for Kalibr and OpenVINS."""

from __future__ import annotations

import argparse
import re
import sys
import time
from dataclasses import replace
from pathlib import Path

from .. import kernels
from ..atomic import atomic_output, write_json_atomic
from ..errors import AccelcalError
from .common import _positive, _provenance, _read, _reader_options, _step, warn

NOISE_HELP = """\
RECORDING: a static recording, the sensor at rest in one orientation for its whole
length (hours resolve the bias terms): a ROS 1/2 bag or MCAP file (sensor_msgs/Imu:
accelerometer and gyroscope), a PX4 ULog, an ArduPilot DataFlash log, or a table
(accelerometer only), read with the readers and options of calibrate. Outputs (JSON, YAML, figure) are written only on success.
The exported values are continuous-time, the worst axis, with every axis and the
interval in a comment: noise density N [m/s^2/sqrt(Hz), rad/s/sqrt(Hz)] and random
walk K [m/s^3/sqrt(Hz), rad/s^2/sqrt(Hz)] of the IEEE fit of the Allan deviation.
Part of a recording: --start/--end (seconds from its first sample) analyse one static
stretch; --intervals FILE (or the rests a file marks itself) pools the rests, each
static on its own, the orientation free to change between them.
The summary quotes the data-sheet units (angle random walk deg/sqrt(h), velocity
random walk m/s/sqrt(h), bias instability deg/h and mg, from the flicker floor
0.664 B), how long a record would give each term +-WIDTH (--plan-width), and where
allan_variance_ros would read a value more than 2x apart, why.
"""


def add_parser(sub, epilog: str) -> None:
    """The ``noise`` subcommand."""
    n = sub.add_parser("noise", help="noise densities and random walks of a static recording (Kalibr, OpenVINS)",
                       description="Allan deviation and IEEE noise terms (quantization, white noise, bias "
                                   "instability, random walk, ramp) of a static recording, with intervals; exports "
                                   "for Kalibr and OpenVINS.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=NOISE_HELP)
    n.add_argument("recording", type=Path, help="the static recording (log or table)")
    n.add_argument("--out", type=Path, required=True, help="noise report JSON")
    n.add_argument("--kalibr", type=Path, metavar="YAML", help="also write Kalibr's imu.yaml")
    n.add_argument("--openvins", type=Path, metavar="YAML", help="also write OpenVINS's kalibr_imu_chain.yaml")
    n.add_argument("--calibration", type=Path, metavar="JSON",
                   help="accelcal calibration whose intrinsics (accelerometer and gyroscope) go into the Kalibr and "
                        "OpenVINS files (default: none; OpenVINS's are then the identity)")
    n.add_argument("--inflate", type=_positive, default=1.0, metavar="F",
                   help="multiply the exported densities and random walks by F (OpenVINS advises 10-20)")
    n.add_argument("--figure", type=Path, metavar="PNG", help="also draw the Allan deviations (.png and .pdf)")
    n.add_argument("--level", type=float, default=0.95, help="confidence level of the intervals (default 0.95)")
    n.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    n.add_argument("--start", type=float, metavar="S", help="analyse from S seconds after the first sample")
    n.add_argument("--end", type=float, metavar="S", help="analyse up to S seconds after the first sample")
    n.add_argument("--plan-width", type=_positive, default=0.25, metavar="W",
                   help="the record-length planner's relative interval half-width (default 0.25: +-25 %%)")
    _reader_options(n)
    n.set_defaults(func=_noise)


def _noise(args) -> int:
    from ..noise.report import analyse_noise

    t0 = time.perf_counter()
    if not args.recording.exists():
        raise AccelcalError(f"{args.recording}: no such file or folder")
    if not 0 < args.level < 1:
        raise AccelcalError(f"--level must be between 0 and 1, got {args.level}")
    if args.intervals is not None and (args.start is not None or args.end is not None):
        raise AccelcalError("--intervals chooses the rests already; give either --intervals or --start/--end")
    # The analysis's compiled kernels (numba, if installed) loaded before the reading: a large
    # table is then read by the compiled parser instead of pandas (accelcal.formats.numeric_block;
    # 10^6 rows: 0.45 s and ~40 MB less), numba's start-up being paid once either way.
    kernels.compiled("noise._fast")
    rec = _read(args, accelerometer=False, time_column=False)  # no time column is written back
    if args.no_gyro and rec.gyro is not None:  # the table's own gyro columns too, not only --gyro FILE

        rec = replace(rec, gyro=None, gyro_unit=None, notes=rec.notes + ("gyro columns ignored (--no-gyro)",))
    segments = _segments(args, rec)
    cal = None
    if args.calibration is not None:
        from ..calibration import load_calibration

        cal = load_calibration(args.calibration)
    with _step("Allan deviations and the noise fit"):
        report = analyse_noise(rec, level=args.level, seed=args.seed, segments=segments)
    texts, warnings = _noise_exports(args, rec, report, cal)
    figure = None
    if args.figure is not None:
        from ..noise.figures import noise_figure

        with _step("drawing the figure"):
            figure = noise_figure(report, title=f"{args.recording.name}: {report.duration_s / 3600:.3g} h at "
                                                f"{report.fs:.4g} Hz")
    _noise_write(args, report, texts, figure, t0)
    _noise_summary(args, report, warnings, _avr_readings(rec, report, segments))
    return 0


def _segments(args, rec):
    """The sample ranges to analyse: --start/--end, the recording's rests (--intervals or its own), or None."""
    import numpy as np

    if args.start is None and args.end is None:
        return None if rec.intervals is None else [tuple(int(v) for v in row) for row in rec.intervals]
    t = rec.t - rec.t[0]
    start = 0.0 if args.start is None else args.start
    end = float(t[-1]) if args.end is None else args.end
    if not (np.isfinite(start) and np.isfinite(end) and 0 <= start < end):
        raise AccelcalError(f"--start {start:g} / --end {end:g}: need 0 <= start < end (seconds from the first sample)")
    if start >= t[-1]:
        raise AccelcalError(f"--start {start:g} s is beyond the recording's end ({t[-1]:.4g} s)")
    a, b = int(np.searchsorted(t, start)), int(np.searchsorted(t, end, side="right"))
    if b - a < 4:
        raise AccelcalError(f"--start {start:g} / --end {end:g} holds {b - a} samples; give a longer stretch")
    return [(a, b)]


def _avr_readings(rec, report, segments) -> dict:
    """allan_variance_ros's reading of each sensor, on the one continuous stretch analysed (not on pooled rests)."""
    from ..noise.avr import avr_reading

    if segments is not None and len(segments) > 1:
        return {}
    a, b = segments[0] if segments else (0, rec.n)
    data = {"accelerometer": rec.acc, "gyroscope": rec.gyro}
    return {name: avr_reading(data[name][a:b], report.fs) for name in report.sensors if data[name] is not None}


def _noise_exports(args, rec, report, cal) -> tuple[dict, list]:
    from ..noise.export import calibrated_kalibr_yaml, kalibr_yaml, openvins_yaml

    found = next((m.group(1) for n in rec.notes if (m := re.search(r"topic (/\S+) \(sensor_msgs/Imu", n))), None)
    topic = args.topic or found or "/imu0"
    texts, warnings = {}, []
    if args.kalibr is not None:
        if cal is None:
            texts[args.kalibr] = kalibr_yaml(report, rostopic=topic, inflate=args.inflate)
        else:
            texts[args.kalibr], w = calibrated_kalibr_yaml(report, cal, rostopic=topic, inflate=args.inflate)
            warnings += w
    if args.openvins is not None:
        texts[args.openvins], w = openvins_yaml(report, rostopic=topic, inflate=args.inflate, calibration=cal)
        warnings += [x for x in w if x not in warnings]
    elif cal is not None and args.kalibr is None:
        warnings.append("--calibration is used by --kalibr and --openvins only; nothing was exported from it")
    if texts and found is None:
        warnings.append(f"rostopic in the YAML is {topic} (the recording is not a ROS log): set it to your topic")
    return texts, warnings


def _noise_write(args, report, texts: dict, figure, t0: float) -> None:
    out = report.to_dict()
    out["provenance"] = _provenance(args, t0)
    write_json_atomic(args.out, out)
    for path, text in texts.items():
        with atomic_output(path) as tmp:
            Path(tmp).write_text(text)
    if figure is not None:
        from ..plotting import save_figure

        save_figure(figure, args.figure)


def _noise_summary(args, report, warnings: list, avr: dict) -> None:
    written = ", ".join(str(p) for p in (args.out, args.kalibr, args.openvins, args.figure) if p is not None)
    print(report.summary(written_to=written, plan_width=args.plan_width, allan_variance_ros=avr), file=sys.stderr)
    for w in (*report.warnings, *warnings):
        warn(w)
