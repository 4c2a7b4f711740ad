"""Wall time per step of the filter (exact single run; shared-gain batch per run)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_cost, stream

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_filter_cost")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
tm = cfg["filter"]["timing"]
cost = filter_cost(scenario_from_config(cfg, "changing"), stream(cfg["seed"], "timing"), **filter_kwargs(cfg),
                   steps=int(tm["steps"]), runs=int(tm["runs"]), repeat=int(tm["repeat"]))
log.info("filter cost:\n%s", cost.to_string())
write_csv(cost, snakemake.output[0])
