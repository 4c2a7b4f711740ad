"""The ADIS16405 record through the noise analysis: report, Kalibr and OpenVINS files, the datasheet table, the figure."""

import sys
from dataclasses import replace
from pathlib import Path

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.atomic import atomic_output, write_json_atomic
from accelcal.errors import AccelcalError
from accelcal.noise import analyse_noise
from accelcal.noise.export import kalibr_yaml, openvins_yaml
from accelcal.noise.figures import noise_figure
from accelcal.plotting import save_figure
from accelcal.summary import write_summaries
from accelcal_repro.measured.smac import read_smac_imu
from accelcal_repro.measured.sources import read_manifest
from accelcal_repro.noise.adis import datasheet_table, figure_references

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("noise_adis")

log = configure_logging(snakemake)
p, out = snakemake.params, snakemake.output
try:
    rec = read_smac_imu(read_manifest(snakemake.input.manifest)[p.file])
except AccelcalError as e:
    log.error("%s: %s", type(e).__name__, e)
    sys.exit(1)
rec = replace(rec, source=f"smac_adis16405/{p.file}")  # the dataset's name, not this machine's path
report = analyse_noise(rec, level=p.adis["level"], n_boot=p.adis["n_boot"], seed=p.adis["seed"])
write_json_atomic(out.report, report.to_dict())
write_summaries(out.summaries, {"adis16405": report.summary(written_to=out.report)})
texts = {out.kalibr: kalibr_yaml(report, rostopic=p.adis["rostopic"], inflate=p.adis["inflate"]),
         out.openvins: openvins_yaml(report, rostopic=p.adis["rostopic"], inflate=p.adis["inflate"])[0]}
for path, text in texts.items():
    with atomic_output(path) as tmp:
        Path(tmp).write_text(text)
table = datasheet_table(report)
write_csv(table, out.datasheet)
fig = noise_figure(report, title=f"ADIS16405 (SMAC imudata), {report.duration_s / 3600:.3g} h static at "
                                 f"{report.fs:.4g} Hz: Allan deviation, IEEE fit and the datasheet's typical values",
                   references=figure_references(table))
for path in save_figure(fig, out.png):
    log.info("wrote %s", path)
for r in table[table.primary].itertuples():
    log.info("%s %s %s: %.4g (%s) = %.2fx the datasheet", r.sensor, r.quantity, r.axis, r.fitted, r.unit, r.ratio)
for w in report.warnings:
    log.info("warning: %s", w)
