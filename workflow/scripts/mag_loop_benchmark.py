"""The magnetometer loop's benchmark: false positives and power at a multiple of the MDE."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.mag.loop_benchmark import run_benchmark

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_loop_benchmark")

log = configure_logging(snakemake)
p = snakemake.params.mag["loop"]
cases, summary = run_benchmark(n_null=p["n_null"], n_effect=p["n_effect"], multiple=p["multiple"],
                               seed=snakemake.params.mag["seed"], n_boot=p["n_boot"], alpha=p["alpha"])
for row in summary.itertuples():
    log.info("%s: FPR (anything) %.3f, this %.3f; power at %gx MDE %.2f", row.candidate, row.fpr_any, row.fpr_this,
             p["multiple"], row.power)
write_csv(cases, snakemake.output.cases)
write_csv(summary, snakemake.output.summary)
