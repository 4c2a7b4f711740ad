"""Time to write a calibrated one-hour 400 Hz bag with ``accelcal apply``, against copying it.

Writes a synthetic bag with rosbags' own writer (1,440,000 ``sensor_msgs/Imu`` messages,
:mod:`tests.ros_synthetic`), a calibration with every term non-zero and a noise
report, then times in fresh subprocesses, side by side and alternating, ``--repeat`` times:

* ``apply``: ``accelcal apply CAL BAG --out OUT --noise NOISE`` (read, calibrate, write the
  calibrated log with filled covariances: the whole command);
* ``rosbags copy``: rosbags' reader and writer alone, every message copied verbatim (the
  floor of a rewrite through the same library);
* ``file copy``: ``shutil.copytree`` of the bag (the floor of any copy).

Wall and CPU times (user + system of each subprocess) are both recorded: on a shared
machine the CPU times move less with the load.

Usage::

    nice .venv/bin/python tools/bench_log_write.py [--kind ros2-sqlite3|ros2-mcap|mcap|ros1] [--minutes 60]
        [--rate 400] [--repeat 2] [--out results/bench/log_write.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROSBAGS_COPY = """
import sys
from pathlib import Path
src, dst, ros1 = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3] == "1"
if ros1:
    from rosbags.rosbag1 import Reader, Writer
    w = Writer(dst)
else:
    from rosbags.rosbag2 import Reader, StoragePlugin, Writer
    plugin = StoragePlugin.MCAP if sys.argv[4] == "mcap" else StoragePlugin.SQLITE3
    w = Writer(dst, version=9, storage_plugin=plugin)
from accelcal.formats.ros_write import _add_connection
with Reader(src) as r:
    w.open()
    cmap = {c.id: _add_connection(w, c, ros1) for c in r.connections}
    for c, t, raw in r.messages():
        w.write(cmap[c.id], t, raw)
    w.close()
"""


def _run(cmd: list[str], cpu: list) -> float:
    """Wall time of a subprocess; its CPU time (user + system, less sensitive to a loaded machine) to ``cpu``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return wall


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--kind", default="ros2-sqlite3")
    p.add_argument("--minutes", type=float, default=60.0)
    p.add_argument("--rate", type=float, default=400.0)
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--out", type=Path)
    args = p.parse_args()
    from accelcal.calibration import FullLLSCalibration
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' bag writer
    from tests.ros_synthetic import write_imu_bag

    work = Path(tempfile.mkdtemp(prefix="bench_log_write."))
    try:
        n = int(args.minutes * 60 * args.rate)
        rng = np.random.default_rng(0)
        suffix = {"ros1": ".bag", "mcap": ".mcap"}.get(args.kind, "")
        t0 = time.perf_counter()
        bag = write_imu_bag(work / ("in" + suffix), 1.7e9 + np.arange(n) / args.rate,
                            [0, 0, 9.81] + 0.01 * rng.standard_normal((n, 3)), 0.001 * rng.standard_normal((n, 3)),
                            kind=args.kind, serialize="fast")
        made = time.perf_counter() - t0
        cal = FullLLSCalibration(bias=np.array([0.05, -0.03, 0.08]), M=np.array(
            [[1.01, 0, 0], [0.002, 0.99, 0], [-0.003, 0.001, 1.02]]), g=9.80665, unit="m/s^2", input_unit="m/s^2")
        cal.save(work / "cal.json")
        axes = {a: {"noise_density": {"value": 1e-3}} for a in "xyz"}
        (work / "noise.json").write_text(json.dumps({"format": "accelcal-noise", "fs_hz": args.rate, "sensors": {
            "accelerometer": {"unit": "m/s^2", "axes": axes}, "gyroscope": {"unit": "rad/s", "axes": axes}}}))
        storage = "mcap" if "mcap" in args.kind else "sqlite3"
        times = {"apply": [], "rosbags copy": [], "file copy": []}
        cpu = {"apply": [], "rosbags copy": []}
        for k in range(args.repeat):
            out = work / f"apply{k}{suffix}"
            times["apply"].append(_run([sys.executable, "-m", "accelcal.cli", "apply", str(work / "cal.json"), str(bag),
                                        "--out", str(out), "--noise", str(work / "noise.json")], cpu["apply"]))
            copy = work / f"copy{k}{suffix}"
            times["rosbags copy"].append(_run([sys.executable, "-c", ROSBAGS_COPY, str(bag), str(copy),
                                               "1" if args.kind == "ros1" else "0", storage], cpu["rosbags copy"]))
            t1 = time.perf_counter()
            (shutil.copytree if bag.is_dir() else shutil.copy)(bag, work / f"plain{k}{suffix}")
            times["file copy"].append(time.perf_counter() - t1)
            for q in (out, copy, work / f"plain{k}{suffix}"):
                shutil.rmtree(q) if q.is_dir() else q.unlink()
        best = {k: min(v) for k, v in times.items()}
        result = {"kind": args.kind, "messages": n, "rate_hz": args.rate, "bag_written_s": made, "times_s": times,
                  "best_s": best, "apply_over_rosbags_copy": best["apply"] / best["rosbags copy"],
                  "apply_over_file_copy": best["apply"] / best["file copy"], "cpu_s": cpu,
                  "cpu_apply_over_rosbags_copy": min(cpu["apply"]) / min(cpu["rosbags copy"]),
                  "machine": platform.platform(), "load_average": list(os.getloadavg())}
    finally:
        shutil.rmtree(work, ignore_errors=True)
    text = json.dumps(result, indent=2)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
