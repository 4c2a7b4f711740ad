"""One job's share of the Monte Carlo runs of the Tereshkov estimator: one tidy table per
scenario (one estimator loop for all scenarios of equal duration) and the wall times.
Run r of a scenario belongs to job ``r mod jobs``; tereshkov_merge.py joins the jobs."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.montecarlo import run_scenarios

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_simulate", job="0")

log = configure_logging(snakemake)
job, jobs = int(snakemake.params.job), int(snakemake.params.jobs)
out = run_scenarios(snakemake.params.cfg, list(snakemake.params.scenarios), job=job, jobs=jobs)
rows = []
for name, (df, timing) in out.items():
    log.info("%s (job %d of %d): %d runs x %d steps in %.1f s (estimator %.1f s, loop shared by %s); "
             "table %d rows in %.1f s", name, job + 1, jobs, timing["runs"], timing["steps"], timing["wall_s"],
             timing["estimator_s"], timing["merged_with"], len(df), timing["tidy_s"])
    write_csv(df, getattr(snakemake.output, name))
    rows.append(timing)
write_csv(pd.DataFrame(rows), snakemake.output.timing)
