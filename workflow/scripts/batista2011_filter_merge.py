"""Filter Monte Carlo: the chunks' per-run errors concatenated and their statistics merged."""

import pandas as pd
from _helpers import configure_logging
from batista2011_common import OUT, TABLES, standalone, write_table

from accelcal_repro.batista2011.montecarlo import filter_summary, merge_filter_moments

if "snakemake" not in globals():
    snakemake = standalone("batista2011_filter_merge",
                           input={"runs": [f"{OUT}/chunks/filter_runs_0.csv.gz"],
                                  "moments": [f"{OUT}/chunks/filter_moments_0.csv.gz"]},
                           output={"runs": TABLES["filter_runs"], "summary": TABLES["filter_summary"]})

log = configure_logging(snakemake)
runs = pd.concat([pd.read_csv(p) for p in snakemake.input.runs], ignore_index=True)
runs = runs.sort_values(["run", "t"], kind="stable", ignore_index=True)
summary = filter_summary(merge_filter_moments(pd.read_csv(p) for p in snakemake.input.moments))
log.info("%d runs from %d chunks", runs["run"].nunique(), len(snakemake.input.runs))
write_table(runs, snakemake.output.runs, float_format="%.6g")
write_table(summary, snakemake.output.summary, float_format="%.6g")
