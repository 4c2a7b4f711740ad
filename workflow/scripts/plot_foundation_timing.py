"""Figure foundation_timing: per-problem time of LLS vs NLLS, batched LLS, speed-ups."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake

from accelcal.plotting import plot_timing, save_figure

if "snakemake" not in globals():
    from _helpers import load_config

    snakemake = mock_snakemake(
        "foundation_timing_figure",
        input={"single": "results/foundation/timing.csv", "summary": "results/foundation/timing_summary.csv"},
        output={"png": "results/figures/foundation_timing.png", "pdf": "results/figures/foundation_timing.pdf"},
        params={"interleave": load_config()["foundation"]["timing"]["headline_interleave"]},
    )

log = configure_logging(snakemake)
summary = pd.read_csv(snakemake.input.summary)
fig = plot_timing(pd.read_csv(snakemake.input.single), summary, snakemake.params.interleave)
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
