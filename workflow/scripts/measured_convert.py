"""One measured recording as canonical CSV (t,ax,ay,az), in the unit of its file."""

from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.measured.sources import convert, read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_convert", recording="xsens_mti")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
rec = convert(name, read_manifest(snakemake.input.manifest), snakemake.output[0])
log.info("%s: %d samples, %.1f s at %.1f Hz -> %s", name, rec.n, rec.t[-1] - rec.t[0], rec.rate, snakemake.output[0])
