"""The filter with ω along a fixed axis vs a changing axis, and the observability Gramian."""

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_montecarlo, gramian_table, observability_table, run_streams

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_observability_mc")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
o = cfg["observability"]
tables, grams = [], []
for case in ("changing", "constant"):
    sc = scenario_from_config(cfg, case)
    rngs = run_streams(cfg["seed"], f"observability_{case}", range(int(o["runs"])))
    mc = filter_montecarlo(sc, rngs, **filter_kwargs(cfg),
                           record_every_s=float(o["record_every_s"]), summary_every_s=float(o["record_every_s"]))
    tables.append(observability_table(mc, o["axis_body"], case))
    n = int(round(float(o["gramian_window_s"]) / sc.dt)) + 1
    grams.append(gramian_table(sc.t[:n], sc.attitude.omega[:n], o["axis_body"], case))
obs, gram = pd.concat(tables, ignore_index=True), pd.concat(grams, ignore_index=True)
log.info("Gramian:\n%s", gram.to_string())
last = obs[obs["t"] == obs["t"].max()]
log.info("final RMS errors:\n%s", last.to_string())
write_csv(obs, snakemake.output.table, float_format="%.6g")
write_csv(gram, snakemake.output.gramian)
assert np.isfinite(gram["eig_ratio"]).all()
