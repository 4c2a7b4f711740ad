"""Claims of Batista et al. (2011), computed from the stage's result tables."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.claims import batista_claims
from accelcal_repro.claims import verdict_counts

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_claims")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
inp = snakemake.input
f = cfg["filter"]
rows = batista_claims(
    pd.read_csv(inp.summary), pd.read_csv(inp.filter_summary), pd.read_csv(inp.filter_runs),
    pd.read_csv(inp.observability), pd.read_csv(inp.gramian),
    bias=f["bias"], noise_acc=float(f["noise"]["accel"]), steady_from_s=float(f["steady_from_s"]),
    error_budget=pd.read_csv(inp.error_budget), rules=cfg["claims"],
    sources={"calibration": inp.summary, "filter": inp.filter_summary, "filter_runs": inp.filter_runs,
             "observability": inp.observability, "gramian": inp.gramian},
    observability_runs=int(cfg["observability"]["runs"]),
)
for _, r in rows.iterrows():
    log.info("%s: %s (%s)", r["claim_id"], r["verdict"], r["reproduced_value"])
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
