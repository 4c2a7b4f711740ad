"""Filter Monte Carlo: the chunks' per-run errors concatenated and their statistics merged."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.montecarlo import filter_summary, merge_filter_moments

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_filter_merge")

log = configure_logging(snakemake)
runs = pd.concat([pd.read_csv(p) for p in snakemake.input.runs], ignore_index=True)
runs = runs.sort_values(["run", "t"], kind="stable", ignore_index=True)
summary = filter_summary(merge_filter_moments(pd.read_csv(p) for p in snakemake.input.moments))
log.info("%d runs from %d chunks", runs["run"].nunique(), len(snakemake.input.runs))
write_csv(runs, snakemake.output.runs, float_format="%.6g")
write_csv(summary, snakemake.output.summary, float_format="%.6g")
