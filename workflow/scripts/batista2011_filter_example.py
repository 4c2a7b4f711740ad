"""One run of the exact filter (its own covariance), for Figs. 4 and 5."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_example, stream

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_filter_example")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
ex = filter_example(scenario_from_config(cfg, "changing"), stream(cfg["seed"], "example"), **filter_kwargs(cfg),
                    record_every_s=float(cfg["filter"]["example_every_s"]))
write_csv(ex, snakemake.output[0], float_format="%.8g")
log.info("wrote %d rows", len(ex))
