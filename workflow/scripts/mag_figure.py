"""The mag stage's figure: |m| spread and dip spread per session and method."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.plotting import save_figure
from accelcal_repro.mag.stage import figure

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_spread_figure")

log = configure_logging(snakemake)
for path in save_figure(figure(pd.read_csv(snakemake.input.table)), snakemake.output.png):
    log.info("wrote %s", path)
