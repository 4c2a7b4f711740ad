"""Gather the per-recording tables of the measured stage into results/measured/<table>.csv."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal_repro.measured.calibrate import TABLES

if "snakemake" not in globals():
    from measured_common import measured_config

    _recs = list(measured_config()["recordings"])
    snakemake = mock_snakemake("measured_tables",
                               input={t: [f"results/measured/{r}/{t}.csv" for r in _recs] for t in TABLES},
                               output={t: f"results/measured/{t}.csv" for t in TABLES})

log = configure_logging(snakemake)
for t in TABLES:
    files = list(getattr(snakemake.input, t))
    frames = [pd.read_csv(f) for f in files]
    frames = [f for f in frames if len(f)] or frames[:1]  # an empty table keeps its header
    df = pd.concat(frames, ignore_index=True)
    write_csv(df, getattr(snakemake.output, t))
    log.info("%s: %d rows from %d recording(s)", t, len(df), len(files))
