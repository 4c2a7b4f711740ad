"""Every real magnetometer session through the magnetometer's discrepancy loop."""

import pandas as pd
from _helpers import configure_logging, dataset_dirs, mock_snakemake_from_argv, write_csv

from accelcal_repro.mag.stage import loop_rows

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_loop_sessions")

log = configure_logging(snakemake)
dirs = dataset_dirs(snakemake.input.manifests)
p = snakemake.params.mag["loop"]
rows = []
for name in snakemake.params.mag["sessions"]:
    r = loop_rows(name, dirs, alpha=p["alpha"], n_boot=p["n_boot"], seed=snakemake.params.mag["seed"])
    rows += r
    log.info("%s: named %s", name, r[0]["named"] if r else "-")
write_csv(pd.DataFrame(rows), snakemake.output[0])
