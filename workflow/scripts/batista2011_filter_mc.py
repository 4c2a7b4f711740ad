"""Monte Carlo of the online filter on the changing-ω trajectory (Figs. 6-8)."""

import time

from _helpers import configure_logging
from batista2011_common import TABLES, standalone, write_table

from accelcal.batista.experiment import filter_kwargs, scenario_from_config
from accelcal.batista.montecarlo import filter_montecarlo, stream

if "snakemake" not in globals():
    snakemake = standalone("batista2011_filter_mc", output={"runs": TABLES["filter_runs"],
                                                             "summary": TABLES["filter_summary"]})

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
f = cfg["filter"]
sc = scenario_from_config(cfg, "changing")
t0 = time.perf_counter()
mc = filter_montecarlo(sc, int(f["runs"]), stream(cfg["seed"], "filter"), **filter_kwargs(cfg),
                       record_every_s=float(f["record_every_s"]), summary_every_s=float(f["summary_every_s"]))
log.info("%d runs x %d steps in %.1f s", int(f["runs"]), len(sc.t), time.perf_counter() - t0)
write_table(mc.runs, snakemake.output.runs, float_format="%.6g")
write_table(mc.summary, snakemake.output.summary, float_format="%.6g")
