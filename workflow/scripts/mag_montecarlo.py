"""The ML and the Li-Griffiths ellipsoid against the Cramér-Rao bound."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.mag.montecarlo import run

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_montecarlo")

log = configure_logging(snakemake)
mc = snakemake.params.mag["monte_carlo"]
table = run(trials=mc["trials"], n_samples=mc["samples"], seed=snakemake.params.mag["seed"])
for (cov, method), g in table.groupby(["coverage", "method"]):
    log.info("%s %s: RMS/CRLB %.3f-%.3f", cov, method, g.rms_over_crlb.min(), g.rms_over_crlb.max())
write_csv(table, snakemake.output[0])
