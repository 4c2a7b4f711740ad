"""The Gauss-Newton gyro fit against CasADi/IPOPT on the same cost (result and, apart, wall times)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.stage import ipopt_table

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_ipopt")

log = configure_logging(snakemake)
table, timing = ipopt_table(snakemake.params.gyro)
log.info("largest difference %.3g standard errors (%s)", table.max_diff_in_se.iloc[0], table.ipopt_status.iloc[0])
write_csv(table, snakemake.output.table)
write_csv(timing, snakemake.output.timing)
