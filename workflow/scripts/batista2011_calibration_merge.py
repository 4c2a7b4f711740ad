"""Table I Monte Carlo: the chunks merged, the CRLB, the summaries."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import design_from_config
from accelcal_repro.batista2011.montecarlo import calibration_bounds, calibration_summary, lls_comparison

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_calibration_merge")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
# one order whatever the number of chunks: data set, method, run (parameters keep theirs)
errors = (pd.concat([pd.read_csv(p) for p in snakemake.input.chunks], ignore_index=True)
          .sort_values(["data", "method", "run"], kind="stable", ignore_index=True))
runs = errors["run"].nunique()
if runs != int(cfg["calibration"]["runs"]) or errors["run"].max() != runs - 1:
    raise SystemExit(f"batista2011: the chunks hold {runs} runs, the config asks for {cfg['calibration']['runs']}")
bounds = calibration_bounds(design_from_config(cfg))
summary = calibration_summary(errors, bounds)
comparison = lls_comparison(errors)
bad = errors.groupby(["data", "method"])["converged"].apply(lambda s: int((~s).sum()))
log.info("%d runs from %d chunks; non-converged (or invalid) rows per data/method: %s", runs,
         len(snakemake.input.chunks), bad.to_dict())
write_csv(errors, snakemake.output.errors, float_format="%.10g")
write_csv(bounds, snakemake.output.bounds)
write_csv(summary, snakemake.output.summary)
write_csv(comparison, snakemake.output.comparison)
log.info("comparison:\n%s", comparison.to_string())
