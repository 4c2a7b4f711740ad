"""The Tereshkov Monte Carlo jobs merged: one table per scenario in the order one job
would write it, and the wall times summed over the jobs."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake
from tereshkov_common import stage_config, write_table

from accelcal_repro.tereshkov.montecarlo import merge_job_tables, merge_job_timings

if "snakemake" not in globals():  # standalone: the outputs of the standalone simulate runs (one job each)
    _d = "results/tereshkov"
    _sc = ["field", "straight", "artificial"]
    snakemake = mock_snakemake(
        "tereshkov_merge",
        input={**{s: [f"{_d}/chunks/{s}_0.csv.gz"] for s in _sc + ["sweep"]},
               "main_timing": [f"{_d}/chunks/timing_main_0.csv"], "sweep_timing": [f"{_d}/chunks/timing_sweep_0.csv"]},
        output={**{s: f"{_d}/{s}.csv.gz" for s in _sc + ["sweep"]}, "timing_main": f"{_d}/timing_main.csv",
                "timing_sweep": f"{_d}/timing_sweep.csv"},
        params={"cfg": stage_config(), "scenarios": _sc + ["sweep"]},
    )

log = configure_logging(snakemake)
for name in snakemake.params.scenarios:
    paths = list(snakemake.input[name])
    df = merge_job_tables(pd.read_csv(p) for p in paths)
    log.info("%s: %d rows from %d jobs", name, len(df), len(paths))
    write_table(df, getattr(snakemake.output, name))
for part in ("main", "sweep"):
    timing = merge_job_timings(pd.concat([pd.read_csv(p) for p in snakemake.input[f"{part}_timing"]],
                                         ignore_index=True))
    log.info("%s wall times:\n%s", part, timing.to_string())
    write_table(timing, snakemake.output[f"timing_{part}"])
