"""Figures of the Burkhard stage (``snakemake.params.figures``: any of fig1a ... fig1e,
lls_limit, timing); output ``<figure>_png`` / ``<figure>_pdf`` for each."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake

from accelcal_repro.burkhard2024 import figures
from accelcal_repro.burkhard2024.grid import experiments_from_config
from accelcal.plotting import save_figure

if "snakemake" not in globals():
    import sys

    from _helpers import stage_config

    _figs = sys.argv[1:] or ["fig1a", "fig1b", "fig1c", "fig1d", "fig1e", "lls_limit", "timing"]
    _d = "results/burkhard2024"
    snakemake = mock_snakemake(
        "burkhard2024_figures",
        input={"summary": f"{_d}/summary.csv", "limit": f"{_d}/lls_limit.csv", "onsets": f"{_d}/lls_limit_onsets.csv",
               "timing_summary": f"{_d}/timing_summary.csv", "mc_timing": f"{_d}/mc_timing_summary.csv"},
        output={f"{f}_{ext}": f"results/figures/burkhard2024_{f}.{ext}" for f in _figs for ext in ("png", "pdf")},
        params={"figures": _figs, "cfg": stage_config("burkhard2024")})

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
