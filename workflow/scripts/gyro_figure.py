"""Figures of the gyro stage (one script; the figure id is a parameter)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.plotting import save_figure
from accelcal_repro.gyro import integrators, montecarlo, report

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_integrator_bias_figure")

log = configure_logging(snakemake)
fid = snakemake.params.figure
table = pd.read_csv(snakemake.input.table)
if fid == "gyro_integrator_bias":
    fig = integrators.figure(table)
elif fid == "gyro_crlb":
    fig = montecarlo.figure(table)
elif fid == "gyro_figure_of_merit":
    try:
        imucal = pd.read_csv(snakemake.input.imucal)
    except pd.errors.EmptyDataError:  # imucal's session not configured
        imucal = None
    fig = report.figure(table, imucal)
else:
    raise ValueError(f"unknown figure id {fid!r}")
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
