"""Read time and peak memory of the ROS bag reader on a one-hour 400 Hz IMU topic.

Writes a synthetic bag with rosbags' own writer (1,440,000 ``sensor_msgs/Imu`` messages,
serialised in numpy chunks checked byte-for-byte against rosbags' serialiser, see
:mod:`tests.ros_synthetic`), then reads it in fresh subprocesses on one
core, side by side in one run:

* ``accelcal``: :func:`accelcal.formats.read` (what ``accelcal calibrate BAG`` reads with:
  the format detected by the registry, the whole ros reader: open, decode, checks,
  Recording);
* ``rosbags iterate``: rosbags' message iterator alone, every raw message touched, no
  decoding (a floor: the reader cannot be faster than the bag's iteration);
* ``rosbags deserialise``: the iterator plus rosbags' own deserialisation of every
  message into Python objects, keeping only the six numbers (what a reader without the
  numpy decoding would cost; ``--skip-deserialise`` leaves it out).

Peak memory is the subprocess's peak resident set (``VmHWM``), which includes the
interpreter and the imported libraries (printed too: the same script importing only).

Usage::

    nice .venv/bin/python tools/bench_log_read.py [--kind ros2-sqlite3|ros2-mcap|mcap|ros1] [--minutes 60]
        [--rate 400] [--out results/bench/log_read.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SEED = 20250125
ONE_CORE = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}

READERS = {
    "imports only": "import accelcal.formats.ros, rosbags.rosbag2, rosbags.rosbag1, numpy\n",
    "accelcal": "from accelcal.formats import read\nrec = read(PATH)\nN = rec.n\n",
    "rosbags iterate": (
        "from accelcal.formats.ros import _locate, _open\np, kind = _locate(Path(PATH))\nN = 0\n"
        "with _open(p, kind) as r:\n    for c, t, raw in r.messages():\n        N += len(raw) > 0\n"),
    "rosbags deserialise": (
        "import numpy as np\nfrom accelcal.formats.ros import _locate, _open\n"
        "from rosbags.typesys import Stores, get_typestore\np, kind = _locate(Path(PATH))\n"
        "store = get_typestore(Stores.ROS1_NOETIC if kind == 'ROS 1 bag' else Stores.LATEST)\n"
        "de = store.deserialize_ros1 if kind == 'ROS 1 bag' else store.deserialize_cdr\nN = 0\n"
        "with _open(p, kind) as r:\n    out = np.empty((r.message_count, 6))\n"
        "    for c, t, raw in r.messages():\n        m = de(raw, c.msgtype)\n"
        "        a, w = m.linear_acceleration, m.angular_velocity\n"
        "        out[N] = (a.x, a.y, a.z, w.x, w.y, w.z)\n        N += 1\n"),
}
# VmHWM, the peak resident set of this process image: ru_maxrss would carry the parent's peak over exec
PEAK = ("def PEAK():\n    for line in open('/proc/self/status'):\n        if line.startswith('VmHWM:'):\n"
        "            return int(line.split()[1]) / 1024\n")
HARNESS = PEAK + ("import sys, time, json\nfrom pathlib import Path\nPATH = sys.argv[1]\n"
                  "t0 = time.perf_counter()\nc0 = time.process_time()\n"
           "N = 0\n{body}\nprint(json.dumps({{'wall_s': time.perf_counter() - t0, 'cpu_s': time.process_time() - c0, "
           "'messages': N, 'peak_rss_mb': PEAK()}}))\n")


def write_bag(path: Path, kind: str, minutes: float, rate: float) -> dict:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' bag writer
    from tests.ros_synthetic import write_imu_bag

    n = int(round(minutes * 60 * rate))
    rng = np.random.default_rng(SEED)
    t = 1.7e9 + np.arange(n) / rate
    acc = np.array([0.05, -0.1, 9.81]) + 0.02 * rng.standard_normal((n, 3))
    gyro = 0.003 * rng.standard_normal((n, 3))
    t0 = time.perf_counter()
    p = write_imu_bag(path, t, acc, gyro, kind=kind, serialize="fast")
    size = sum(f.stat().st_size for f in (p.rglob("*") if p.is_dir() else [p]))
    return {"path": str(p), "messages": n, "write_s": time.perf_counter() - t0, "bag_mb": size / 2**20}


def run(reader: str, path: str) -> dict:
    env = {**os.environ, **ONE_CORE, "PYTHONPATH": str(ROOT / "src")}
    code = HARNESS.format(body=READERS[reader])
    cmd = ["taskset", "-c", "0"] if shutil.which("taskset") else []
    out = subprocess.run(cmd + [sys.executable, "-c", code, path], capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kind", default="ros2-sqlite3", choices=["ros1", "ros2-sqlite3", "ros2-mcap", "mcap"])
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--rate", type=float, default=400.0)
    ap.add_argument("--skip-deserialise", action="store_true")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench_log_"))
    try:
        bag = write_bag(tmp / ("imu" + {"ros1": ".bag", "mcap": ".mcap"}.get(args.kind, "")), args.kind,
                        args.minutes, args.rate)
        print(f"{args.kind}: {bag['messages']:,} messages ({args.minutes:g} min at {args.rate:g} Hz), "
              f"{bag['bag_mb']:.0f} MB, written in {bag['write_s']:.1f} s", flush=True)
        results = {}
        for reader in READERS:
            if reader == "rosbags deserialise" and args.skip_deserialise:
                continue
            results[reader] = r = run(reader, bag["path"])
            print(f"  {reader:<20} wall {r['wall_s']:7.2f} s  cpu {r['cpu_s']:7.2f} s  "
                  f"peak RSS {r['peak_rss_mb']:7.0f} MB"
                  f"  ({r['messages']:,} messages)", flush=True)
        base = results["imports only"]["peak_rss_mb"]
        acc = results["accelcal"]
        output_mb = bag["messages"] * (6 * 8 + 8 + 8) / 2**20
        print(f"  accelcal: {acc['cpu_s'] / bag['messages'] * 1e6:.2f} us of CPU per message; "
              f"peak RSS {acc['peak_rss_mb']:.0f} MB"
              f" = {base:.0f} MB (interpreter and libraries) + {acc['peak_rss_mb'] - base:.0f} MB; the output arrays "
              f"(t, acc, gyro, time column) are {output_mb:.0f} MB")
        if "rosbags deserialise" in results:
            print(f"  accelcal / rosbags deserialise: {acc['wall_s'] / results['rosbags deserialise']['wall_s']:.2f} "
                  f"(wall time ratio)")
        summary = {"kind": args.kind, "minutes": args.minutes, "rate_hz": args.rate, **bag, "results": results,
                   "output_arrays_mb": output_mb, "python": platform.python_version(), "machine": platform.machine(),
                   "loadavg": Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None}
        if args.out:
            from accelcal.atomic import write_json_atomic

            write_json_atomic(args.out, summary)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
