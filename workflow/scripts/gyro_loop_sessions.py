"""Every real gyro session through the gyro loop, and which named effects repeat across sessions of one unit."""

import json
from pathlib import Path

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.gyro.loop_sessions import session_tables
from accelcal_repro.measured.sources import read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_loop_sessions")

log = configure_logging(snakemake)
paths = {json.loads(Path(m).read_text())["dataset"]: read_manifest(m) for m in snakemake.input.manifests}
rows, repeats = session_tables(snakemake.params.gyro, paths)
for r in rows.itertuples(index=False):
    log.info("%s: %s", r.session, r.reason or f"named {r.named}, excess {r.excess_before:.3g} -> {r.excess_after:.3g}")
write_csv(rows, snakemake.output.sessions)
write_csv(repeats, snakemake.output.repeats)
