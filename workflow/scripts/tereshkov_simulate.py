"""Monte Carlo runs of the Tereshkov estimator: one tidy table per scenario (one estimator
loop for all scenarios of equal duration) and the wall times."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake
from tereshkov_common import stage_config, write_table

from accelcal.tereshkov.montecarlo import run_scenarios

if "snakemake" not in globals():
    _sc = ["field", "straight", "artificial"]
    snakemake = mock_snakemake(
        "tereshkov_simulate",
        output={**{s: f"results/tereshkov/{s}.csv.gz" for s in _sc}, "timing": "results/tereshkov/timing_main.csv"},
        params={"cfg": stage_config(), "scenarios": _sc},
    )

log = configure_logging(snakemake)
out = run_scenarios(snakemake.params.cfg, list(snakemake.params.scenarios))
rows = []
for name, (df, timing) in out.items():
    log.info("%s: %d runs x %d steps in %.1f s (estimator %.1f s, loop shared by %s); table %d rows in %.1f s",
             name, timing["runs"], timing["steps"], timing["wall_s"], timing["estimator_s"], timing["merged_with"],
             len(df), timing["tidy_s"])
    write_table(df, getattr(snakemake.output, name))
    rows.append(timing)
write_table(pd.DataFrame(rows), snakemake.output.timing)
