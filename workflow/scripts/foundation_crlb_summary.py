"""Gather the per-noise Monte Carlo tables; summarise RMS errors against the CRLB."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal.montecarlo import summarize_crlb

if "snakemake" not in globals():
    import glob

    snakemake = mock_snakemake(
        "foundation_crlb_summary",
        input=sorted(glob.glob("results/foundation/crlb_mc/noise_*.csv")),
        output={"table": "results/foundation/crlb_mc.csv", "summary": "results/foundation/crlb_summary.csv"},
    )

log = configure_logging(snakemake)
df = pd.concat([pd.read_csv(f) for f in snakemake.input], ignore_index=True)
df = df.sort_values(["noise_std", "method", "trial"], kind="stable", ignore_index=True)
summary = summarize_crlb(df)
with pd.option_context("display.width", 200, "display.max_columns", 20):
    log.info("RMS / CRLB:\n%s", summary.pivot_table(index="noise_std", columns="method", values="bias_ratio"))
write_csv(df, snakemake.output.table)
write_csv(summary, snakemake.output.summary)
