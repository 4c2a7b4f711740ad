"""Figures of the measured stage (one script; the figure id is a parameter)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.measured.figures import plot_calibration, plot_residuals, plot_static_detection
from accelcal.plotting import save_figure
from accelcal.formats import read

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_calibration_figure")

log = configure_logging(snakemake)
fid = snakemake.params.figure
if fid == "measured_static_detection":
    recs = {}
    for name, path in zip(snakemake.params.recordings, snakemake.input.csv):
        r = read(path, strict=True)
        recs[name] = (r.t, r.acc)
    fig = plot_static_detection(recs, pd.read_csv(snakemake.input.poses))
elif fid == "measured_calibration":
    peer = list(snakemake.input.peer)
    fig = plot_calibration(pd.read_csv(snakemake.input.params), pd.read_csv(peer[0]) if peer else None)
elif fid == "measured_residuals":
    fig = plot_residuals(pd.read_csv(snakemake.input.pose_errors))
else:
    raise ValueError(f"unknown figure id {fid!r}")
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
