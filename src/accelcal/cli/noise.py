"""``accelcal noise``: noise densities and random walks of a static recording, for Kalibr and OpenVINS."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

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
                   help="accelcal calibration whose M becomes OpenVINS's Ta (default: identity)")
    n.add_argument("--inflate", type=_positive, default=1.0, metavar="F",
                   help="multiply the exported densities and random walks by F (OpenVINS advises 10-20)")
    n.add_argument("--figure", type=Path, metavar="PNG", help="also draw the Allan deviations (.png and .pdf)")
    n.add_argument("--level", type=float, default=0.95, help="confidence level of the intervals (default 0.95)")
    n.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    _reader_options(n)
    n.set_defaults(func=_noise)


def _noise(args) -> int:
    from ..noise.report import analyse_noise

    t0 = time.perf_counter()
    if not args.recording.exists():
        raise AccelcalError(f"{args.recording}: no such file or folder")
    if not 0 < args.level < 1:
        raise AccelcalError(f"--level must be between 0 and 1, got {args.level}")
    if args.intervals is not None:
        raise AccelcalError("--intervals: the noise analysis takes the whole recording as one rest; cut the static "
                            "part out instead")
    rec = _read(args, accelerometer=False)
    cal = None
    if args.calibration is not None:
        from ..calibration import load_calibration

        cal = load_calibration(args.calibration)
    with _step("Allan deviations and the noise fit"):
        report = analyse_noise(rec, level=args.level, seed=args.seed)
    texts, warnings = _noise_exports(args, rec, report, cal)
    figure = None
    if args.figure is not None:
        from ..noise.figures import noise_figure

        with _step("drawing the figure"):
            figure = noise_figure(report, title=f"{args.recording.name}: {report.duration_s / 3600:.3g} h at "
                                                f"{report.fs:.4g} Hz")
    _noise_write(args, report, texts, figure, t0)
    _noise_summary(args, report, warnings)
    return 0


def _noise_exports(args, rec, report, cal) -> tuple[dict, list]:
    import re

    from ..noise.export import kalibr_yaml, openvins_yaml

    found = next((m.group(1) for n in rec.notes if (m := re.search(r"topic (/\S+) \(sensor_msgs/Imu", n))), None)
    topic = args.topic or found or "/imu0"
    texts, warnings = {}, []
    if args.kalibr is not None:
        texts[args.kalibr] = kalibr_yaml(report, rostopic=topic, inflate=args.inflate)
    if args.openvins is not None:
        texts[args.openvins], warnings = openvins_yaml(report, rostopic=topic, inflate=args.inflate, calibration=cal)
    elif cal is not None:
        warnings.append("--calibration is used by --openvins only; nothing was exported from it")
    if texts and found is None:
        warnings.append(f"rostopic in the YAML is {topic} (the recording is not a ROS log): set it to your topic")
    return texts, warnings


def _noise_write(args, report, texts: dict, figure, t0: float) -> None:
    from ..atomic import atomic_output, write_json_atomic

    out = report.to_dict()
    out["provenance"] = _provenance(args, t0)
    write_json_atomic(args.out, out)
    for path, text in texts.items():
        with atomic_output(path) as tmp:
            Path(tmp).write_text(text)
    if figure is not None:
        from ..plotting import save_figure

        save_figure(figure, args.figure)


def _noise_summary(args, report, warnings: list) -> None:
    from ..noise.export import exported_values

    lines = [f"noise: {report.n} samples, {report.duration_s / 3600:.3g} h at {report.fs:.4g} Hz"]
    lines += [f"  read: {n}" for n in report.notes if n]
    for s in report.sensors.values():
        ex = [exported_values(s, j) for j in range(3)]
        lines.append(f"  {s.sensor}: noise density " + ", ".join(f"{e['noise_density']['value']:.3g}" for e in ex)
                     + f" {s.unit}/sqrt(Hz); random walk " + ", ".join(
                         f"{'<' if e['random_walk']['upper_bound'] else ''}{e['random_walk']['value']:.3g}" for e in ex)
                     + f" {ex[0]['random_walk']['unit']} (x, y, z)")
    lines.append(f"  written to {args.out}" + "".join(f", {p}" for p in (args.kalibr, args.openvins, args.figure)
                                                         if p is not None))
    print("\n".join(lines), file=sys.stderr)
    for w in (*report.warnings, *warnings):
        warn(w)
