"""Benchmark: first-call time of the compiled kernels in fresh processes, with an empty
numba cache (compilation) and with the cache the first process wrote (loading)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.errors import AccelcalError
from accelcal_repro.first_calls import check_calls
from accelcal_repro.timing import compile_timing

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("timing_compile")

log = configure_logging(snakemake)
try:  # a config rule checked here, not while the Snakefile is parsed (no reproduction imported there)
    check_calls(snakemake.params.calls)
except AccelcalError as e:
    raise SystemExit(f"invalid config: {e}") from None
table = compile_timing(snakemake.params.calls)
if table.empty:
    log.warning("numba is not installed: nothing is compiled, the numpy implementations run")
log.info("first-call times [s]:\n%s", table.to_string())
write_csv(table, snakemake.output[0])
