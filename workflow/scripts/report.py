"""results/report.html: the one page a reviewer opens first (accelcal_repro.report).

The benchmark files (results/benchmarks/) are read as they are when this job runs: the
rule depends on every figure and the claims ledger, so every job of the workflow has
finished (and written its benchmark) by then.
"""

import sys
from pathlib import Path

from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal_repro.report import ReportError, build_report, load_conclusions, write_report

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("report")

log = configure_logging(snakemake)
try:
    page = build_report(
        claims=snakemake.input.claims,
        figures=dict(zip(snakemake.params.figure_ids, snakemake.input.figures, strict=True)),
        captions={fid: Path(p).read_text(encoding="utf-8") for fid, p in snakemake.params.captions.items()},
        conclusions=load_conclusions(snakemake.input.conclusions),
        tables=[tuple(t) for t in snakemake.params.tables],
        summaries=[tuple(t) for t in snakemake.params.summaries],
        config=snakemake.config,
        lock_text=Path(snakemake.input.lock).read_text(encoding="utf-8"),
        benchmarks_dir=snakemake.params.benchmarks_dir,
        config_files=snakemake.params.config_files,
    )
except ReportError as e:
    log.error("%s", e)  # one line in the log and on stderr, no traceback
    sys.exit(1)
write_report(page, snakemake.output[0])
log.info("wrote %s (%.1f MB, %d figures)", snakemake.output[0], len(page.encode()) / 1e6,
         len(snakemake.params.figure_ids))
