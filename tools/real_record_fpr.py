"""False-positive rate of the wander-null loop on a real-record profile, with many replicates.

The benchmark (``snakemake all``) runs ``seeds_none_real`` effect-free sessions of the
real-record profile; they share the record's clean windows, so their interval is wide.
This tool runs as many as asked (replicate ``r``: window ``r mod W``, axis permutation
``⌊r / W⌋ mod 6``, its own sensor and temperature, exactly as the benchmark's chunk does)
and prints the rate with the benchmark's interval (Clopper–Pearson on Kish's effective
sample size, clustered by window), and a cluster-robust check (mean and t interval of
the per-window rates).  It reads the profiles and the record a workflow run wrote.

Usage (after ``snakemake all``, or the target ``results/discrepancy/benchmark/profiles.json``)::

    .venv/bin/python tools/real_record_fpr.py [--replicates 4800] [--jobs 2] [--out per_recording.csv]
    PYTHONPATH=OTHER/src .venv/bin/python tools/real_record_fpr.py ...   # another checkout's loop
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):  # one BLAS thread per worker
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import yaml  # noqa: E402

from accelcal.discrepancy.vocabulary import Rules  # noqa: E402
from accelcal_repro.discrepancy.benchmark import Session, detect_nulls, simulate_case  # noqa: E402
from accelcal_repro.discrepancy.profiles import NoiseProfile  # noqa: E402
from accelcal_repro.discrepancy.scoring import interval  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
NOTHING = ("none", "not_identifiable", "error")


def _run(args) -> list[dict]:
    """Replicates ``start .. stop`` of the profile under the wander null."""
    start, stop, cfg_path, profiles_path, record_path, name = args
    cfg = yaml.safe_load(Path(cfg_path).read_text())["discrepancy"]
    bench = cfg["benchmark"]
    session, rules = Session.from_config(bench["session"]), Rules.from_config(cfg["rules"])
    prof = NoiseProfile.from_dict(json.loads(Path(profiles_path).read_text())[name])
    records = {prof.real: np.load(record_path).astype(float)}
    rows = []
    for r in range(start, stop):
        rec, key = simulate_case("none", 0.0, r, seed=cfg["seed"], session=session, rules=rules, profile=prof,
                                 records=records)
        (det,) = detect_nulls(rec, session.g, rules, ["wander"])
        rows.append({"replicate": r, "window": key["noise_window"], "outcome": det["outcome"]})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--replicates", type=int, default=4800)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--profile", default="adis_real")
    ap.add_argument("--config", default=str(REPO / "config" / "config.yaml"))
    ap.add_argument("--results", default=str(REPO / "results"), help="the results folder of a workflow run")
    ap.add_argument("--out", help="CSV: one row per replicate (window, outcome)")
    a = ap.parse_args(argv)
    res = Path(a.results)
    profiles, record = res / "discrepancy/benchmark/profiles.json", res / "discrepancy/adis/noise.npy"
    for p in (profiles, record):
        if not p.is_file():
            print(f"error: {p} not found: run the workflow first (snakemake all, or that target)", file=sys.stderr)
            return 2
    if a.replicates < 1 or a.jobs < 1:
        print("error: --replicates and --jobs must be at least 1", file=sys.stderr)
        return 2
    edges = np.linspace(0, a.replicates, 4 * a.jobs + 1).astype(int)
    tasks = [(int(s), int(e), a.config, str(profiles), str(record), a.profile) for s, e in zip(edges[:-1], edges[1:])
             if e > s]
    with ProcessPoolExecutor(a.jobs) as pool:
        df = pd.DataFrame([row for part in pool.map(_run, tasks) for row in part])
    fp = ~df.outcome.isin(NOTHING).to_numpy()
    lo, hi, ne = interval(fp, df.window.to_numpy())
    per_window = pd.Series(fp).groupby(df.window.to_numpy()).mean()
    m, se = per_window.mean(), per_window.std(ddof=1) / np.sqrt(len(per_window))
    print(f"{a.profile}: {fp.sum()} of {len(df)} effect-free sessions named something: {fp.mean():.4f} "
          f"[{lo:.4f}, {hi:.4f}] (Kish n_eff {ne:.0f}, {len(per_window)} windows)")
    print(f"  per-window rates: mean {m:.4f} +- {se:.4f} (cluster-robust), sd {per_window.std(ddof=1):.3f}")
    print("  outcomes:", df.outcome.value_counts().to_dict())
    if a.out:
        df.to_csv(a.out, index=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
