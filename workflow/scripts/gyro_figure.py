"""Figures of the gyro stage, drawn in one job (common.smk's stage_figures)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, stage_figures

from accelcal.plotting import save_figure
from accelcal_repro.gyro import integrators, montecarlo, report

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_figures")

log = configure_logging(snakemake)


def draw(fid, inp):
    table = pd.read_csv(inp.table)
    if fid == "gyro_integrator_bias":
        return integrators.figure(table)
    if fid == "gyro_crlb":
        return montecarlo.figure(table)
    if fid == "gyro_figure_of_merit":
        try:
            imucal = pd.read_csv(inp.imucal)
        except pd.errors.EmptyDataError:  # imucal's session not configured
            imucal = None
        return report.figure(table, imucal)
    raise ValueError(f"unknown figure id {fid!r}")


for fid, inp, out in stage_figures(snakemake):
    for path in save_figure(draw(fid, inp), out.png):
        log.info("wrote %s", path)
