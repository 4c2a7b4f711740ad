"""Claims of the foundation stage (Burkhard 2024), computed from its summary tables."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal.claims import burkhard_foundation_claims, verdict_counts

if "snakemake" not in globals():
    from _helpers import load_config

    _cfg = load_config()
    snakemake = mock_snakemake(
        "foundation_claims",
        input={"crlb_summary": "results/foundation/crlb_summary.csv",
               "timing_summary": "results/foundation/timing_summary.csv"},
        output=["results/claims/foundation.csv"],
        params={"claims": _cfg["claims"], "interleave": _cfg["foundation"]["timing"]["headline_interleave"]},
    )

log = configure_logging(snakemake)
c = snakemake.params.claims
rows = burkhard_foundation_claims(
    pd.read_csv(snakemake.input.crlb_summary),
    pd.read_csv(snakemake.input.timing_summary),
    speed_min_ratio=float(c["speed_min_ratio"]), equal_rel_tol=float(c["equal_rel_tol"]),
    interleave=snakemake.params.interleave,
    crlb_path=snakemake.input.crlb_summary, timing_path=snakemake.input.timing_summary,
)
for _, r in rows.iterrows():
    log.info("%s/%s: %s (%s)", r["paper"], r["claim_id"], r["verdict"], r["reproduced_value"])
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
