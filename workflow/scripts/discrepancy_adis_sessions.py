"""Session-shaped pieces of the ADIS record: observed pose-mean wander vs the reference model and the stochastic layer."""

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.discrepancy import adis as A
from accelcal_repro.discrepancy.benchmark import Session

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_adis_sessions")

log = configure_logging(snakemake)
p = snakemake.params
acc = np.load(snakemake.input.noise).astype(float)
models = pd.read_csv(snakemake.input.models)
session = Session.from_config(p.session)
check = A.session_check(acc, session.rate, session, A.chosen_models(models), n_layer=p.adis["layer_pieces"],
                        seed=p.adis["seed"], n_boot=p.adis["n_boot"], n_resim=p.adis["n_resim"],
                        candidates=tuple(p.candidates))
summ = A.session_check_summary(check)
write_csv(check, snakemake.output.check)
write_csv(summ, snakemake.output.summary)
for r in summ.itertuples():
    log.info("axis %s: %d pieces, pose-mean excess %.2f, reference/observed %.2f, layer/observed %s",
             r.axis, r.pieces, r.excess_observed, r.reference_over_observed,
             f"{r.layer_over_observed:.2f}" if "layer_over_observed" in summ else "-")
