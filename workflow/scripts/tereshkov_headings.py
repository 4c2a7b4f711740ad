"""True heading, yaw rate and speed of the example field runs (Fig. 2)."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.tereshkov.montecarlo import heading_table

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_headings")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
runs = int(cfg.get("figures", {}).get("example_runs", 2))
df = heading_table(cfg, "field", runs=runs, every_s=0.5)
log.info("%d example runs, %d samples each", runs, len(df) // runs)
write_csv(df, snakemake.output[0])
