"""Figures of the Batista (2011) stage, drawn in one job (common.smk's stage_figures)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, stage_figures

from accelcal_repro.batista2011 import figures
from accelcal_repro.batista2011.experiment import changing_attitude, constant_attitude, design_from_config
from accelcal.plotting import save_figure

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_figures")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
noise = float(cfg["filter"]["noise"]["accel"])


def draw(fid, inp):
    def read(name):
        return pd.read_csv(getattr(inp, name))

    if fid == "batista2011_trajectories":
        return figures.plot_trajectories(design_from_config(cfg), changing_attitude(cfg), constant_attitude(cfg))
    if fid == "batista2011_calibration":
        c = cfg["claims"]
        return figures.plot_calibration(read("summary"), read("comparison"), float(c["mean_threshold"]),
                                        float(c["std_threshold"]))
    if fid == "batista2011_fig4":
        return figures.plot_estimates(read("filter_example"), "g", "Gravity estimate in body coordinates (cf. Fig. 4)")
    if fid == "batista2011_fig5":
        return figures.plot_estimates(read("filter_example"), "b", "Bias estimate (cf. Fig. 5), ± filter σ shaded",
                                      sigma=True)
    if fid == "batista2011_errors":
        return figures.plot_errors(read("filter_summary"), noise, cost=read("filter_cost"))
    if fid == "batista2011_observability":
        return figures.plot_observability(read("observability"), read("gramian"),
                                          str(cfg["observability"]["axis_body"]))
    raise ValueError(f"unknown figure id {fid!r}")


for fid, inp, out in stage_figures(snakemake):
    for path in save_figure(draw(fid, inp), out.png):
        log.info("wrote %s", path)
