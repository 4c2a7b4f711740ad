"""Coverage of the noise analysis's term intervals on the simulated records of one configuration."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.noise.coverage import coverage_rows

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("noise_coverage", configuration="white")

log = configure_logging(snakemake)
p, c = snakemake.params, snakemake.params.coverage
terms = {k: v for k, v in p.terms.items() if k != "name" and v > 0}
rows = coverage_rows(snakemake.wildcards.configuration, terms, records=c["records"], samples=c["samples"],
                     fs=c["fs_hz"], seed=c["seed"], index=p.index, level=c["level"], n_boot=c["n_boot"])
write_csv(rows, snakemake.output[0])
for r in rows.itertuples():
    log.info("%s: coverage %.3f [%.3f, %.3f] over %d axes", r.term, r.coverage, r.coverage_low, r.coverage_high, r.axes)
