"""results/claims.csv: the stages' claims files, validated and concatenated."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import assemble_ledger, verdict_counts

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("claims")

log = configure_logging(snakemake)
ledger = assemble_ledger(list(snakemake.input))
log.info("%d claims from %d stage file(s): %s", len(ledger), len(snakemake.input), verdict_counts(ledger))
write_csv(ledger, snakemake.output[0])
