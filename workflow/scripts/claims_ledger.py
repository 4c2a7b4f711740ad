"""results/claims.csv: the stages' claims files, validated and concatenated."""

from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal_repro.claims import assemble_ledger, verdict_counts

if "snakemake" not in globals():
    import glob

    snakemake = mock_snakemake("claims", input=sorted(glob.glob("results/claims/*.csv")),
                               output=["results/claims.csv"])

log = configure_logging(snakemake)
ledger = assemble_ledger(list(snakemake.input))
log.info("%d claims from %d stage file(s): %s", len(ledger), len(snakemake.input), verdict_counts(ledger))
write_csv(ledger, snakemake.output[0])
