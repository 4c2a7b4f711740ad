"""Claims of the Burkhard (2024) stage, computed from its summary tables."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.burkhard2024.claims import burkhard2024_claims
from accelcal_repro.burkhard2024.grid import experiments_from_config
from accelcal_repro.claims import verdict_counts

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("burkhard2024_claims")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
i = snakemake.input
rows = burkhard2024_claims(
    pd.read_csv(i.summary), pd.read_csv(i.comparisons), pd.read_csv(i.timing_summary), pd.read_csv(i.mc_timing_summary),
    experiments_from_config(cfg["experiments"]), cfg["claims"],
    interleave=cfg["timing"]["headline_interleave"], timing_n_poses=int(cfg["timing"]["headline_n_poses"]),
    summary_path=i.summary, comparisons_path=i.comparisons, timing_path=i.timing_summary,
)
for _, r in rows.iterrows():
    log.info("%s/%s: %s (%s)", r["paper"], r["claim_id"], r["verdict"], r["reproduced_value"])
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
