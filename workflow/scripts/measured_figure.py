"""Figures of the measured stage (one script; the figure id is a parameter)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake

from accelcal_repro.measured.figures import plot_calibration, plot_residuals, plot_static_detection
from accelcal.plotting import save_figure
from accelcal.recording import read_recording

if "snakemake" not in globals():
    import sys

    from measured_common import measured_config

    _fig = sys.argv[1] if len(sys.argv) > 1 else "measured_calibration"
    _recs = list(measured_config()["recordings"])
    snakemake = mock_snakemake(
        f"{_fig}_figure",
        input={"csv": [f"results/measured/{r}.csv" for r in _recs], "poses": "results/measured/poses.csv",
               "params": "results/measured/params.csv", "peer": ["results/measured/peer_imucal.csv"],
               "pose_errors": "results/measured/pose_errors.csv"},
        output={"png": f"results/figures/{_fig}.png", "pdf": f"results/figures/{_fig}.pdf"},
        params={"figure": _fig, "recordings": _recs})

log = configure_logging(snakemake)
fid = snakemake.params.figure
if fid == "measured_static_detection":
    recs = {}
    for name, path in zip(snakemake.params.recordings, snakemake.input.csv):
        r = read_recording(path)
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
