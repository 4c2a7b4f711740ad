"""Locate or download (and verify) the files of one measured recording; write its manifest
and the recording as canonical CSV (t,ax,ay,az, in the unit of its file).

A failure (checksum mismatch, download error) is one line in the log and on stderr and
exit status 1, not a traceback: the message says which file and what to do."""

import sys

from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.measured.data import DatasetError
from accelcal.atomic import write_json_atomic
from accelcal_repro.measured.sources import convert, fetch_source, manifest, read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_fetch", recording="xsens_mti")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
try:
    paths = fetch_source(name, snakemake.params.data_dir, snakemake.params.resources_dir)
except DatasetError as e:
    log.error("%s: recording %s: %s", type(e).__name__, name, e)
    sys.exit(1)
m = manifest(name, paths)
for f, v in m["files"].items():
    log.info("%s/%s: %s (sha256 %s, verified)", name, f, v["path"], v["sha256"])
write_json_atomic(snakemake.output.manifest, m)
# the recording as the discrepancy stage and the figures read it, from the paths just written
rec = convert(name, read_manifest(snakemake.output.manifest), snakemake.output.csv)
log.info("%s: %d samples, %.1f s at %.1f Hz -> %s", name, rec.n, rec.t[-1] - rec.t[0], rec.rate, snakemake.output.csv)
