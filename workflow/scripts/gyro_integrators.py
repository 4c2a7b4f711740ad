"""The integrator study: scale-factor bias vs rotation rate and sample rate, per method."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.integrators import choose
from accelcal_repro.gyro.stage import integrator_table

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_integrators")

log = configure_logging(snakemake)
table = integrator_table(snakemake.params.gyro)
log.info("smallest median angle error at hand-motion rates: %s", choose(table))
write_csv(table, snakemake.output[0])
