"""The gyro loop's benchmark: false-positive rate and power per candidate at multiples of its MDE."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.loop_benchmark import benchmark_tables

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_loop_benchmark")

log = configure_logging(snakemake)
cases, summary = benchmark_tables(snakemake.params.gyro)
for r in summary.itertuples(index=False):
    log.info("%s x%g: power %.2f (MDE %.3g); FPR %.3f [%.3f, %.3f] of %d", r.candidate, r.multiple, r.power, r.mde,
             r.fpr_any, r.fpr_lo, r.fpr_hi, r.n_null)
write_csv(cases, snakemake.output.cases)
write_csv(summary, snakemake.output.summary)
