"""The ADIS16405 record (2.78 h, 100 Hz, static) through the noise analysis, against its datasheet.

Reads ``shared/data/smac_adis16405/adis_16405_imu1.rda`` with the ``rdata`` package (the
``workflow`` extra), as :mod:`accelcal_repro.measured.smac` does, but keeps the gyroscope
too: columns ``Gyro. X/Y/Z`` [deg/s] → rad/s and ``Accel. X/Y/Z`` [g] → m/s² (× 9.80665).
Runs :func:`accelcal.noise.report.analyse_noise` and writes to ``--out-dir``: the JSON
report, Kalibr's and OpenVINS's YAML, the figure, and ``datasheet.csv``, the fitted
terms against the datasheet's typical values with their ratio:

* accelerometer velocity random walk 0.2 m/s/√h (N = 0.2/60 m/s²/√Hz);
* accelerometer in-run bias stability 0.2 mg (1σ);
* gyroscope angle random walk 2 °/√h (N = 2/60 °/s/√Hz);
* gyroscope in-run bias stability 0.007 °/s (1σ).

"In-run bias stability" is compared two ways: with the minimum of the measured Allan
deviation (how Analog Devices characterises it) and with the flicker floor of the fit,
0.664 B (IEEE Std 952).

Usage::

    .venv/bin/python tools/adis_noise.py [--rda PATH] [--out-dir results/noise/adis16405]
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RDA = ROOT / ".." / "shared" / "data" / "smac_adis16405" / "adis_16405_imu1.rda"
G0 = 9.80665
FS = 100.0
#: (sensor, quantity, datasheet value, unit, how the fit gives it)
DATASHEET = (
    ("accelerometer", "velocity random walk", 0.2 / 60.0, "m/s^2/sqrt(Hz)", "white N"),
    ("accelerometer", "in-run bias stability", 0.2e-3 * G0, "m/s^2", "ADEV minimum"),
    ("accelerometer", "in-run bias stability", 0.2e-3 * G0, "m/s^2", "flicker floor 0.664 B"),
    ("gyroscope", "angle random walk", math.radians(2.0 / 60.0), "rad/s/sqrt(Hz)", "white N"),
    ("gyroscope", "in-run bias stability", math.radians(0.007), "rad/s", "ADEV minimum"),
    ("gyroscope", "in-run bias stability", math.radians(0.007), "rad/s", "flicker floor 0.664 B"),
)


def read_adis(path: Path):
    """The record as a Recording: accelerometer [m/s²] and gyroscope [rad/s], t = i / 100 Hz."""
    import rdata

    from accelcal.recording import Recording

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        objs = rdata.conversion.convert(rdata.parser.parse_file(path))
    (name, obj), = objs.items()
    cols = [str(c) for c in obj.coords[obj.dims[1]].values]
    x = np.asarray(obj, dtype=float)
    acc = x[:, [cols.index(f"Accel. {a}") for a in "XYZ"]] * G0
    gyro = np.radians(x[:, [cols.index(f"Gyro. {a}") for a in "XYZ"]])
    notes = ("SMAC-Group imudata adis_16405_imu1: Accel. X/Y/Z in g (x 9.80665), Gyro. X/Y/Z in deg/s (to rad/s), "
             "t = i / 100 Hz",)
    return Recording(np.arange(len(x)) / FS, acc, None, f"{path.name}:{name}", notes=notes, unit="m/s^2",
                     gyro=gyro, gyro_unit="rad/s")


def datasheet_rows(report) -> list[dict]:
    rows = []
    for sensor, quantity, value, unit, how in DATASHEET:
        s = report.sensors[sensor]
        for j, ax in enumerate("xyz"):
            t = s.terms[j]
            if how == "white N":
                fit, lo, hi = t["white"].value, t["white"].lo, t["white"].hi
            elif how == "ADEV minimum":
                i = int(np.argmin(s.allan.adev[:, j]))
                fit, (lo, hi) = float(s.allan.adev[i, j]), s.adev_interval[i, j]
            else:
                b = t["bias_instability"]
                fit, lo, hi = 0.664 * b.value, 0.664 * b.lo, 0.664 * b.hi
            rows.append({"sensor": sensor, "quantity": quantity, "from": how, "axis": ax, "fitted": fit,
                         "interval_lo": float(lo), "interval_hi": float(hi), "datasheet": value, "unit": unit,
                         "ratio": fit / value})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rda", type=Path, default=RDA)
    ap.add_argument("--out-dir", type=Path, default=ROOT / "results" / "noise" / "adis16405")
    args = ap.parse_args(argv)
    from accelcal.atomic import atomic_output, write_json_atomic
    from accelcal.noise.export import kalibr_yaml, openvins_yaml
    from accelcal.noise.figures import noise_figure
    from accelcal.noise.report import analyse_noise
    from accelcal.plotting import save_figure

    report = analyse_noise(read_adis(args.rda))
    out = args.out_dir
    write_json_atomic(out / "noise.json", report.to_dict())
    for name, text in (("imu.yaml", kalibr_yaml(report)), ("kalibr_imu_chain.yaml", openvins_yaml(report)[0])):
        with atomic_output(out / name) as tmp:
            Path(tmp).write_text(text)
    save_figure(noise_figure(report, title="ADIS16405 (SMAC imudata), 2.78 h static at 100 Hz"), out / "noise")
    rows = datasheet_rows(report)
    with atomic_output(out / "datasheet.csv") as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"{'sensor':<14}{'quantity':<24}{'from':<22}{'axis':<5}{'fitted':>11} {'95 % interval':<23}"
          f"{'datasheet':>10}  ratio")
    for r in rows:
        print(f"{r['sensor']:<14}{r['quantity']:<24}{r['from']:<22}{r['axis']:<5}{r['fitted']:>11.3g} "
              f"[{r['interval_lo']:.3g}, {r['interval_hi']:.3g}]".ljust(23 + 76) + f"{r['datasheet']:>10.3g}  "
              f"{r['ratio']:.2f}")
    for w_ in report.warnings:
        print(f"warning: {w_}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
