"""Both layers of the discrepancy workflow on one measured recording (the JSON of `accelcal discrepancy`)."""

import json

from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.atomic import atomic_output
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.report import StochasticSettings, discrepancy_report
from accelcal_repro.measured.sources import source
from accelcal.formats import read
from accelcal.jsonsafe import json_safe
from accelcal.summary import write_summaries
from accelcal_repro.discrepancy.sessions import with_disjoint_rests

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_measured_report", recording="xsens_mti")

log = configure_logging(snakemake)
name = snakemake.wildcards.recording
p = snakemake.params
rec, note = with_disjoint_rests(read(snakemake.input.csv, strict=True))
if note:
    log.warning("%s: %s", name, note)
unit = source(name).unit
analysis = discrepancy_report(rec, p.g, rules=Rules.from_config(p.rules),
                              stochastic=StochasticSettings.from_config(p.stochastic), unit=unit)
out = analysis.to_dict()
out.update({"recording": name, "g": p.g, "unit": unit, "rate": rec.rate})
if note:
    out["notes"] = [*out.get("notes", []), note]
with atomic_output(snakemake.output[0]) as tmp, open(tmp, "w") as fh:
    json.dump(json_safe(out), fh, indent=1, sort_keys=False)
    fh.write("\n")
summary = analysis.summary(written_to=snakemake.output[0])
write_summaries(snakemake.output.summaries, {name: summary})
log.info("%s: %s\n%s", name, analysis.deterministic.outcome, summary)
