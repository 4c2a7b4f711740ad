"""The reproduction report: results/report.html, one self-contained page (figures with the
papers' conclusions, the claims ledger, measured-data and discrepancy tables, config and
seeds, locked package versions, wall time per stage).

Needs from common.smk: results, figure_ids, report_tables, report_summaries, log_path.  Inputs are
functions, so that stages included after this file are still seen (they run once the DAG
is built).
The benchmark files (results/benchmarks/) are not inputs: the page reads whatever is there
when it runs; it depends on every figure and the ledger, so every job has finished by then.
"""

import os

from snakemake.io import is_flagged


def report_captions():
    """Figure id -> caption file, from the report(...) flags of the figures' PNG outputs."""
    captions = {}
    for r in workflow.rules:
        for f in r.output:
            name = os.path.basename(str(f))
            if is_flagged(f, "report") and name.endswith(".png") and str(f).startswith("results/figures/"):
                caption = f.flags["report"].caption
                if caption is not None:
                    captions[name[: -len(".png")]] = os.path.normpath(caption.get_path_or_uri(secret_free=True))
    return {fid: captions[fid] for fid in sorted(captions) if fid in figure_ids()}


def report_config_files():
    """The config files in the order they were applied (later ones extend earlier ones),
    relative to the project root where they are inside it."""
    given = [str(f) for f in (workflow.overwrite_configfiles or [])]  # --configfile: applied last
    files = [str(f) for f in workflow.configfiles if str(f) not in given] + given
    return [os.path.relpath(str(f), workflow.basedir) if os.path.isabs(str(f)) else str(f) for f in files]


rule report:
    """results/report.html from every figure, the claims ledger and the stages' summary tables."""
    localrule: True  # on a cluster: the login node (the HTML of finished outputs)
    input:
        claims=results("claims.csv"),
        figures=lambda w: expand(results("figures/{figure}.png"), figure=sorted(figure_ids())),
        tables=lambda w: [path for _, _, path in report_tables()],
        summaries=lambda w: [path for _, _, path in report_summaries()],
        captions=lambda w: sorted(report_captions().values()),
        conclusions=os.path.join(workflow.basedir, "workflow", "report", "conclusions.yaml"),
        lock=os.path.join(workflow.basedir, "environment.lock"),
    output:
        results("report.html"),
    params:
        figure_ids=lambda w: sorted(figure_ids()),
        captions=lambda w: report_captions(),
        tables=lambda w: [list(t) for t in report_tables()],
        summaries=lambda w: [list(t) for t in report_summaries()],
        benchmarks_dir=results("benchmarks"),
        config_files=report_config_files(),
    log:
        log_path("report"),
    # no benchmark: the page shows the benchmark files, and its own (from the previous run)
    # would make every rebuild differ
    threads: 1
    resources:
        mem_mb=2000,  # every figure decoded once, downscaled and base64-encoded
        runtime=10,
    script:
        "../scripts/report.py"
