"""One chunk of the filter Monte Carlo on the changing-ω trajectory (Figs. 6-8): the runs
``params.runs = [first, stop)``, each from its own random stream."""

import time

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_montecarlo, run_streams

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_filter_mc", chunk="0")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
f = cfg["filter"]
first, stop = (int(x) for x in snakemake.params.runs)
sc = scenario_from_config(cfg, "changing")
ids = range(first, stop)
t0 = time.perf_counter()
mc = filter_montecarlo(sc, run_streams(cfg["seed"], "filter", ids), **filter_kwargs(cfg), run_ids=ids,
                       record_every_s=float(f["record_every_s"]), summary_every_s=float(f["summary_every_s"]))
log.info("runs %d-%d x %d steps in %.1f s", first, stop - 1, len(sc.t), time.perf_counter() - t0)
# lossless: the merge combines these into the statistics over all runs
write_csv(mc.runs, snakemake.output.runs, float_format="%.17g")
write_csv(mc.moments, snakemake.output.moments, float_format="%.17g")
