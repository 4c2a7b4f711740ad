"""Figures of the Burkhard stage (``snakemake.params.figures``: any of fig1a ... fig1e,
lls_limit, timing); output ``<figure>_png`` / ``<figure>_pdf`` for each."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.burkhard2024 import figures
from accelcal_repro.burkhard2024.grid import experiments_from_config
from accelcal.plotting import save_figure

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("burkhard2024_figures")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
i = snakemake.input
exps = experiments_from_config(cfg["experiments"])
tables = {}


def table(name):
    if name not in tables:
        tables[name] = pd.read_csv(getattr(i, name))
    return tables[name]


def draw(which):
    if which == "timing":
        t = cfg["timing"]
        return figures.plot_timing(table("timing_summary"), table("mc_timing"), t["headline_interleave"],
                                   int(t["headline_n_poses"]))
    if which == "lls_limit":
        return figures.plot_lls_limit(table("limit"), table("onsets"))
    if which == "fig1a":
        return figures.plot_fig1a(table("summary"), exps["fig1a"], exps["efficiency"])
    if which == "fig1b":
        return figures.plot_fig1b(table("summary"), exps["fig1b"])
    if which == "fig1c":
        return figures.plot_fig1c(table("summary"), exps["fig1cd"], "(c)", "M ≠ I")
    if which == "fig1d":
        return figures.plot_fig1d(table("summary"), exps["fig1cd"], float(cfg["g"]))
    if which == "fig1e":
        return figures.plot_fig1c(table("summary"), exps["fig1e"], "(e)", "M = I")
    raise SystemExit(f"unknown Burkhard figure {which!r}")


for which in snakemake.params.figures:
    for path in save_figure(draw(which), getattr(snakemake.output, f"{which}_png")):
        log.info("wrote %s", path)
