"""Benchmark: cost per step of the Batista filter and of Tereshkov's estimator, with the
compiled kernels and with the numpy reference implementations."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_cost, stream
from accelcal_repro.timing import filter_timing, tereshkov_inputs

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("timing_filters")

log = configure_logging(snakemake)
p = snakemake.params
b, tm = p.batista, p.batista["filter"]["timing"]
scenario = scenario_from_config(b, "changing")


def batista_cost(steps=None):
    return filter_cost(scenario, stream(b["seed"], "timing"), **filter_kwargs(b), steps=int(steps or tm["steps"]),
                       runs=int(tm["runs"]), repeat=int(tm["repeat"]))


data = tereshkov_inputs(p.tereshkov, int(p.bench["runs"]), float(p.bench["duration_s"]))
table = filter_timing(batista_cost, data, repeat=int(p.bench["repeat"]))
with pd.option_context("display.width", 200, "display.max_columns", 20, "display.float_format", "{:.4g}".format):
    log.info("filter cost per step (wall times are machine-dependent; recorded, not asserted):\n%s", table)
write_csv(table, snakemake.output[0])
