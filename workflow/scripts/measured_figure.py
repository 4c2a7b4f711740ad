"""Figures of the measured stage, drawn in one job (common.smk's stage_figures)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, stage_figures

from accelcal_repro.measured.figures import plot_calibration, plot_residuals, plot_static_detection
from accelcal.plotting import save_figure
from accelcal.formats import read

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_figures")

log = configure_logging(snakemake)


def draw(fid, inp):
    if fid == "measured_static_detection":
        recs = {}
        for name, path in zip(snakemake.params.recordings, inp.csv):
            r = read(path, strict=True)
            recs[name] = (r.t, r.acc)
        return plot_static_detection(recs, pd.read_csv(inp.poses))
    if fid == "measured_calibration":
        peer = list(inp.peer)
        return plot_calibration(pd.read_csv(inp.params), pd.read_csv(peer[0]) if peer else None)
    if fid == "measured_residuals":
        return plot_residuals(pd.read_csv(inp.pose_errors))
    raise ValueError(f"unknown figure id {fid!r}")


for fid, inp, out in stage_figures(snakemake):
    for path in save_figure(draw(fid, inp), out.png):
        log.info("wrote %s", path)
