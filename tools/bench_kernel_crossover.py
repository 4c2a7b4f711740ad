"""Time per call of a single-problem estimator against the calls a process makes: the
numpy path, the compiled kernels forced (``ACCELCAL_KERNELS=numba``) and the default
(``auto``, which switches to the kernels once its calls would have saved, compiled,
numba's start-up :data:`accelcal.kernels.STARTUP_S`: about 14 300 full LLS calls),
side by side in one run.

Every point is a fresh process (as a user's script is): it imports accelcal, makes one
problem (24 poses by default, Burkhard et al.'s truth ranges, noise 1e-3 m/s²) and
calls the estimator N times on it; the time of the N calls, numba's import and kernel
loading included, divided by N is the µs per call.  The compiled kernels run with two
disk caches (``NUMBA_CACHE_DIR``, so the project's own cache is neither used nor
touched): ``cold``, empty for every process (each compiles, as on a fresh install) and
``warm``, filled once beforehand (as every later process).  One core (BLAS, OpenMP and
numba threads 1).  The median over ``--repeat`` processes is printed, with the
quantities the threshold is chosen from: the time per call of each path for many calls,
the start-up of the kernels (the first call's extra time), and the break-even count
(start-up / time saved per call), and written to ``--out`` (CSV) if given.

Usage::

    .venv/bin/python tools/bench_kernel_crossover.py [--method full_lls] [--poses 24] [--repeat 3]
        [--calls 1,10,...] [--out FILE | --rows FILE]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

CALLS = (1, 10, 100, 1000, 3000, 10000, 14000, 14300, 20000, 30000, 100000)
#: Label -> (ACCELCAL_KERNELS, cache).
PATHS = {"numpy": ("numpy", None), "numba, warm cache": ("numba", "warm"), "numba, cold cache": ("numba", "cold"),
         "auto, warm cache": ("auto", "warm"), "auto, cold cache": ("auto", "cold")}

CHILD = """
import json, sys, time
import numpy as np
from accelcal import kernels
from accelcal.registry import estimator
from accelcal.simulation import random_directions, sample_truth, simulate_poses
method, n_poses, calls = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(0)
tr = sample_truth(rng, 1)
z = simulate_poses(random_directions(rng, n_poses), 9.8055, tr["M"][0], tr["bias"][0], 1e-3, rng)
e = estimator(method)
f = e.load()
kw = {"noise_std": 1e-3} if e.needs_noise else {}
t0, c0 = time.perf_counter(), time.process_time()
for _ in range(calls):
    f(z, 9.8055, **kw)
total, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({"seconds": total, "cpu_seconds": cpu, "backend": kernels.backend(), "numba": "numba" in sys.modules,
                  "loaded": sorted(kernels._loaded)}))
"""


def run(method: str, n_poses: int, calls: int, kernels: str, cache_dir: str) -> dict:
    env = dict(os.environ, ACCELCAL_KERNELS=kernels, NUMBA_CACHE_DIR=cache_dir, OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, method, str(n_poses), str(calls)], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(method: str, n_poses: int, repeat: int, calls=CALLS) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory(prefix="accelcal-crossover-") as tmp:
        warm = os.path.join(tmp, "warm")
        run(method, n_poses, 2, "numba", warm)  # fill the warm cache once
        for r in range(repeat):
            for n in calls:
                for label, (kernels, cache) in PATHS.items():
                    cache_dir = warm if cache == "warm" else os.path.join(tmp, f"cold-{r}-{n}-{kernels}")
                    res = run(method, n_poses, n, kernels, cache_dir)
                    rows.append({"method": method, "n_poses": n_poses, "calls": n, "path": label, "repeat": r,
                                 "seconds": res["seconds"], "cpu_seconds": res["cpu_seconds"],
                                 "us_per_call": 1e6 * res["seconds"] / n,
                                 "cpu_us_per_call": 1e6 * res["cpu_seconds"] / n, "compiled": bool(res["loaded"])})
    return rows


def summary(rows: list[dict], column: str = "us_per_call") -> tuple[dict, dict]:
    """Median µs per call per (calls, path) of ``column``, and the figures the threshold
    is chosen from: the cost of one more call of each path (the slope between the two
    largest call counts), the kernels' start-up (the first call's cost less one call),
    the break-even count (start-up / time a compiled call saves) and the first call count
    at which ``auto``, switched to the kernels, costs no more per call than numpy."""
    med, switched = {}, set()
    for row in rows:
        med.setdefault((int(row["calls"]), row["path"]), []).append(row[column])
        if row["compiled"] in (True, "True"):
            switched.add((int(row["calls"]), row["path"]))
    med = {k: statistics.median(v) for k, v in med.items()}
    counts = sorted({n for n, _ in med})
    a, b = counts[-2], counts[-1]

    def slope(path):
        return (med[(b, path)] * b - med[(a, path)] * a) / (b - a)

    fig = {"numpy_us": slope("numpy"), "numba_us": slope("numba, warm cache")}
    saved = fig["numpy_us"] - fig["numba_us"]
    for cache in ("warm", "cold"):
        startup = med[(1, f"numba, {cache} cache")] - fig["numba_us"]
        fig[f"startup_{cache}_s"] = 1e-6 * startup
        fig[f"break_even_{cache}"] = startup / saved if saved > 0 else float("inf")
        auto = f"auto, {cache} cache"  # after its switch to the kernels
        fig[f"auto_pays_{cache}"] = next((n for n in counts if (n, auto) in switched and med[(n, auto)]
                                          <= med[(n, "numpy")]), None)
    return med, fig


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--method", default="full_lls", help="a single-problem estimator with a compiled kernel")
    ap.add_argument("--poses", type=int, default=24)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--calls", type=lambda s: tuple(int(x) for x in s.split(",")), default=CALLS,
                    help="calls per process, comma-separated (must include 1)")
    ap.add_argument("--out", help="CSV of every process's time")
    ap.add_argument("--rows", help="summarise a CSV written by --out instead of measuring")
    args = ap.parse_args(argv)
    from accelcal import kernels

    if args.rows:
        with open(args.rows, newline="") as f:
            rows = [{k: (v if k in ("method", "path", "compiled") else float(v)) for k, v in r.items()}
                    for r in csv.DictReader(f)]
    else:
        rows = measure(args.method, args.poses, args.repeat, args.calls)
    if args.out:
        with open(args.out, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    paths = list(PATHS)
    from accelcal.lls import SAVES_S

    saves = SAVES_S[args.method] + (SAVES_S["full_lls"] if args.method == "full_als" else 0.0)  # ALS runs its LLS
    print(f"{args.method}, {args.poses} poses; median of {args.repeat} fresh processes, numba's import and kernel "
          f"loading included; auto switches in call {int(-(-kernels.STARTUP_S // saves))} "
          f"(STARTUP_S {kernels.STARTUP_S} s / {1e6 * saves:.1f} µs saved per call)")
    for column, what in (("cpu_us_per_call", "CPU µs per call"), ("us_per_call", "wall µs per call")):
        med, fig = summary(rows, column)
        print(f"\n{what}\n{'calls':>8}  " + "  ".join(f"{p:>18}" for p in paths))
        for n in sorted({n for n, _ in med}):
            print(f"{n:>8}  " + "  ".join(f"{med[(n, p)]:>18.2f}" for p in paths))
        print(f"one more call: numpy {fig['numpy_us']:.1f} µs, compiled {fig['numba_us']:.1f} µs")
        for cache in ("warm", "cold"):
            pays = fig[f"auto_pays_{cache}"]
            pays = f"from {pays} calls" if pays else "at no count measured"
            print(f"kernels' start-up, {cache} cache: {fig[f'startup_{cache}_s']:.3f} s = break-even after "
                  f"{fig[f'break_even_{cache}']:.0f} calls; auto (switched) no slower than numpy {pays}")
    with open("/proc/loadavg") as f:
        print(f"load average: {f.read().split()[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
