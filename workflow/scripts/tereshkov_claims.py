"""Claims of the Tereshkov stage, computed from its summary tables."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import verdict_counts
from accelcal_repro.tereshkov.claims import tereshkov_claims

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_claims")

log = configure_logging(snakemake)
i = snakemake.input
rows = tereshkov_claims(pd.read_csv(i.summary), pd.read_csv(i.observability), pd.read_csv(i.artificial),
                        pd.read_csv(i.sweep), dict(snakemake.params.rules), summary_path=i.summary,
                        observability_path=i.observability, artificial_path=i.artificial, sweep_path=i.sweep,
                        artificial_runs=int(snakemake.config["tereshkov"]["scenarios"]["artificial"]["runs"]))
for _, r in rows.iterrows():
    log.info("%s/%s: %s (%s)", r["paper"], r["claim_id"], r["verdict"], r["reproduced_value"])
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
