"""Figures of the Batista (2011) stage; ``params.figure`` picks which."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.batista2011 import figures
from accelcal_repro.batista2011.experiment import changing_attitude, constant_attitude, design_from_config
from accelcal.plotting import save_figure

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_fig4_plot")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
fid = snakemake.params.figure
inp = snakemake.input


def read(name):
    return pd.read_csv(getattr(inp, name))


noise = float(cfg["filter"]["noise"]["accel"])
if fid == "batista2011_trajectories":
    fig = figures.plot_trajectories(design_from_config(cfg), changing_attitude(cfg), constant_attitude(cfg))
elif fid == "batista2011_calibration":
    c = cfg["claims"]
    fig = figures.plot_calibration(read("summary"), read("comparison"), float(c["mean_threshold"]),
                                   float(c["std_threshold"]))
elif fid == "batista2011_fig4":
    fig = figures.plot_estimates(read("filter_example"), "g", "Gravity estimate in body coordinates (cf. Fig. 4)")
elif fid == "batista2011_fig5":
    fig = figures.plot_estimates(read("filter_example"), "b", "Bias estimate (cf. Fig. 5), ± filter σ shaded",
                                 sigma=True)
elif fid == "batista2011_errors":
    fig = figures.plot_errors(read("filter_summary"), noise, cost=read("filter_cost"))
elif fid == "batista2011_observability":
    fig = figures.plot_observability(read("observability"), read("gramian"), str(cfg["observability"]["axis_body"]))
else:
    raise ValueError(f"unknown figure id {fid!r}")
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
