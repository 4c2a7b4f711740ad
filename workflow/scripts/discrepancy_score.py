"""Benchmark scoring: join detections and key; rates per null, profile, row and size; summary; headline;
the loop against the oracle."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.discrepancy.scoring import headline, oracle_differences, rates, score_cases, summary

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_score")

log = configure_logging(snakemake)
key = pd.concat([pd.read_csv(f) for f in snakemake.input.key], ignore_index=True)
# the named outliers' times as written ('a;b'; read as numbers, a chunk with one per recording
# would come back as floats and another as strings)
det = pd.concat([pd.read_csv(f, keep_default_na=False, na_values=[""],
                             dtype={"outlier_t_detected": str, "outlier_poses_detected": str, "named_set": str})
                 for f in snakemake.input.detections], ignore_index=True)
# Plan order (the key's chunks interleave the plan): sort by recording and null for a stable table.
scores = score_cases(key, det).sort_values(["recording", "null"], kind="stable").reset_index(drop=True)
rules = snakemake.params.rules
rate_table = rates(scores)
summ = summary(scores, rate_table, alpha=rules["alpha"], power=rules["power"])
write_csv(scores, snakemake.output.scores)
write_csv(rate_table, snakemake.output.rates)
write_csv(summ, snakemake.output.summary)
write_csv(headline(summ, snakemake.params.profiles), snakemake.output.headline)
write_csv(oracle_differences(scores), snakemake.output.oracle)
for r in summ[summ.metric.isin(["false_positive_rate", "oracle_agreement"])].itertuples():
    log.info("%s null, %s: %s %.3f [%.3f, %.3f] (n %d, independent %d) %s", r.null, r.profile, r.metric,
             r.value, r.ci_low, r.ci_high, r.n, r.n_independent, r.verdict)
