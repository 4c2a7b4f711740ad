"""Fill the project's numba disk cache before the jobs that call compiled kernels start:
every first call once, in a fresh process (accelcal_repro.timing.fill_kernel_cache)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.timing import fill_kernel_cache

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("kernel_cache")

log = configure_logging(snakemake)
table = fill_kernel_cache()
if table.empty:
    log.warning("numba is not installed: nothing is compiled, the numpy implementations run")
log.info("first calls, compiled or loaded from the disk cache [s]:\n%s", table.to_string())
write_csv(table, snakemake.output[0])
