"""Fill the project's numba disk cache before the jobs that call compiled kernels start, and
time the kernels' first calls (accelcal_repro.timing.kernel_cache_and_compile_timing: one
compilation, in a fresh process with an empty cache, copied into the project's)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.errors import AccelcalError
from accelcal_repro.first_calls import check_calls
from accelcal_repro.timing import kernel_cache_and_compile_timing

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("kernel_cache")

log = configure_logging(snakemake)
try:  # a config rule checked here, not while the Snakefile is parsed (no reproduction imported there)
    check_calls(snakemake.params.calls)
except AccelcalError as e:
    raise SystemExit(f"invalid config: {e}") from None
cache, timing = kernel_cache_and_compile_timing(snakemake.params.calls)
if cache.empty:
    log.warning("numba is not installed: nothing is compiled, the numpy implementations run")
log.info("first calls filling the cache, compiled or loaded [s]:\n%s", cache.to_string())
log.info("first-call times, empty and filled cache [s]:\n%s", timing.to_string())
write_csv(cache, snakemake.output.cache)
write_csv(timing, snakemake.output.compile)
