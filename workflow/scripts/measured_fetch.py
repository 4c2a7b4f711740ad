"""Locate or download (and verify) the files of one measured recording; write its manifest."""

from _helpers import configure_logging, mock_snakemake

from accelcal.measured.sources import fetch_source, manifest, write_json_atomic

if "snakemake" not in globals():
    from measured_common import measured_config

    _m = measured_config()
    snakemake = mock_snakemake("measured_fetch", output=["results/measured/data/xsens_mti.json"],
                               params={"data_dir": _m["data_dir"], "resources_dir": _m["resources_dir"]},
                               wildcards={"recording": "xsens_mti"})

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
paths = fetch_source(name, snakemake.params.data_dir, snakemake.params.resources_dir)
m = manifest(name, paths)
for f, v in m["files"].items():
    log.info("%s/%s: %s (sha256 %s, verified)", name, f, v["path"], v["sha256"])
write_json_atomic(snakemake.output[0], m)
