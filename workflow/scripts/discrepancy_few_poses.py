"""A session of too few orientations for the loop: what can be tested (the rests' noise terms, the
bias-only fits' excess) and what cannot, with the reason."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.atomic import write_json_atomic
from accelcal.discrepancy.report import StochasticSettings
from accelcal.formats import read
from accelcal.jsonsafe import json_safe
from accelcal_repro.discrepancy import sessions as SS

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_few_poses", recording="imucal_ferraris")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
named, excess = SS.few_poses_rows(name, read(snakemake.input.csv, strict=True),
                                  pd.read_csv(snakemake.input.measured_summary),
                                  StochasticSettings.from_config(snakemake.params.stochastic))
write_json_atomic(snakemake.output[0], json_safe({"recording": name, "named": named, "excess": excess}))
for r in named:
    log.info("%s: %s %s: %s", name, r["layer"], r["item"], r["value"])
