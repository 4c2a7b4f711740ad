"""Monte Carlo of the one-step and the iterative gyro estimate against the Cramér–Rao bound."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.stage import monte_carlo_summary, monte_carlo_tables

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_montecarlo")

log = configure_logging(snakemake)
table, timing = monte_carlo_tables(snakemake.params.gyro)
summary = monte_carlo_summary(table)
for r in summary.itertuples(index=False):
    log.info("%s", r)
write_csv(table, snakemake.output.table)
write_csv(summary, snakemake.output.summary)
write_csv(timing, snakemake.output.timing)
