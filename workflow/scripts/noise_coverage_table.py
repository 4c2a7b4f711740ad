"""Gather the coverage of every configuration into results/noise/coverage.csv."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("noise_coverage_table")

log = configure_logging(snakemake)
df = pd.concat([pd.read_csv(f) for f in snakemake.input], ignore_index=True)
write_csv(df, snakemake.output[0])
log.info("%d rows from %d configuration(s)", len(df), len(snakemake.input))
