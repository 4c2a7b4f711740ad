"""The Tereshkov Monte Carlo jobs merged: one table per scenario in the order one job
would write it, and the wall times summed over the jobs."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.montecarlo import merge_job_tables, merge_job_timings

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_merge")

log = configure_logging(snakemake)
for name in snakemake.params.scenarios:
    paths = list(snakemake.input[name])
    df = merge_job_tables(pd.read_csv(p) for p in paths)
    log.info("%s: %d rows from %d jobs", name, len(df), len(paths))
    write_csv(df, getattr(snakemake.output, name))
for part in ("main", "sweep"):
    timing = merge_job_timings(pd.concat([pd.read_csv(p) for p in snakemake.input[f"{part}_timing"]],
                                         ignore_index=True))
    log.info("%s wall times:\n%s", part, timing.to_string())
    write_csv(timing, snakemake.output[f"timing_{part}"])
