"""One run of the exact filter (its own covariance), for Figs. 4 and 5."""

from _helpers import configure_logging
from batista2011_common import TABLES, standalone, write_table

from accelcal_repro.batista2011.experiment import filter_kwargs, scenario_from_config
from accelcal_repro.batista2011.montecarlo import filter_example, stream

if "snakemake" not in globals():
    snakemake = standalone("batista2011_filter_example", output=[TABLES["filter_example"]])

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
ex = filter_example(scenario_from_config(cfg, "changing"), stream(cfg["seed"], "example"), **filter_kwargs(cfg),
                    record_every_s=float(cfg["filter"]["example_every_s"]))
write_table(ex, snakemake.output[0], float_format="%.8g")
log.info("wrote %d rows", len(ex))
