"""Benchmark chunk: simulated recordings with one hidden effect each (canonical CSV) and their key."""

from pathlib import Path

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.discrepancy.benchmark import Session, chunk, plan, simulate_case, write_counts_csv
from accelcal.discrepancy.detect import Rules

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_generate", chunk="0")

log = configure_logging(snakemake)
p = snakemake.params
bench = p.benchmark
session = Session.from_config(bench["session"])
rules = Rules.from_config(p.rules)
todo = chunk(plan(rules.candidates, bench["sizes_mde"], bench["seeds"], bench["seeds_none"],
                  bench["seeds_constant"]), p.chunks, p.chunk)
out = Path(snakemake.output.recordings)
out.mkdir(parents=True, exist_ok=True)
rows = []
for _, spec in todo.iterrows():
    rec, key = simulate_case(spec.truth, spec.size_mde, int(spec.replicate), seed=p.seed, session=session, rules=rules)
    write_counts_csv(out / f"{spec.recording}.csv", rec)
    rows.append({"recording": spec.recording, **key})
write_csv(pd.DataFrame(rows), snakemake.output.key)
log.info("chunk %d of %d: %d recordings -> %s, key -> %s", p.chunk, p.chunks, len(rows), out, snakemake.output.key)
