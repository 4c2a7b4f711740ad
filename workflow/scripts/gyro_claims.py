"""Claims-ledger rows of the gyro stage, each verdict computed from its tables."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.claims import verdict_counts
from accelcal_repro.gyro.stage import claims


def _read(path):
    try:
        return pd.read_csv(path)
    except pd.errors.EmptyDataError:  # a table with no rows (e.g. no peer for the sessions configured)
        return pd.DataFrame()


if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_claims")

log = configure_logging(snakemake)
i = snakemake.input
rows = claims(_read(i.integrators), _read(i.montecarlo), _read(i.ipopt), _read(i.figure_of_merit),
              _read(i.peer_parameters), _read(i.imucal_parameters), _read(i.coverage), _read(i.stability),
              _read(i.loop))
for r in rows.itertuples():
    log.info("%s/%s: %s (%s)", r.paper, r.claim_id, r.verdict, r.reproduced_value)
log.info("verdicts: %s", verdict_counts(rows))
write_csv(rows, snakemake.output[0])
