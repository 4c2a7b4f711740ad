"""Figures of the Batista (2011) stage; ``params.figure`` picks which."""

import pandas as pd
from _helpers import configure_logging
from batista2011_common import TABLES, standalone

from accelcal_repro.batista2011 import figures
from accelcal_repro.batista2011.experiment import changing_attitude, constant_attitude, design_from_config
from accelcal.plotting import save_figure

if "snakemake" not in globals():
    import sys

    fid = sys.argv[1] if len(sys.argv) > 1 else "batista2011_fig4"
    snakemake = standalone(f"{fid}_plot", input=TABLES,
                           output={"png": f"results/figures/{fid}.png", "pdf": f"results/figures/{fid}.pdf"},
                           figure=fid)

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
