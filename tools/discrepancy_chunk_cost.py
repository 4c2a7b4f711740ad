"""Where a discrepancy benchmark chunk spends its CPU: a sample of one chunk's recordings run as
``workflow/scripts/discrepancy_chunk.py`` runs them, with CPU seconds per component.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python tools/discrepancy_chunk_cost.py RESULTS [CHUNK] [STEP]   # from the repo root

``RESULTS``: the results folder of a run of the default config (its
``discrepancy/benchmark/profiles.json`` and ``discrepancy/adis/noise.npy``); every ``STEP``-th
recording of chunk ``CHUNK`` of the config's ``benchmark.chunks`` (default 0 and 4).  Prints
the CPU per recording by profile and the share of each component (timers wrapped around module functions, no profiler: its
overhead inflates the Python-heavy parts).  Run with one BLAS thread, as Snakemake's jobs do.

Measured (2026-11-29, 118 recordings of chunk 0 of 16, load 7-10 on 2 cores): 70 ms a
recording; the wander loop 53 % (its noise fit over the (phi, tau) grid, ``fit_common``, 19 %;
the round's bootstrap tests 23 %), the simulation 15 %, the static detection 9 %, the oracle
8 %, the white null 3 %; LAPACK ``eigh`` 20 % of the whole.
"""

from __future__ import annotations

import collections
import functools
import importlib
import json
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from accelcal.discrepancy.rules import Rules
from accelcal_repro.discrepancy import benchmark as B
from accelcal_repro.discrepancy.oracle import oracle_detection
from accelcal_repro.discrepancy.profiles import NoiseProfile
from accelcal_repro.montecarlo import grid_seed

#: (module, function) pairs timed; nested ones count inside their callers too.
TIMED = [("accelcal_repro.discrepancy.benchmark", f) for f in
         ("simulate_case", "detect_static_recording", "pose_data_from_static", "discrepancy")] + [
    ("accelcal.discrepancy.detect", "discrepancy_wander"), ("accelcal.discrepancy.detect", "discrepancy_white"),
    ("accelcal.discrepancy.wander_loop", "linearise_noise"), ("accelcal.discrepancy.wander_loop", "_round"),
    ("accelcal.discrepancy.wander", "round_tests"), ("accelcal.discrepancy.wander", "fit_common"),
    ("numpy.linalg", "eigh")]
SPENT: collections.Counter = collections.Counter()


def _timed(module: str, name: str) -> None:
    mod = importlib.import_module(module)
    fn = getattr(mod, name)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        t0 = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            SPENT[f"{module.rsplit('.', 1)[-1]}.{name}"] += time.process_time() - t0

    setattr(mod, name, wrapper)


def _plan(cfg: dict, profiles: dict, rules: Rules, k: int) -> pd.DataFrame:
    bench = cfg["benchmark"]
    return B.chunk(B.plan(list(profiles), rules.candidates, bench["sizes_mde"], bench["seeds"], bench["seeds_none"],
                          bench["seeds_constant"], pairs=bench["pairs"], outlier=bench["outlier"],
                          extra_sizes={p: bench["power_curve"]["sizes_mde"] for p in bench["power_curve"]["profiles"]},
                          none_counts={n: bench["seeds_none_real"] for n, p in profiles.items() if p.real}),
                   bench["chunks"], k)


def main(results: Path, k: int, step: int) -> None:
    cfg = yaml.safe_load(Path("config/config.yaml").read_text())["discrepancy"]
    session, rules = B.Session.from_config(cfg["benchmark"]["session"]), Rules.from_config(cfg["rules"])
    profiles = {n: NoiseProfile.from_dict(d) for n, d in
                json.loads((results / "discrepancy/benchmark/profiles.json").read_text()).items()}
    records = {"adis16405": np.load(results / "discrepancy/adis/noise.npy").astype(float)}
    for module, name in TIMED:
        _timed(module, name)
    rows = []
    for spec in _plan(cfg, profiles, rules, k).iloc[::step].itertuples():
        t0 = time.process_time()
        rec, _ = B.simulate_case(spec.truth, spec.size_mde, spec.replicate, seed=cfg["seed"], session=session,
                                 rules=rules, profile=profiles[spec.profile], records=records)
        rng = np.random.default_rng(grid_seed(cfg["seed"], f"discrepancy-oracle/{spec.profile}/{spec.truth}",
                                              float(spec.size_mde), int(spec.replicate)))
        B.detect_nulls(rec, session.g, rules, B.nulls_for(spec.truth, cfg["benchmark"]["nulls"]),
                       lambda data, loop, p=profiles[spec.profile]: oracle_detection(data, p, session.rate, rules,
                                                                                     rng, loop))
        rows.append((spec.profile, time.process_time() - t0))
    t = pd.DataFrame(rows[1:], columns=["profile", "cpu_s"])  # the first pays the kernels' loading
    print((t.groupby("profile").cpu_s.agg(["count", "mean"]) * [1, 1000]).round(1).rename(
        columns={"mean": "ms"}).to_string())
    total = float(t.cpu_s.sum() + rows[0][1])
    print(f"{len(rows)} recordings, {1000 * total / len(rows):.1f} ms each")
    for key, s in SPENT.most_common():
        print(f"  {key:40s} {s:7.2f} s {100 * s / total:5.1f} %")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(Path(args[0]), int(args[1]) if len(args) > 1 else 0, int(args[2]) if len(args) > 2 else 4)
