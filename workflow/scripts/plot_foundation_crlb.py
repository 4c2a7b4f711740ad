"""Figure foundation_crlb: RMS bias error vs noise against the CRLB, and their ratio."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake

from accelcal.plotting import plot_crlb, save_figure

if "snakemake" not in globals():
    from _helpers import load_config

    snakemake = mock_snakemake(
        "foundation_crlb_figure",
        input={"summary": "results/foundation/crlb_summary.csv"},
        output={"png": "results/figures/foundation_crlb.png", "pdf": "results/figures/foundation_crlb.pdf"},
        params={"methods": load_config()["foundation"]["crlb"]["methods"]},
    )

log = configure_logging(snakemake)
fig = plot_crlb(pd.read_csv(snakemake.input.summary), snakemake.params.methods)
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
