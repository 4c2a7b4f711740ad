"""Summaries of the Tereshkov Monte Carlo tables: convergence times, steady-state errors,
the artificial-bias test, the installation sweep, and the wall times of the jobs."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.montecarlo import artificial_summary, convergence_summary, sweep_summary

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_summary")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
mc = cfg["monte_carlo"]
ss, frac, nonconv = float(mc["steady_state_from_s"]), float(mc["convergence_fraction"]), float(mc["nonconvergence_ratio"])
main = pd.concat([pd.read_csv(snakemake.input.field), pd.read_csv(snakemake.input.straight)], ignore_index=True)
summary = convergence_summary(main, ss, frac, nonconv)
log.info("convergence summary:\n%s", summary.to_string())
art = artificial_summary(pd.read_csv(snakemake.input.artificial), ss)
log.info("artificial-bias test:\n%s", art.to_string())
sw = sweep_summary(pd.read_csv(snakemake.input.sweep), float(cfg["sweep"]["steady_state_from_s"]), frac, nonconv)
log.info("installation sweep:\n%s", sw[["reference", "kind", "angle_deg", "sensor", "ss_rms", "t_conv"]].to_string())
timing = pd.concat([pd.read_csv(p) for p in snakemake.input.timings], ignore_index=True)
timing["us_per_step"] = 1e6 * timing["estimator_s"] / timing["steps"]
timing["us_per_run_step"] = timing["us_per_step"] / timing["runs"]
write_csv(summary, snakemake.output.summary)
write_csv(art, snakemake.output.artificial)
write_csv(sw, snakemake.output.sweep)
write_csv(timing, snakemake.output.timing)
