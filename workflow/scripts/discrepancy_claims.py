"""Claims-ledger rows of the discrepancy stage: the loop's goals on the benchmark and the ADIS reference."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import verdict_counts
from accelcal_repro.discrepancy.benchmark import null_available
from accelcal_repro.discrepancy.claims import discrepancy_claims

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_claims")

log = configure_logging(snakemake)
p = snakemake.params
rows = discrepancy_claims(pd.read_csv(snakemake.input.summary, keep_default_na=False, na_values=[""]),
                          pd.read_csv(snakemake.input.profiles), pd.read_csv(snakemake.input.adis),
                          alpha=p.rules["alpha"], power=p.rules["power"],
                          nulls=[n for n, rows in p.nulls.items() if rows != "none" and null_available(n)],
                          stability=pd.read_csv(snakemake.input.stability),
                          excess=pd.read_csv(snakemake.input.excess), gaps=pd.read_csv(snakemake.input.gaps),
                          layer_n_boot=int(snakemake.config["discrepancy"]["adis"]["n_boot"]))
for r in rows.itertuples():
    log.info("%s/%s: %s (%s)", r.paper, r.claim_id, r.verdict, r.reproduced_value)
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
