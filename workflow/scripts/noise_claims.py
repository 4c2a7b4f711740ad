"""Claims-ledger rows of the noise stage: the ADIS16405 datasheet's figures and the intervals' coverage."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import verdict_counts
from accelcal_repro.noise.claims import noise_claims

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("noise_claims")

log = configure_logging(snakemake)
c = snakemake.params.claims
rows = noise_claims(pd.read_csv(snakemake.input.datasheet), pd.read_csv(snakemake.input.coverage),
                    factor=c["datasheet_factor"], floor=c["coverage_floor"], level=snakemake.params.level)
for r in rows.itertuples():
    log.info("%s/%s: %s (%s)", r.paper, r.claim_id, r.verdict, r.reproduced_value)
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
