"""Calibrate one measured recording with every configured estimator and evaluate it."""

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.errors import TooFewPosesError
from accelcal.summary import write_summaries
from accelcal_repro.measured.calibrate import TABLES, calibrate_recording, check_section_list_estimators
from accelcal_repro.measured.sources import read_manifest, read_source, section_list

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_calibrate", recording="xsens_mti")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
s, b = snakemake.params.settings, snakemake.params.bootstrap
paths = read_manifest(snakemake.input.manifest)
try:  # a config rule checked here, not while the Snakefile is parsed (no reproduction imported there)
    check_section_list_estimators(name, s["estimators"], section_list(name, paths),
                                  s.get("pose_selection", "section_list"))
except TooFewPosesError as e:
    raise SystemExit(f"invalid config: {e}") from None
mc = calibrate_recording(  # the original file, read as `accelcal calibrate` reads it
    name, read_source(name, paths), g=float(s["g"]), estimators=list(s["estimators"]),
    sections=section_list(name, paths),
    pose_selection=s.get("pose_selection", "section_list"), n_boot=int(b["replicates"]), seed=int(b["seed"]),
    level=float(b["level"]), min_valid_fraction=float(b["min_valid_fraction"]), static_kw=dict(snakemake.params.static))
log.info("%s: %d rests detected, %d used", name, len(mc.poses), int(mc.poses.used.sum()))
for r in mc.summary.itertuples():
    log.info("%s %s:\n%s", name, r.estimator, mc.results[r.estimator].summary())
    log.info("%s %s: LOPO RMS %.3g%s; bootstrap valid %.0f%% -> %s", name, r.estimator, r.lopo_rms,
             f" ({r.lopo_note})" if r.lopo_note else "", 100 * r.boot_valid_fraction, r.ci_method)
for t in TABLES:
    write_csv(getattr(mc, t), getattr(snakemake.output, t))
write_summaries(snakemake.output.summaries, {e: mc.results[e].summary() for e in mc.summary["estimator"]})
