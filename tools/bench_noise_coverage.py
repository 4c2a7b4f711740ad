"""Coverage of the noise analysis's term intervals on simulated records with known terms.

Simulates static three-axis records with the stochastic layer's simulator
(:func:`accelcal.discrepancy.stochastic.simulate_noise`: white noise N, flicker B
(Kasdin–Walter), random walk K, and optionally quantization Q and a ramp R), runs
:func:`accelcal.noise.report.analyse_noise` on each, and counts for every term how
often the true coefficient lies inside its interval (the report's level, 95 % by
default); each axis is an independent replicate.  A term whose true value is zero is
counted too (its interval must reach down to zero).  Prints per configuration and
term: replicates, coverage with its binomial standard error, the median interval
width relative to the true value, and how often the term was "resolved".

Configurations (``--config``, default all; :data:`CONFIGS`): white noise only; a flicker
floor that dominates a decade of τ; a random walk that dominates; a flicker floor masked
by the random walk and the white noise (never the largest term); the same on a short
record; quantization on top of the flicker configuration.

Usage::

    nice .venv/bin/python tools/bench_noise_coverage.py [--seeds 100] [--config long short] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from accelcal.noise.simulation import simulate_noise
from accelcal.noise.report import analyse_noise
from accelcal.noise.terms import ieee_terms
from accelcal.recording import Recording

FS = 100.0
CONFIGS = {
    # white noise only
    "white": (2**18, {"white": 2e-3}),
    # a flicker floor dominating tau = 10 ... 2600 s; the random walk below it (only bounded)
    "flicker": (2**20, {"white": 2e-3, "bias_instability": 1e-3, "random_walk": 1e-5}),
    # a random walk dominating from tau = 30 s; the flicker floor below it
    "walk": (2**20, {"white": 2e-3, "bias_instability": 1e-4, "random_walk": 1e-4}),
    # the flicker floor never dominates: the random walk overtakes it before the white noise does
    "masked": (2**20, {"white": 2e-3, "bias_instability": 2e-4, "random_walk": 2e-5}),
    # the "masked" terms on a 22 min record: only N resolved
    "short": (2**17, {"white": 2e-3, "bias_instability": 2e-4, "random_walk": 2e-5}),
    # quantization of the integrated output on top of "flicker"
    "quantized": (2**20, {"white": 2e-3, "quantization": 2e-4, "bias_instability": 1e-3, "random_walk": 1e-5}),
}


def one_record(n: int, terms: dict, seed: int, level: float, n_boot: int):
    rng = np.random.default_rng(seed)
    acc = np.array([0.0, 0.0, 9.8]) + simulate_noise(rng, n, FS, terms, size=3)
    rec = Recording(np.arange(n) / FS, acc, None, f"sim{seed}", unit="m/s^2")
    report = analyse_noise(rec, level=level, n_boot=n_boot, seed=seed, allow_motion=True)
    return report.sensors["accelerometer"]


def run(config: str, seeds: int, level: float, n_boot: int, first_seed: int) -> dict:
    n, terms = CONFIGS[config]
    fitted = ieee_terms()
    hits = {k: [] for k in fitted}
    width = {k: [] for k in fitted}
    resolved = {k: [] for k in fitted}
    errors = []
    t0 = time.perf_counter()
    for seed in range(first_seed, first_seed + seeds):
        s = one_record(n, terms, seed, level, n_boot)
        errors += list(s.model_error)
        for axis in s.terms:
            for k in fitted:
                e, truth = axis[k], terms.get(k, 0.0)
                hits[k].append(e.lo <= truth <= e.hi)
                resolved[k].append(e.resolved)
                if truth > 0:
                    width[k].append((e.hi - e.lo) / truth)
    out = {"n": n, "duration_h": n / FS / 3600, "terms": terms, "seeds": seeds, "level": level, "n_boot": n_boot,
           "elapsed_s": time.perf_counter() - t0, "model_error_median": float(np.median(errors)), "per_term": {}}
    for k in fitted:
        h = np.array(hits[k], dtype=float)
        cov = float(h.mean())
        out["per_term"][k] = {"true": terms.get(k, 0.0), "replicates": int(h.size), "coverage": cov,
                              "coverage_se": float(np.sqrt(cov * (1 - cov) / h.size)),
                              "median_relative_width": float(np.median(width[k])) if width[k] else None,
                              "resolved_share": float(np.mean(resolved[k]))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", nargs="*", default=list(CONFIGS), choices=list(CONFIGS))
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--level", type=float, default=0.95)
    ap.add_argument("--n-boot", type=int, default=400)
    ap.add_argument("--out")
    args = ap.parse_args(argv)
    results = {}
    for c in args.config:
        r = results[c] = run(c, args.seeds, args.level, args.n_boot, args.first_seed)
        print(f"{c}: {r['seeds']} records x 3 axes, {r['duration_h']:.2g} h each, level {r['level']:g}, "
              f"{r['elapsed_s']:.0f} s; median model misfit {50 * r['model_error_median']:.2g} %", flush=True)
        for k, v in r["per_term"].items():
            w = "" if v["median_relative_width"] is None else f", median width {v['median_relative_width']:.3g}x true"
            print(f"  {k:<17} true {v['true']:<8.3g} coverage {v['coverage']:.3f} +- {v['coverage_se']:.3f} "
                  f"({v['replicates']} axes){w}, resolved on {100 * v['resolved_share']:.0f} %", flush=True)
    if args.out:
        from accelcal.atomic import write_json_atomic

        write_json_atomic(args.out, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
