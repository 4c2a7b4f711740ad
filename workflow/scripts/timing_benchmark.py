"""Benchmark: the headline table (with the project's goals) and the figure of where the
compute time goes."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.plotting import save_figure
from accelcal_repro.cost import headline, plot_cost

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("timing_benchmark_figure")

log = configure_logging(snakemake)
i, p = snakemake.input, snakemake.params
tables = {k: pd.read_csv(getattr(i, k)) for k in ("estimators", "filters", "compile", "stages")}
summary = headline(tables["estimators"], tables["filters"], tables["compile"], tables["stages"], p.goals,
                   n_poses=int(p.n_poses), interleave=p.interleave)
with pd.option_context("display.width", 200, "display.max_columns", 20, "display.float_format", "{:.4g}".format):
    log.info("where the compute time goes:\n%s", summary)
write_csv(summary, snakemake.output.summary)
save_figure(plot_cost(tables["estimators"], tables["filters"], tables["compile"], tables["stages"],
                      interleave=p.interleave), snakemake.output.png)
