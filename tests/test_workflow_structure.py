"""How the workflow is put together: the order of the stage includes does not matter, the
final targets are gathered from the stages' declarations and match the rules, the measured
data are fetched by jobs (the simulation stages plan without them, offline), every script is
the script of a rule and runs standalone with that rule's own paths (pypsa-eur's
mock_snakemake: the Snakefile is the one place for paths)."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.configs import CI_CONFIG, REPO, load_config

from .conftest import copy_of_ci_workflow
from .snakemake_plan import planned_jobs, rule_counts

SCRIPTS = REPO / "workflow" / "scripts"
sys.path.insert(0, str(SCRIPTS))
import _helpers  # noqa: E402


def test_stage_include_order_does_not_matter(tmp_path):
    text = (REPO / "Snakefile").read_text()
    includes = re.findall(r'^include: "workflow/rules/(?!common)\w+\.smk"\n', text, re.M)
    assert len(includes) >= 6
    reordered = text
    for line in includes:
        reordered = reordered.replace(line, "")
    # gatherers first, stages in reverse: every list is read only when the DAG is built
    at = reordered.index("\n", reordered.index('include: "workflow/rules/common.smk"')) + 1
    reordered = reordered[:at] + "".join(sorted(includes, reverse=True)) + reordered[at:]
    snakefile = REPO / f".Snakefile.reordered.{os.getpid()}"  # beside the real one: same basedir
    snakefile.write_text(reordered)
    try:  # the dry runs' job tables, planned in this process (tests/snakemake_plan.py)
        counts = [rule_counts(planned_jobs(tmp_path, ["all"], [CI_CONFIG], snakefile=sf))
                  for sf in (REPO / "Snakefile", snakefile)]
    finally:
        snakefile.unlink()
    assert counts[0] == counts[1]
    assert {"claims", "report", "all"} <= set(counts[0])


@pytest.fixture(scope="module")
def workflow():
    cwd = Path.cwd()
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import (ConfigSettings, DeploymentSettings, OutputSettings, ResourceSettings,
                                          StorageSettings, WorkflowSettings)
    try:
        with SnakemakeApi(OutputSettings()) as api:
            yield api.workflow(resource_settings=ResourceSettings(cores=1), storage_settings=StorageSettings(),
                               config_settings=ConfigSettings(), workflow_settings=WorkflowSettings(),
                               deployment_settings=DeploymentSettings(), snakefile=REPO / "Snakefile",
                               workdir=cwd)._workflow
    finally:
        os.chdir(cwd)


def test_final_targets_are_the_stages_declarations_and_match_the_rules(workflow):
    """`all` asks for every declared figure, the ledger and the report; every figure a rule
    draws is declared by a stage, and every declared figure id is a target rule of its own."""
    g = workflow.globals
    declared = g["figure_ids"]()
    assert len(declared) == len(set(declared)) > 20
    drawn = {Path(str(f)).stem for r in workflow.rules for f in r.output
             if str(f).startswith("results/figures/") and str(f).endswith(".png")}
    assert drawn == set(declared)
    assert list(workflow.get_rule("all").input) == g["get_final_output"]()
    assert {"results/claims.csv", "results/report.html"} <= set(workflow.get_rule("all").input)
    for fid in declared:
        assert set(workflow.get_rule(fid).input) == {f"results/figures/{fid}.png", f"results/figures/{fid}.pdf"}
    # the ledger's stages, in the order of the Snakefile's STAGES
    assert g["claim_stages"]() == ["burkhard2024", "batista2011", "tereshkov", "measured", "discrepancy", "gyro", "noise"]
    tables = g["report_tables"]()
    made = {str(f) for r in workflow.rules for f in r.output}
    assert tables and all(path in made for _, _, path in tables), [t for t in tables if t[2] not in made]
    # the results' summaries the report renders (Summary.as_html): every stage that shows results with a
    # Summary declares them, and a rule makes each (tests/test_report_summaries.py: the scripts write them)
    summaries = g["report_summaries"]()
    assert {stage for stage, _, _ in summaries} == {"measured", "discrepancy", "gyro", "noise", "mag"}
    assert all(any(r.is_producer(path) for r in workflow.rules) for _, _, path in summaries), summaries


_OFFLINE = {k: "http://127.0.0.1:9" for k in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY")}


def test_simulation_stages_plan_without_the_measured_data(tmp_path, monkeypatch):
    """No shared copy, no download cache and no network: the simulation stages and their
    figures plan and need no fetch; `all` plans too, with the fetch jobs in it (they fail
    when they run: tests/test_resilience.py).  Planned in this process, offline as the
    command line would be (tests/snakemake_plan.py)."""
    overlay = tmp_path / "no_data.yaml"
    overlay.write_text(f"measured:\n  data_dir: {tmp_path / 'absent'}\n  resources_dir: {tmp_path / 'cache'}\n")
    for var, value in {**_OFFLINE, "no_proxy": "", "NO_PROXY": ""}.items():
        monkeypatch.setenv(var, value)
    (tmp_path / "work").mkdir()

    def dry_run(*targets):
        return rule_counts(planned_jobs(tmp_path / "work", targets, [CI_CONFIG, overlay]))

    jobs = dry_run("burkhard2024", "batista2011", "tereshkov", "burkhard2024_fig1a", "batista2011_fig4")
    assert {"burkhard2024_mc", "batista2011_filter_mc", "tereshkov_simulate", "burkhard2024_fig1a"} <= set(jobs)
    assert not [r for r in jobs if "fetch" in r or r.startswith(("measured", "discrepancy"))], jobs
    jobs = dry_run("all")
    assert jobs["measured_fetch"] == len(load_config("ci.yaml")["measured"]["recordings"])
    assert jobs["discrepancy_adis_fetch"] == 1
    assert not (tmp_path / "cache").exists()


def _scripts():
    return sorted(p for p in SCRIPTS.glob("*.py") if not p.name.startswith("_"))


@pytest.mark.parametrize("script", _scripts(), ids=lambda p: p.name)
def test_every_script_mocks_a_rule_that_runs_it(workflow, script):
    m = re.search(r'mock_snakemake_from_argv\("(\w+)"', script.read_text())
    assert m, f"{script.name} has no standalone block (mock_snakemake_from_argv)"
    rule = workflow.get_rule(m.group(1))
    assert rule.script and Path(rule.script).name == script.name, (
        f"rule {rule.name} runs {rule.script}, not {script.name}")


def test_mock_snakemake_gives_the_rules_paths():
    smk = _helpers.mock_snakemake("discrepancy_chunk", chunk="3")
    assert smk.output.detections == "results/discrepancy/benchmark/detections/chunk_3.csv"
    assert smk.input.profiles == "results/discrepancy/benchmark/profiles.json"
    assert smk.log == ["results/logs/discrepancy/chunk_3.log"]
    assert smk.config["discrepancy"]["benchmark"]["chunks"] == 8  # the default config
    ci = _helpers.mock_snakemake("discrepancy_chunk", configfile=CI_CONFIG, chunk="0")
    assert ci.config["discrepancy"]["benchmark"]["chunks"] == 2


def test_a_script_run_standalone_rebuilds_the_workflows_output(ci_workflow, tmp_path):
    """claims_ledger.py outside Snakemake (mock `snakemake` object: the rule's inputs, in the
    stages' order), on a copy of the CI run without results/claims.csv, rewrites it byte for
    byte (the same rows in the same order)."""
    work = copy_of_ci_workflow(ci_workflow, tmp_path)
    target = work / "results" / "claims.csv"
    want = target.read_bytes()
    target.unlink()
    env = {**os.environ, "ACCELCAL_CONFIG": str(CI_CONFIG)}
    proc = subprocess.run([sys.executable, str(SCRIPTS / "claims_ledger.py")], cwd=work, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert target.read_bytes() == want
    # and Snakemake sees nothing to redo beyond that file's own rule
    rules = {rule for rule, _ in planned_jobs(work, ["results/claims.csv"], [CI_CONFIG]).values()}
    assert rules <= {"claims"}, rules
    shutil.rmtree(work / "results")


@pytest.mark.parametrize("output", ["results/report.html", "results/claims.csv", "results/claims/discrepancy.csv"])
def test_no_issue_numbers_in_the_report_and_ledger_of_a_run(ci_workflow, output):
    """What a run writes for readers speaks of the project only (the sources: tests/test_project_text.py)."""
    from tests.test_project_text import issue_numbers

    text = (ci_workflow[0] / output).read_text(errors="replace")
    assert text and not issue_numbers(text), issue_numbers(text)[:10]
