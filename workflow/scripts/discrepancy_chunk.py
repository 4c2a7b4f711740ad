"""One benchmark chunk: simulate each recording (key row apart), run the loop on it under every null and the oracle."""

import json

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.discrepancy.rules import Rules
from accelcal_repro.discrepancy.benchmark import (Session, chunk, detect_nulls, null_available, nulls_for, plan,
                                                  simulate_case)
from accelcal_repro.discrepancy.oracle import oracle_detection
from accelcal_repro.discrepancy.profiles import NoiseProfile
from accelcal_repro.montecarlo import grid_seed

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_chunk", chunk="0")

log = configure_logging(snakemake)
p = snakemake.params
bench = p.benchmark
session = Session.from_config(bench["session"])
rules = Rules.from_config(p.rules)
with open(snakemake.input.profiles) as f:
    profiles = {n: NoiseProfile.from_dict(d) for n, d in json.load(f).items()}
records = {"adis16405": np.load(snakemake.input.record[0]).astype(float) * 1.0} if snakemake.input.record else {}
for n in sorted(n for n in bench["nulls"] if not null_available(n)):
    log.warning("null hypothesis %r: not in this library's discrepancy loop yet; skipped", n)
todo = chunk(plan(list(profiles), rules.candidates, bench["sizes_mde"], bench["seeds"], bench["seeds_none"],
                  bench["seeds_constant"], pairs=bench["pairs"], outlier=bench["outlier"],
                  extra_sizes={pr: bench["power_curve"]["sizes_mde"] for pr in bench["power_curve"]["profiles"]},
                  none_counts={n: bench["seeds_none_real"] for n, pr in profiles.items() if pr.real}),
              bench["chunks"], p.chunk)
keys, dets = [], []
for spec in todo.itertuples():
    rec, key = simulate_case(spec.truth, spec.size_mde, spec.replicate, seed=p.seed, session=session, rules=rules,
                             profile=profiles[spec.profile], records=records)
    keys.append({"recording": spec.recording, **key})
    nulls = nulls_for(spec.truth, bench["nulls"])
    orng = np.random.default_rng(grid_seed(p.seed, f"discrepancy-oracle/{spec.profile}/{spec.truth}",
                                           float(spec.size_mde), int(spec.replicate)))
    oracle = ((lambda data, rows, prof=profiles[spec.profile], r=orng:
               oracle_detection(data, prof, session.rate, rules, r, rows)) if bench["oracle"] else None)
    dets += [{"recording": spec.recording, **row} for row in detect_nulls(rec, session.g, rules, nulls, oracle)]
write_csv(pd.DataFrame(keys), snakemake.output.key)
det = pd.DataFrame(dets)
write_csv(det, snakemake.output.detections)
log.info("chunk %d of %d: %d recordings, nulls %s: %s", p.chunk, bench["chunks"], len(keys), bench["nulls"],
         det.groupby("null")["outcome"].value_counts().to_dict() if len(det) else {})
