"""Torque change caused by a known accelerometer-bias shift, straight motion vs turns."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.montecarlo import observability_table

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_observability")

log = configure_logging(snakemake)
df, timing = observability_table(snakemake.params.cfg)
means = df.groupby("mode")[["du_rms_dps", "predicted_rms_dps", "sensitivity"]].mean()
log.info("torque change per mode (means over runs):\n%s", means.to_string())
log.info("%d pairs x %d steps in %.1f s", timing["runs"] // 2, timing["steps"], timing["wall_s"])
write_csv(df, snakemake.output.table)
write_csv(pd.DataFrame([timing]), snakemake.output.timing)
