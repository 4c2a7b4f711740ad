"""The ADIS16405 record: Allan deviation to ~1000 s, the library's noise models fitted to it, its noise."""

import sys

import numpy as np
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.atomic import atomic_output
from accelcal.errors import AccelcalError
from accelcal_repro.discrepancy import adis as A
from accelcal_repro.measured.smac import read_smac_rda
from accelcal_repro.measured.sources import read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_adis")

log = configure_logging(snakemake)
p = snakemake.params
try:
    path = read_manifest(snakemake.input.manifest)[p.file]
    rec = read_smac_rda(path)
except AccelcalError as e:
    log.error("%s: %s", type(e).__name__, e)
    sys.exit(1)
fs = 1.0 / float(rec.t[1] - rec.t[0])
acc = A.noise_of(rec)
av, allan = A.reference_allan(acc, fs)
models, curves = A.fit_long_tau(av, fs, p.adis["tau_min_s"], p.adis["tau_max_s"])
write_csv(allan, snakemake.output.allan)
write_csv(models, snakemake.output.models)
write_csv(curves, snakemake.output.curves)
with atomic_output(snakemake.output.noise) as tmp, open(tmp, "wb") as fh:
    np.save(fh, acc.astype(np.float32))
log.info("%s: %d samples at %g Hz, tau up to %.0f s", path, len(acc), fs, av.taus.max())
for r in models[models.chosen].itertuples():
    log.info("axis %s: %s (BIC %.1f), measured/model ADEV within x%.3f over tau %.3g-%.3g s", r.axis, r.terms, r.bic,
             r.max_ratio, r.tau_min_s, r.tau_max_s)
