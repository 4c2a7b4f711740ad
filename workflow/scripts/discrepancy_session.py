"""One real session re-simulated before and after what the loop named; the gap to the measured residuals."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.formats import read
from accelcal_repro.discrepancy import sessions as SS

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_session", recording="xsens_mti")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
cfg = snakemake.params.sessions
with open(snakemake.input.report) as f:
    report = json.load(f)
rec = read(snakemake.input.csv, strict=True)
rec, _ = SS.with_disjoint_rests(rec)  # the poses of the report (workflow/scripts/discrepancy_measured.py)
sims = SS.resimulate(rec, report, n_rep=cfg["replicates"], seed=cfg["seed"])
gaps = pd.DataFrame(SS.gap_rows(name, report, sims, rec), columns=SS.GAP_COLUMNS)
write_csv(sims, snakemake.output.sims)
write_csv(gaps, snakemake.output.gap)
for r in gaps.itertuples():
    log.info("%s, %s: RMS measured/simulated %.2f, KS %.2f (p %.2g), measured excess %.2f vs simulated %.2f "
             "[%.2f, %.2f]", name, r.model, r.rms_ratio, r.ks_distance, r.ks_p_value, r.excess_measured,
             r.excess_sim_median, r.excess_sim_q025, r.excess_sim_q975)
