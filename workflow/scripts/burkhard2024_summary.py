"""Gather the Burkhard grid points: tidy table, summaries, paired comparisons, relative
errors across the noise range, the LLS limit, the estimators' RMS / CRLB with the NLLS
iteration counts, and the Monte Carlo wall times."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.burkhard2024.analysis import efficiency, limit_onsets, lls_limit, relative_errors
from accelcal_repro.burkhard2024.grid import experiments_from_config
from accelcal_repro.montecarlo import CASE_KEYS, compare_methods, summarize, summarize_mc_timing

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("burkhard2024_summary")

log = configure_logging(snakemake)
p = snakemake.params
out = snakemake.output
exps = experiments_from_config(p.experiments)
df = pd.concat([pd.read_csv(f) for f in snakemake.input.tables], ignore_index=True)
df = df.sort_values(CASE_KEYS + ["method", "trial"], kind="stable", ignore_index=True)
summary = summarize(df)
comparisons = compare_methods(df)
rel = relative_errors(df, exps["fig1a"], p.paper_noise_range)
limit = lls_limit(summary, comparisons, [exps["fig1a"], exps["lls_limit"], exps["efficiency"]], float(p.z),
                  float(p.min_effect))
onsets = limit_onsets(limit)
eff = efficiency(summary, [exps["fig1a"], exps["efficiency"]], float(p.g))
timing = pd.concat([pd.read_csv(f) for f in snakemake.input.timings], ignore_index=True)
timing = timing.sort_values(CASE_KEYS + ["method"], kind="stable", ignore_index=True)
with pd.option_context("display.width", 220, "display.max_columns", 30, "display.float_format", "{:.4g}".format):
    log.info("relative errors across the noise range:\n%s", rel)
    log.info("where LLS leaves NLLS and the CRLB:\n%s", onsets)
    log.info("RMS error / CRLB and NLLS iterations:\n%s", eff)
    log.info("Monte Carlo wall time per trial:\n%s", summarize_mc_timing(timing))
write_csv(df, out.table, float_format="%.10g")
write_csv(summary, out.summary)
write_csv(comparisons, out.comparisons)
write_csv(rel, out.relative_errors)
write_csv(limit, out.limit)
write_csv(onsets, out.onsets)
write_csv(eff, out.efficiency)
write_csv(timing, out.mc_timing)
write_csv(summarize_mc_timing(timing), out.mc_timing_summary)
