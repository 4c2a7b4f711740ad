"""The SLURM profile (profiles/slurm/): the executor plugin pinned in environment.lock
imports, and the whole CI workflow's DAG builds with the profile in dry-run mode without
calling any SLURM command."""

import os
import re
import stat
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
PROFILE = REPO / "profiles" / "slurm"
SLURM_COMMANDS = ("sbatch", "squeue", "sacct", "sinfo", "scancel", "sacctmgr", "srun", "scontrol")


def test_plugin_is_pinned_and_imports():
    import snakemake_executor_plugin_slurm  # noqa: F401

    assert "\nsnakemake-executor-plugin-slurm==" in (REPO / "environment.lock").read_text()


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


def dry_run(workdir, fake_slurm, *args):
    bindir, _ = fake_slurm
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ['PATH']}"}
    cmd = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
           "--profile", str(PROFILE), "-n", *args]
    return subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)


def test_dag_builds_with_the_slurm_profile_in_dry_run(tmp_path, fake_slurm):
    # --cores 8: a login node with 8 cores, so that the timing jobs' `threads: workflow.cores`
    # asks for more than the profile's max-threads allows
    proc = dry_run(tmp_path, fake_slurm, "all", "--configfile", REPO / "config" / "ci.yaml", "--cores", "8")
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-4000:]
    assert "This was a dry-run" in out
    for rule in ("report", "claims", "batista2011_filter_cost"):
        assert f"rule {rule}:" in out, rule
    # every job within the profile's cap; the timing jobs capped, not given the login node
    cap = yaml.safe_load((PROFILE / "config.yaml").read_text())["max-threads"]
    threads = [int(t) for t in re.findall(r"^\s+threads: (\d+)$", out, re.M)]
    assert threads and max(threads) == cap < 8
    block = out[out.index("rule batista2011_filter_cost:"):]
    assert f"threads: {cap}\n" in block[:block.index("\n\n")], block[:600]
    # The plugin reads the cluster's limits (`scontrol show config`; it falls back to defaults
    # when that fails, as here and on a machine without SLURM), but submits nothing.
    calls = fake_slurm[1].read_text().splitlines() if fake_slurm[1].exists() else []
    submitted = [c for c in calls if c.split()[0] in ("sbatch", "srun", "scancel")]
    assert not submitted, f"a dry run submitted to SLURM: {submitted}"
