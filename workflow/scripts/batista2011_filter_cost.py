"""Wall time per step of the filter (exact single run; shared-gain batch per run)."""

from _helpers import configure_logging
from batista2011_common import TABLES, standalone, write_table

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_cost, stream

if "snakemake" not in globals():
    snakemake = standalone("batista2011_filter_cost", output=[TABLES["filter_cost"]])

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
tm = cfg["filter"]["timing"]
cost = filter_cost(scenario_from_config(cfg, "changing"), stream(cfg["seed"], "timing"), **filter_kwargs(cfg),
                   steps=int(tm["steps"]), runs=int(tm["runs"]), repeat=int(tm["repeat"]))
log.info("filter cost:\n%s", cost.to_string())
write_table(cost, snakemake.output[0])
