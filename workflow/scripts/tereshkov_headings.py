"""True heading, yaw rate and speed of the example field runs (Fig. 2)."""

from _helpers import configure_logging, mock_snakemake
from tereshkov_common import stage_config, write_table

from accelcal_repro.tereshkov.montecarlo import heading_table

if "snakemake" not in globals():
    snakemake = mock_snakemake("tereshkov_headings", output=["results/tereshkov/headings.csv"],
                               params={"cfg": stage_config()})

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
runs = int(cfg.get("figures", {}).get("example_runs", 2))
df = heading_table(cfg, "field", runs=runs, every_s=0.5)
log.info("%d example runs, %d samples each", runs, len(df) // runs)
write_table(df, snakemake.output[0])
