"""Locate or download (and verify) the files of one dataset of the mag stage; write its manifest."""

import sys

from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.atomic import write_json_atomic
from accelcal_repro.measured.data import DatasetError, fetch_dataset
from accelcal_repro.measured.sources import dataset_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_fetch", mag_dataset="mag_ck_explorer")

log = configure_logging(snakemake)
p, dataset = snakemake.params, snakemake.wildcards.mag_dataset
try:
    paths = fetch_dataset(dataset, p.data_dir, p.resources_dir, files=p.files)
except DatasetError as e:
    log.error("%s: %s", type(e).__name__, e)
    sys.exit(1)
m = dataset_manifest(dataset, paths)
for f, v in m["files"].items():
    log.info("%s/%s: %s (sha256 %s, verified)", dataset, f, v["path"], v["sha256"])
write_json_atomic(snakemake.output[0], m)
