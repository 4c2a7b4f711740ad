"""Coverage of the noise analysis's term intervals on simulated static records with known terms.

Each configuration is a noise model of the term library (white noise N, quantization Q,
flicker B, random walk K, ramp R; :mod:`accelcal.noise.terms`); ``records`` three-axis
records of ``samples`` samples at ``fs`` are simulated with it
(:func:`accelcal.noise.simulate_noise`, each record from its own seed) and analysed by
:func:`accelcal.noise.analyse_noise`, each axis an independent replicate.  For every term
of the fit the table counts how often its interval holds the true coefficient (a term the
configuration lacks, true value 0, is counted too: its interval must reach down to zero),
with the exact (Clopper–Pearson) interval of that rate.  ``tools/bench_noise_coverage.py``
runs the same on longer records and more of them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.noise import analyse_noise, simulate_noise
from accelcal.noise.terms import ieee_terms
from accelcal.recording import Recording

from ..discrepancy.scoring import clopper_pearson

COLUMNS = ("configuration", "term", "true", "present", "axes", "covered", "coverage", "coverage_low",
           "coverage_high", "level", "median_relative_width", "resolved_share", "samples", "duration_h")
#: A record's specific force at rest [m/s²] (one orientation; the analysis removes it).
GRAVITY_DOWN = np.array([0.0, 0.0, 9.80665])


def simulated_record(terms: dict, samples: int, fs: float, seed) -> Recording:
    """A static three-axis accelerometer record of the noise model ``terms`` (m/s²)."""
    rng = np.random.default_rng(seed)
    acc = GRAVITY_DOWN + simulate_noise(rng, samples, fs, terms, size=3)
    return Recording(np.arange(samples) / fs, acc, None, "simulated", unit="m/s^2")


def coverage_rows(name: str, terms: dict, *, records: int, samples: int, fs: float, seed: int, index: int,
                  level: float, n_boot: int) -> pd.DataFrame:
    """The coverage of every fitted term's interval over ``records`` simulated records of one configuration.

    ``index`` (the configuration's place in the config) and the record number seed each
    record, so a configuration's records do not depend on the others'.
    """
    fitted = ieee_terms()
    hits = {k: [] for k in fitted}
    width = {k: [] for k in fitted}
    resolved = {k: [] for k in fitted}
    for r in range(records):
        seq = np.random.SeedSequence([int(seed), int(index), r])
        record_seed, boot_seed = (int(s.generate_state(1)[0]) for s in seq.spawn(2))
        rec = simulated_record(terms, samples, fs, record_seed)
        # allow_motion: a random walk moves the 1 s means by design; the check is not under test here
        sensor = analyse_noise(rec, level=level, n_boot=n_boot, seed=boot_seed,
                               allow_motion=True).sensors["accelerometer"]
        for axis in sensor.terms:
            for k in fitted:
                e, truth = axis[k], float(terms.get(k, 0.0))
                hits[k].append(e.lo <= truth <= e.hi)
                resolved[k].append(e.resolved)
                if truth > 0:
                    width[k].append((e.hi - e.lo) / truth)
    rows = []
    for k in fitted:
        h = np.array(hits[k], dtype=float)
        lo, hi = clopper_pearson(np.array(h.sum()), np.array(h.size), level=0.95)
        truth = float(terms.get(k, 0.0))
        rows.append({"configuration": name, "term": k, "true": truth, "present": truth > 0, "axes": int(h.size),
                     "covered": int(h.sum()), "coverage": float(h.mean()), "coverage_low": float(lo),
                     "coverage_high": float(hi), "level": level,
                     "median_relative_width": float(np.median(width[k])) if width[k] else float("nan"),
                     "resolved_share": float(np.mean(resolved[k])), "samples": samples,
                     "duration_h": samples / fs / 3600.0})
    return pd.DataFrame(rows, columns=list(COLUMNS))


__all__ = ["COLUMNS", "coverage_rows", "simulated_record"]
