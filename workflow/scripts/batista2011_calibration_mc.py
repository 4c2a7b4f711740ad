"""Table I Monte Carlo (with the linear-only variant and the full LLS), the CRLB, summaries."""

import time

from _helpers import configure_logging
from batista2011_common import TABLES, standalone, write_table

from accelcal.batista.experiment import design_from_config
from accelcal.batista.montecarlo import (calibration_bounds, calibration_montecarlo, calibration_summary,
                                         lls_comparison, stream)

if "snakemake" not in globals():
    snakemake = standalone("batista2011_calibration_mc",
                           output={k: TABLES[k] for k in ("errors", "bounds", "summary", "comparison")})

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
c = cfg["calibration"]
design = design_from_config(cfg)
log.info("design: %d steps x %d samples, Tg = %s", len(design.euler), design.schedule.samples_per_window,
         design.g_table.round(4).tolist())
t0 = time.perf_counter()
errors = calibration_montecarlo(design, int(c["runs"]), stream(cfg["seed"], "calibration"), tol=float(c["tol"]),
                                max_iter=int(c["max_iter"]), chunk=int(c["chunk"]))
log.info("%d runs in %.1f s", int(c["runs"]), time.perf_counter() - t0)
bounds = calibration_bounds(design)
summary = calibration_summary(errors, bounds)
comparison = lls_comparison(errors)
bad = errors.groupby(["data", "method"])["converged"].apply(lambda s: int((~s).sum()))
log.info("non-converged (or invalid) rows per data/method: %s", bad.to_dict())
write_table(errors, snakemake.output.errors, float_format="%.10g")
write_table(bounds, snakemake.output.bounds)
write_table(summary, snakemake.output.summary)
write_table(comparison, snakemake.output.comparison)
log.info("comparison:\n%s", comparison.to_string())
