"""Tereshkov vs the Batista (2011) Kalman filter on the same simulated runs: tidy table of
bias estimates and a summary with convergence, steady-state error and cost per step."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.comparison import comparison_summary, run_comparison

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_comparison")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
table, cost = run_comparison(cfg, dict(snakemake.params.batista))
mc, cmp = cfg["monte_carlo"], cfg.get("comparison", {})
ss = float(cmp.get("steady_state_from_s", float(cmp.get("duration_s", 900)) / 2))
summary = comparison_summary(table, cost, ss, float(mc["convergence_fraction"]), float(mc["nonconvergence_ratio"]))
log.info("comparison:\n%s", summary[["method", "sensor", "t_conv", "ss_rms", "final_ratio", "us_per_step_single_run",
                                     "us_per_run_step_batched"]].to_string())
write_csv(table, snakemake.output.table)
write_csv(summary, snakemake.output.summary)
