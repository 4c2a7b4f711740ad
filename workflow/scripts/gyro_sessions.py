"""Every configured real session with gyro data calibrated (the CLI's route) beside the peers."""

import json
import tempfile
from pathlib import Path

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.summary import write_summaries
from accelcal_repro.gyro.report import run
from accelcal_repro.measured.sources import read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("gyro_sessions")

log = configure_logging(snakemake)
paths = {json.loads(Path(m).read_text())["dataset"]: read_manifest(m) for m in snakemake.input.manifests}
imutk = [json.loads(Path(p).read_text())["runs"] for p in snakemake.input.imutk_run]
with tempfile.TemporaryDirectory() as tmp:  # the tables are written below, atomically, to the rule's paths
    summaries = {}
    tabs = run(Path(tmp), paths, tuple(snakemake.params.sessions), imutk[0] if imutk else None, summaries)
for r in tabs["sessions"].itertuples(index=False):
    log.info("%s: %s", r.session, r.error or f"{r.motions:.0f} motions, chi2/dof {r.chi2_per_dof:.3g}")
for name, path in snakemake.output.items():
    if name != "summaries":
        write_csv(tabs[name], path)
write_summaries(snakemake.output.summaries, summaries)
