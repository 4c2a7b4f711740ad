"""Coverage of the gyro's 95 % intervals in a Monte Carlo with a wandering bias."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.stage import coverage_tables

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_coverage")

log = configure_logging(snakemake)
table, summary = coverage_tables(snakemake.params.gyro)
for r in summary.itertuples(index=False):
    log.info("%s", r)
write_csv(table, snakemake.output.table)
write_csv(summary, snakemake.output.summary)
