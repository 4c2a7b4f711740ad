"""Claims-ledger rows of the measured stage: the papers' real-data results."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import verdict_counts
from accelcal_repro.measured.claims import measured_claims

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_claims")

log = configure_logging(snakemake)
peer = list(snakemake.input.peer)
rows = measured_claims(pd.read_csv(snakemake.input.summary), pd.read_csv(snakemake.input.params),
                       pd.read_csv(snakemake.input.nominal), pd.read_csv(peer[0]) if peer else None)
for r in rows.itertuples():
    log.info("%s/%s: %s", r.paper, r.claim_id, r.verdict)
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
