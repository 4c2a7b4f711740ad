"""Accelerometer and gyro of one IMU-TK-style session (two ASCII files ``t x y z``), end to end.

    .venv/bin/python tools/gyro_calibrate_files.py ACC GYRO --g 9.81744 --unit counts [--out cal.json]

What ``accelcal calibrate --gyro GYRO`` will do once the command line is wired: read both
files, find the static poses (the default settings, or the automatic choice when they find
too few), fit the accelerometer (full LLS) and the gyro (iterative, Magnus-4), print both
summaries and write one JSON.  Used to time accelcal against IMU-TK's ``test_imu_calib``
on the same files, as whole processes.
"""

from __future__ import annotations

import argparse
import json
import sys


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("acc")
    ap.add_argument("gyro")
    ap.add_argument("--g", type=float, required=True, help="local gravity [m/s^2]")
    ap.add_argument("--unit", default="counts", help="unit of both files: counts, or m/s^2 and rad/s")
    ap.add_argument("--out", default=None)
    ap.add_argument("--reader", choices=("accelcal", "numpy"), default="accelcal",
                    help="accelcal's reader (what the command line uses) or numpy.loadtxt (to show the reader's share)")
    ap.add_argument("--times", action="store_true", help="print the CPU seconds of each stage")
    a = ap.parse_args(argv)
    from accelcal.calibration import calibrate_poses
    from accelcal.errors import AccelcalError
    from accelcal.gyro.calibrate import calibrate_gyro
    from accelcal.recording import read_imutk_ascii
    from accelcal.static import detect_static
    from accelcal.static_auto import choose_static

    import time

    import numpy as np

    from accelcal.recording import Recording

    stamps = [("start", time.process_time())]
    try:
        if a.reader == "numpy":
            acc, gyro = (Recording(x[:, 0], x[:, 1:4], None, p) for p, x in
                         ((a.acc, np.loadtxt(a.acc)), (a.gyro, np.loadtxt(a.gyro))))
        else:
            acc, gyro = read_imutk_ascii(a.acc), read_imutk_ascii(a.gyro)
        stamps.append(("read", time.process_time()))
        acc_unit = "counts" if a.unit == "counts" else "m/s^2"
        gyro_unit = "counts" if a.unit == "counts" else "rad/s"
        try:
            poses = detect_static(acc.t, acc.acc)
            if len(poses) < 12:
                raise AccelcalError("too few poses")
        except AccelcalError:
            choice = choose_static(acc.t, acc.acc, a.g, unit=acc_unit)
            poses = choice.poses
            print(choice.describe())
        cal = calibrate_poses(poses, a.g, "full_lls", unit=acc_unit)
        stamps.append(("accelerometer", time.process_time()))
        gcal = calibrate_gyro(acc.t, gyro.acc, poses, cal, raw_unit=gyro_unit, t_gyro=gyro.t, acc=acc.acc)
        stamps.append(("gyroscope", time.process_time()))
    except AccelcalError as e:
        print(f"accelcal: error: {e}", file=sys.stderr)
        return 2
    print(f"accelerometer: full LLS, {len(poses)} poses, bias {cal.bias.round(2).tolist()}")
    print(gcal.summary())
    if a.times:
        print("cpu s: " + ", ".join(f"{n} {t - t0:.3f}" for (_, t0), (n, t) in zip(stamps, stamps[1:])))
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"accelerometer": cal.to_dict(), "gyroscope": gcal.to_dict()}, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
