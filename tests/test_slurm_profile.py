"""The SLURM profile (profiles/slurm/) without a cluster: the executor plugin pinned in
environment.lock imports, and the whole workflow's DAG builds with the profile, used as the
README says (`--workflow-profile profiles/slurm`), in dry-run mode without submitting
anything.  The dry runs check what the profile decides: the partition and account a user
sets reach every job (profiles/default does not override them), every job asks for one
CPU, and the default config makes a few dozen SLURM jobs, every rule job being grouped,
local or a timing benchmark.  tests/test_real_slurm.py runs the
profile on a real SLURM."""

import os
import re
import stat
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
PROFILE = REPO / "profiles" / "slurm"
SLURM_COMMANDS = ("sbatch", "squeue", "sacct", "sinfo", "scancel", "sacctmgr", "srun", "scontrol", "sshare")
#: The timing benchmarks: alone in their allocation, never grouped.
TIMING_RULES = {"burkhard2024_timing_run", "batista2011_filter_cost", "timing_filters"}


def profile_settings():
    return yaml.safe_load((PROFILE / "config.yaml").read_text())


def test_plugin_is_pinned_and_imports():
    import snakemake_executor_plugin_slurm  # noqa: F401

    assert "\nsnakemake-executor-plugin-slurm==" in (REPO / "environment.lock").read_text()


def test_status_comes_from_squeue():
    """sacct fails without accounting storage and the plugin (2.8.0) then drops its jobs and
    waits forever; squeue works on both kinds of cluster (README "On a cluster")."""
    assert profile_settings()["slurm-status-command"] == "squeue"


@pytest.fixture(scope="module")
def fake_slurm(tmp_path_factory):
    """A PATH directory where every SLURM command only records that it was called (and
    fails): a dry run must not submit anything even where SLURM is installed."""
    bindir = tmp_path_factory.mktemp("fake_slurm_bin")
    calls = bindir / "calls.log"
    for cmd in SLURM_COMMANDS:
        exe = bindir / cmd
        exe.write_text(f'#!/bin/sh\necho "{cmd} $*" >> "{calls}"\nexit 1\n')
        exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return bindir, calls


def dry_run(workdir, fake_slurm, *args, profile=PROFILE):
    bindir, _ = fake_slurm
    env = {k: v for k, v in os.environ.items() if k != "SLURM_CONF"}
    env["PATH"] = f"{bindir}{os.pathsep}{os.environ['PATH']}"
    cmd = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
           "--workflow-profile", str(profile), "-n", *map(str, args)]
    proc = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-4000:]
    assert "This was a dry-run" in out
    assert f"Using workflow specific profile {profile} " in out  # and not profiles/default
    return out


def job_blocks(out):
    """(rule, group or None, resources line, threads) of every job a dry run lists: a job
    of a group job is printed indented under its "Group job NAME" line."""
    jobs, group = [], None
    lines = out.splitlines()
    for i, line in enumerate(lines):
        header = re.match(r"\[.*\] Group job (\w+) \(jobs in lexicogr", line)
        if header:
            group = header.group(1)
            continue
        m = re.match(r"^( *)rule (\w+):$", line)
        if not m:
            continue
        indent = m.group(1)
        fields = {}
        for body in lines[i + 1:]:
            if not body.startswith(indent + "    "):
                break
            key, _, value = body.strip().partition(": ")
            fields[key] = value
        jobs.append((m.group(2), group if indent else None, fields.get("resources", ""),
                     int(fields.get("threads", 1))))
        if not indent:
            group = None
    return jobs


def local_rules():
    """Rules marked `localrule: True` in the workflow's sources (a named rule's block is
    its indented lines)."""
    local, rule = set(), None
    for path in [REPO / "Snakefile", *sorted((REPO / "workflow" / "rules").glob("*.smk"))]:
        for line in path.read_text().splitlines():
            m = re.match(r"rule (\w+):", line)
            if m or (line and not line[0].isspace()):
                rule = m.group(1) if m else None
            elif rule and re.match(r"\s+localrule:\s*True\b", line):
                local.add(rule)
    return local


def test_dag_builds_with_the_slurm_profile_in_dry_run(tmp_path, fake_slurm):
    out = dry_run(tmp_path, fake_slurm, "all", "--configfile", REPO / "config" / "ci.yaml")
    jobs = job_blocks(out)
    rules = {rule for rule, *_ in jobs}
    for rule in ("report", "claims", "batista2011_filter_cost"):
        assert rule in rules, rule
    # one CPU per SLURM job: `cores: 1` caps every rule's threads, the timing benchmarks'
    # `workflow.cores` included (a group job runs its jobs one at a time anyway)
    assert {t for *_, t in jobs} == {1}, sorted({(rule, t) for rule, _, _, t in jobs})
    # The plugin reads the cluster's limits (`scontrol show config`; it falls back to defaults
    # when that fails, as here and on a machine without SLURM), but submits nothing.
    calls = fake_slurm[1].read_text().splitlines() if fake_slurm[1].exists() else []
    submitted = [c for c in calls if c.split()[0] in ("sbatch", "srun", "scancel")]
    assert not submitted, f"a dry run submitted to SLURM: {submitted}"


def test_partition_and_account_set_in_the_profile_reach_every_job(tmp_path, fake_slurm):
    """Uncommenting the profile's slurm_partition / slurm_account lines, as its comment and
    the README say, sets them for every job: the workflow profile is not overridden by
    profiles/default, which Snakemake would load as the workflow profile otherwise."""
    text = (PROFILE / "config.yaml").read_text()
    for key, value in (("slurm_partition", "compute"), ("slurm_account", "my_project")):
        line = re.search(rf"^(\s*)# {key}: .*$", text, re.M)
        assert line, f"no commented {key} line in profiles/slurm/config.yaml"
        text = text.replace(line.group(0), f'{line.group(1)}{key}: "{value}"')
    profile = tmp_path / "profile"
    profile.mkdir()
    (profile / "config.yaml").write_text(text)
    out = dry_run(tmp_path / "work", fake_slurm, "results/claims/burkhard2024.csv", "--configfile",
                  REPO / "config" / "ci.yaml", profile=profile)
    jobs = job_blocks(out)
    assert len(jobs) > 5
    for rule, _, resources, _ in jobs:
        assert "slurm_partition=compute" in resources and "slurm_account=my_project" in resources, (rule, resources)


def test_default_config_submits_a_few_dozen_slurm_jobs(tmp_path, fake_slurm):
    """At the default (paper-scale) config the profile groups 159 rule jobs into 25 SLURM
    jobs (a few dozen, the issue's aim); every job is in a group, a local rule or a timing benchmark (a new rule
    left ungrouped would add SLURM jobs of seconds), and every rule the profile names exists."""
    out = dry_run(tmp_path, fake_slurm, "all")
    jobs = job_blocks(out)
    local = local_rules()
    assert {"all", "claims", "report", "measured_fetch", "discrepancy_profiles", "timing_stages",
            "timing_benchmark_figure"} <= local, local
    ungrouped = Counter(rule for rule, group, *_ in jobs if group is None and rule not in local)
    assert set(ungrouped) == TIMING_RULES and set(ungrouped.values()) == {1}, ungrouped
    groups = re.findall(r"Group job (\w+) \(jobs in lexicogr", out)
    slurm_jobs = len(groups) + sum(ungrouped.values())
    remote = sum(1 for rule, *_ in jobs if rule not in local)
    print(f"default config: {len(jobs)} rule jobs, {remote} not local -> {slurm_jobs} SLURM jobs {Counter(groups)}")
    assert len(jobs) > 100 and 10 <= slurm_jobs <= 30, (len(jobs), slurm_jobs, Counter(groups))
    settings = profile_settings()
    named = {g.split("=")[0] for g in settings["groups"]}
    assert named <= {rule for rule, *_ in jobs}, sorted(named - {rule for rule, *_ in jobs})
    assert {g.split("=")[1] for g in settings["groups"]} == {g.split("=")[0] for g in settings["group-components"]}
