"""Steady-state filter errors with one noise source at a time (explains the gravity error)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_error_budget, run_streams

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_error_budget")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
f = cfg["filter"]
eb = filter_error_budget(scenario_from_config(cfg, "changing"),
                         run_streams(cfg["seed"], "error_budget", range(int(f["error_budget_runs"]))),
                         steady_from_s=float(f["steady_from_s"]),
                         **filter_kwargs(cfg))
log.info("steady-state RMS per noise source:\n%s", eb.pivot(index="state", columns="source", values="rms_error"))
write_csv(eb, snakemake.output[0])
