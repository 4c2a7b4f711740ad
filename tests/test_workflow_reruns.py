"""Determinism of the whole workflow: a forced rerun of chosen jobs of the CI run rewrites
identical bytes.  A module of its own so that, dispatched after the CI run is made (see
tests/conftest.py), it runs on whichever worker is free while the rest of test_workflow.py
goes on."""

import re
from pathlib import Path

import pandas as pd

from .conftest import CI_CONFIG as CI
from .conftest import copy_of_ci_workflow, run_snakemake as snakemake
from .snakemake_plan import planned_jobs


def test_ci_reruns_are_byte_identical(ci_workflow, tmp_path):
    """Determinism: forcing a representative set of jobs to rerun with the same config
    (a Monte Carlo grid point, a calibration and a filter Monte Carlo chunk, real-data
    tables, a discrepancy benchmark chunk, its scoring and summary, a measured discrepancy
    report, the ADIS analysis, figures, the stage claims and the ledger) rewrites identical
    bytes.  The Burkhard gather and figure jobs are not forced here: their scripts rerun
    outside Snakemake on a copy of the CI run must rewrite every table and figure of the
    stage byte for byte (tests/test_burkhard2024_workflow.py), the same determinism check
    without a second redraw.  Only those jobs run (``--force`` on them as targets, not
    ``--forcerun``, which would redo everything downstream too: the same determinism,
    minutes more).  Wall-time measurements are the exception: files with "timing" in their
    path, the speed claims computed from them, and the report that shows them (its
    byte-identity from identical inputs is tests/test_report.py's)."""
    import hashlib

    workdir = copy_of_ci_workflow(ci_workflow, tmp_path / "copy")
    point = sorted((workdir / "results" / "burkhard2024" / "mc").glob("*.csv.gz"))[0].relative_to(workdir)
    targets = [point, "results/batista2011/chunks/calibration_errors_0.csv.gz",
               "results/tereshkov/chunks/field_0.csv.gz", "measured_tables", "tereshkov_summary",
               "results/discrepancy/benchmark/detections/chunk_0.csv", "results/discrepancy/benchmark/scores.csv.gz",
               "results/discrepancy/summary.csv", "results/discrepancy/measured/mpu6050.json",
               "results/discrepancy/adis/models.csv", "results/claims/discrepancy.csv",
               "results/figures/discrepancy_confusion.png", "batista2011_figures", "claims"]
    results = workdir / "results"

    def digests():
        out = {}
        for p in sorted(results.rglob("*")):
            rel = p.relative_to(results)
            if not p.is_file() or {"logs", "benchmarks"} & set(rel.parts) or "timing" in str(rel) \
                    or rel == Path("report.html"):
                continue
            if p.suffix == ".csv" and "claims" in (rel.parts[0], p.stem):
                ledger = pd.read_csv(p, dtype=str, keep_default_na=False)
                out[rel] = ledger[~ledger["claim_id"].str.startswith("speed_")].to_csv(index=False)
            else:
                out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
        return out

    before = digests()
    proc = snakemake(workdir, *targets, "--configfile", CI, "--force")
    assert proc.returncode == 0, proc.stderr[-3000:]
    after = digests()
    assert before.keys() == after.keys()
    changed = sorted(str(k) for k in before if before[k] != after[k])
    assert not changed, f"rerun changed {changed}"
    out = proc.stdout + proc.stderr
    ran = set(re.findall(r"^(?:local)?rule (\w+):$", out, re.M))
    for rule in ("burkhard2024_mc", "batista2011_calibration_mc", "tereshkov_simulate",
                 "discrepancy_chunk", "discrepancy_score", "discrepancy_summary", "discrepancy_measured_report",
                 "discrepancy_adis", "discrepancy_claims", "discrepancy_figures", "claims"):
        assert rule in ran, rule  # the job did rerun


def test_a_claim_threshold_reruns_only_the_claims(ci_workflow, tmp_path):
    """Config per key (common.smk's config_keys): a rule's params hold only the keys its code
    reads, so a new threshold of a claim that no figure draws reruns the stage's claims job
    and what gathers the claims (the ledger, the report), never a Monte Carlo or a figure."""
    import yaml

    override = tmp_path / "thresholds.yaml"
    override.write_text(yaml.safe_dump({"tereshkov": {"claims": {"straight_torque_max_fraction": 0.2}},
                                        "batista2011": {"claims": {"t_max": 5.0}},
                                        "burkhard2024": {"claims": {"magnitude_factor": 4.0}}}))
    # `snakemake -n all --rerun-triggers params`, planned in this process (tests/snakemake_plan.py)
    jobs = planned_jobs(ci_workflow[0], ["all"], [CI, override], rerun_triggers=["params"])
    ran = {rule for rule, _ in jobs.values()}
    stage_claims = {"tereshkov_claims", "batista2011_claims", "burkhard2024_claims"}
    assert stage_claims <= ran, ran
    # the ledger (results/claims.csv) and what reads it: the report, the job-seconds per stage and its figure
    readers_of_the_ledger = {"claims", "report", "all", "timing_stages", "timing_benchmark_figure", "benchmark"}
    assert ran - stage_claims <= readers_of_the_ledger, sorted(ran - stage_claims)
