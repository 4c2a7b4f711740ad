"""Gather the per-recording tables of the measured stage into results/measured/<table>.csv."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.measured.calibrate import TABLES

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_tables")

log = configure_logging(snakemake)
for t in TABLES:
    files = list(getattr(snakemake.input, t))
    frames = [pd.read_csv(f) for f in files]
    frames = [f for f in frames if len(f)] or frames[:1]  # an empty table keeps its header
    df = pd.concat(frames, ignore_index=True)
    write_csv(df, getattr(snakemake.output, t))
    log.info("%s: %d rows from %d recording(s)", t, len(df), len(files))
