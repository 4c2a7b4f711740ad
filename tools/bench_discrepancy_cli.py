"""Wall time of ``accelcal discrepancy`` on a 40-pose, 10-minute recording at 100 Hz (its goal: under 10 s on one core).

Generates the recording deterministically (seed below): raw 16-bit counts like the Xsens
session (415 counts per m/s², 3.3 counts white noise, rounded), a 30 s initial rest, then
39 hand-placed poses of 12 s joined by 2.6 s motions (600 s in all), a bias wander
(Gauss–Markov, τ = 120 s, the size of the pose-mean white noise) and a temperature
column.  Runs the command ``--repeat`` times as a subprocess on one core (BLAS, OpenMP
and numba threads set to 1; ``--pin`` also pins it to CPU 0 with ``taskset``), and prints and
writes (``--out``, JSON) every wall time, their minimum and median, the machine load
before and after (``/proc/loadavg``), the Python and accelcal versions, and what the
command named.

Usage::

    .venv/bin/python tools/bench_discrepancy_cli.py [--repeat 5] [--out results/bench/discrepancy_cli.json]
    PYTHONPATH=OTHER/src .venv/bin/python tools/bench_discrepancy_cli.py --label before   # another checkout
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SEED = 20240713
G = 9.80665
N_POSES = 40
RATE = 100.0
INIT_REST_S = 30.0
REST_S = 12.0
MOVE_S = 2.6
FLICKER_B = 0.3  # counts


def make_recording(path: Path) -> dict:
    """Write the benchmark recording (canonical CSV) and return its description."""
    from accelcal.model import m_from_params
    from accelcal.formats import write_recording
    from accelcal.recording import Recording
    from accelcal.simulation import random_directions, simulate_recording
    from accelcal.noise import simulate_noise

    rng = np.random.default_rng(SEED)
    u = random_directions(rng, N_POSES)
    M = m_from_params(np.array([414.0, 413.0, 415.5]), np.deg2rad([0.4, -0.8, 1.1]))
    bias = np.array([32768.0 + 250, 32768.0 - 310, 32768.0 + 120])
    sim = simulate_recording(rng, u, G, M, bias, 3.3, rate=RATE, rest_s=REST_S, move_s=MOVE_S,
                             init_rest_s=INIT_REST_S)
    n = len(sim["t"])
    pose_white = 3.3 / np.sqrt(REST_S * RATE)
    # a flicker floor the rests see (Allan floor 0.664 B = 0.2 counts, like the Xsens rests at
    # 5-10 s: the stochastic layer names terms and bootstraps again) and a slow wander
    noise = {"gauss_markov": (pose_white, 120.0), "bias_instability": FLICKER_B}
    wander = simulate_noise(rng, n, RATE, noise, size=3)
    acc = np.round(sim["acc"] + wander)
    t = sim["t"]
    temp = np.round(25.0 + 4.0 * np.sin(2 * np.pi * 1.5 * t / t[-1] + 0.7), 2)
    write_recording(path, Recording(t, acc, temp, "bench_discrepancy_cli"))
    return {"n_poses": N_POSES, "rate_hz": RATE, "duration_s": float(t[-1] + 1 / RATE), "samples": int(n),
            "seed": SEED, "noise_counts": 3.3, "wander": {"gauss_markov_sigma_counts": float(pose_white),
                                                          "tau_s": 120.0, "flicker_B_counts": FLICKER_B}}


def _loadavg() -> list[float]:
    try:
        return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]
    except OSError:
        return []


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", type=Path, default=Path("results/bench/discrepancy_cli.json"))
    ap.add_argument("--label", default="current")
    ap.add_argument("--recording", type=Path, default=None,
                    help="use this recording (generated there first if missing): the same file for two checkouts")
    ap.add_argument("--default-threads", action="store_true",
                    help="leave BLAS/OpenMP threads at their defaults (what a user gets) instead of 1")
    ap.add_argument("--pin", action="store_true",
                    help="pin the command to CPU 0 with taskset (on a shared machine this measures waiting)")
    args = ap.parse_args(argv)
    one = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    env = {**os.environ} if args.default_threads else {**os.environ, **one}
    pin = ["taskset", "-c", "0"] if args.pin and shutil.which("taskset") else []
    with tempfile.TemporaryDirectory() as tmp:
        rec = args.recording or Path(tmp) / "rec.csv"
        desc = make_recording(rec) if not rec.exists() else {"file": str(rec), "n_poses": N_POSES, "seed": SEED}
        walls, cpus, named = [], [], None
        load_before = _loadavg()
        for i in range(args.repeat):
            out = Path(tmp) / f"report_{i}.json"
            cmd = [*pin, sys.executable, "-m", "accelcal.cli", "discrepancy", str(rec), "--g", str(G), "--out", str(out)]
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            p = subprocess.run(cmd, env=env, capture_output=True, text=True)
            walls.append(time.perf_counter() - t0)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus.append((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
            if p.returncode != 0:
                print(p.stderr, file=sys.stderr)
                return p.returncode
            rep = json.loads(out.read_text())
            named = {"outcome": rep["outcome"], "effects": rep["effects"],
                     "noise_model": {k: rep.get("noise_model", {}).get(k) for k in ("term", "process", "size", "tau_s")}}
            print(f"run {i + 1}/{args.repeat}: wall {walls[-1]:.2f} s, cpu {cpus[-1]:.2f} s", flush=True)
        load_after = _loadavg()
    import accelcal

    result = {"label": args.label, "command": "accelcal discrepancy REC.csv --g 9.80665 --out R.json",
              "one_core": {"threads": "default" if args.default_threads else 1, "taskset": bool(pin)}, "recording": desc, "wall_s": walls,
              "wall_min_s": min(walls), "wall_median_s": statistics.median(walls), "cpu_s": cpus,
              "cpu_median_s": statistics.median(cpus), "loadavg_before": load_before,
              "loadavg_after": load_after, "cpus": os.cpu_count(), "python": sys.version.split()[0],
              "accelcal": getattr(accelcal, "__version__", "?"), "accelcal_path": str(Path(accelcal.__file__).parent),
              "named": named, "date": time.strftime("%Y-%m-%d %H:%M:%S")}
    print(json.dumps({k: result[k] for k in ("label", "wall_min_s", "wall_median_s", "cpu_median_s", "loadavg_before",
                                             "loadavg_after", "named")}, indent=1))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
