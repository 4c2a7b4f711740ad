"""Benchmark: wall and CPU seconds per workflow stage from Snakemake's benchmark files (the
last run of every job)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.timing import stage_job_seconds

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("timing_stages")

log = configure_logging(snakemake)
table = stage_job_seconds(snakemake.params.benchmarks_dir)
log.info("job-seconds per stage:\n%s", table.to_string())
write_csv(table, snakemake.output[0])
