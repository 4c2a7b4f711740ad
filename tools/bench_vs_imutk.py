"""Whole-process timing of the command line against IMU-TK's compiled calibration app.

    .venv/bin/python tools/bench_vs_imutk.py --imutk /path/to/test_imu_calib \
        [--imutk-acc /path/to/acc_only_app] [--runs 10] [--out results/timing/cli_vs_imutk.csv]

IMU-TK (Tedaldi, Pretto, Menegatti, ICRA 2014) is not part of this project: build it from
its own sources and pass the binary (``--imutk`` or $IMUTK_CALIB).  Its example app
``test_imu_calib`` reads the Xsens session of ``../shared/data/imu_tk_xsens`` (ASCII
``xsens_acc.mat`` and ``xsens_gyro.mat``) and calibrates the accelerometer and the gyro;
``--imutk-acc`` may name an app that calibrates the accelerometer only (the same calls
without the gyro), which is what ``accelcal calibrate`` does.

``accelcal calibrate`` gets the same session as the canonical CSV (written once into a
temporary folder, not timed: each tool reads its own format), ``--g 9.81744`` (the value
the IMU-TK example uses) and the full LLS; and, as IMU-TK does, accelerometer and gyro from
the very files IMU-TK reads (``xsens_acc.mat --gyro xsens_gyro.mat``), with and without
the nominal gyro sensitivity (the data sheet's: no scalar search for the start).  Also timed: ``python -c "import accelcal"`` and
``accelcal --help`` (the start-up the CLI pays before any work).

The commands run in turn (A B C ... A B C ...), after one untimed warm-up each, so that
the machine's load drifts over all of them alike; wall time and the CPU time of the
child process (user + system) are recorded per run, with the load average, printed as
medians and written to ``--out``.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data" / "imu_tk_xsens"
G_XSENS = "9.81744"


def _run(cmd: list[str], cwd: Path) -> tuple[float, float, int]:
    """Wall and CPU seconds (children's user + system) of one run, and its exit code."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc.returncode


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--imutk", default=os.environ.get("IMUTK_CALIB"),
                    help="IMU-TK's test_imu_calib binary (default $IMUTK_CALIB)")
    ap.add_argument("--imutk-acc", default=os.environ.get("IMUTK_CALIB_ACC"),
                    help="an IMU-TK app calibrating the accelerometer only (optional)")
    ap.add_argument("--data", type=Path, default=DATA, help=f"folder with xsens_acc.mat, xsens_gyro.mat ({DATA})")
    ap.add_argument("--runs", type=int, default=10, help="timed runs of each command (default 10)")
    ap.add_argument("--out", type=Path, default=REPO / "results" / "timing" / "cli_vs_imutk.csv")
    args = ap.parse_args(argv)
    if not args.imutk or not Path(args.imutk).is_file():
        ap.error("give IMU-TK's calibration app with --imutk (or $IMUTK_CALIB); build it from IMU-TK's sources")
    acc, gyro = args.data / "xsens_acc.mat", args.data / "xsens_gyro.mat"
    for f in (acc, gyro):
        if not f.is_file():
            ap.error(f"{f} not found (the shared data folder, see ../shared/data/README.md)")

    import pandas as pd

    from accelcal.formats import write_recording
    from accelcal.formats.imutk import read_imutk_ascii

    bindir = Path(sys.executable).parent
    accelcal = shutil.which("accelcal", path=str(bindir)) or str(bindir / "accelcal")
    with tempfile.TemporaryDirectory(prefix="accelcal-bench-") as tmp:
        tmp = Path(tmp)
        csv = tmp / "xsens_acc.csv"
        write_recording(csv, read_imutk_ascii(acc))
        commands = {
            "imutk test_imu_calib (acc + gyro)": [args.imutk, str(acc), str(gyro)],
            "accelcal calibrate (full-lls)": [accelcal, "calibrate", str(csv), "--g", G_XSENS, "--method", "full-lls",
                                              "--out", str(tmp / "result.json")],
            "accelcal calibrate (acc + gyro, the same files)": [
                accelcal, "calibrate", str(acc), "--gyro", str(gyro), "--g", G_XSENS, "--out", str(tmp / "both.json")],
            "accelcal calibrate (acc + gyro, --gyro-sensitivity 4770/rad/s, the data sheet's)": [
                accelcal, "calibrate", str(acc), "--gyro", str(gyro), "--g", G_XSENS, "--gyro-sensitivity",
                "4770/rad/s", "--out", str(tmp / "both_s.json")],
            "accelcal --help": [accelcal, "--help"],
            "python -c 'import accelcal'": [sys.executable, "-c", "import accelcal"],
        }
        if args.imutk_acc:
            commands["imutk accelerometer only"] = [args.imutk_acc, str(acc)]
        for name, cmd in commands.items():  # warm-up: page cache, first-run costs
            wall, cpu, code = _run(cmd, tmp)
            if code != 0:
                print(f"{name}: exit code {code} ({' '.join(cmd)})", file=sys.stderr)
                return 1
        rows = []
        for r in range(args.runs):
            for name, cmd in commands.items():
                wall, cpu, code = _run(cmd, tmp)
                rows.append({"command": name, "run": r, "wall_s": wall, "cpu_s": cpu, "exit_code": code,
                             "load_1min": os.getloadavg()[0]})
    table = pd.DataFrame(rows)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    print(f"{args.runs} runs each, interleaved; load average now {os.getloadavg()[0]:.2f} "
          f"(1 min), {os.cpu_count()} cores; written to {args.out}")
    for name, d in table.groupby("command", sort=False):
        print(f"  {name:40s} wall median {statistics.median(d['wall_s']):.3f} s (min {d['wall_s'].min():.3f}), "
              f"CPU median {statistics.median(d['cpu_s']):.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
