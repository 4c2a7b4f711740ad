"""Every real session: what is named, excess observed vs predicted, re-simulation gaps, evidence, stability."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.formats import read
from accelcal_repro.discrepancy import sessions as SS
from accelcal_repro.discrepancy.evidence import evidence_rows

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_sessions_tables")

log = configure_logging(snakemake)
p = snakemake.params
reports = {}
for name, path in zip(p.recordings, snakemake.input.reports):
    with open(path) as f:
        reports[name] = json.load(f)
named = [r for n, rep in reports.items() for r in SS.named_rows(n, rep)]
excess = [SS.excess_rows(n, rep) for n, rep in reports.items()]
for path in snakemake.input.few_poses:  # sessions of too few orientations for the loop
    with open(path) as f:
        few = json.load(f)
    named += few["named"]
    excess += few["excess"]
diagnostics = []
for name, path in zip(p.recordings, snakemake.input.csv):
    rec, _ = SS.with_disjoint_rests(read(path, strict=True))
    diagnostics.append(SS.diagnostics_row(name, rec, reports[name]))
evidence = [r for n, rep in reports.items() for r in evidence_rows(n, rep)]
estimates = pd.DataFrame([r for n, rep in reports.items() for r in SS.estimates_of(n, rep)])
# the yardstick: the rests' noise inflated by any excess (se), and for comparison the
# residual scatter alone (se_scaled, smaller where the residuals scatter less than the rests say)
stability = [SS.stability_rows(estimates[estimates.recording.isin(members)], p.alpha, se).assign(group=group,
                                                                                               yardstick=se)
             for group, members in p.same_imu.items() for se in ("se", "se_scaled")]
write_csv(pd.DataFrame(named), snakemake.output.named)
write_csv(pd.DataFrame(excess), snakemake.output.excess)
write_csv(pd.concat([pd.read_csv(g) for g in snakemake.input.gaps], ignore_index=True), snakemake.output.gaps)
write_csv(pd.DataFrame(evidence), snakemake.output.evidence)
write_csv(pd.DataFrame(diagnostics), snakemake.output.diagnostics)
write_csv(estimates, snakemake.output.estimates)
write_csv(pd.concat(stability, ignore_index=True) if stability else pd.DataFrame(columns=["group", "parameter"]),
          snakemake.output.stability)
for r in excess:
    log.info("%s: excess observed %s, predicted %s, explained %s", r["recording"], r["excess_observed"],
             r["excess_predicted"], r["explained"])
