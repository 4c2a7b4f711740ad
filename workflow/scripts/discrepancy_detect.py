"""Benchmark chunk: the discrepancy loop on every recording of the chunk (never reads the key)."""

from pathlib import Path

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.discrepancy.benchmark import detect_case
from accelcal.discrepancy.detect import Rules
from accelcal.errors import AccelcalError
from accelcal.recording import read_recording

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_detect", chunk="0")

log = configure_logging(snakemake)
rules = Rules.from_config(snakemake.params.rules)
paths = sorted(Path(snakemake.input.recordings).glob("*.csv"))
rows = []
for path in paths:
    try:
        rec = read_recording(path)
    except AccelcalError as e:
        rows.append({"recording": path.stem, "outcome": "error", "error": str(e).splitlines()[0]})
        continue
    rows.append({"recording": path.stem, **detect_case(rec, snakemake.params.g, rules)})
df = pd.DataFrame(rows)
write_csv(df, snakemake.output[0])
log.info("%d recordings: %s", len(df), df["outcome"].value_counts().to_dict() if len(df) else {})
