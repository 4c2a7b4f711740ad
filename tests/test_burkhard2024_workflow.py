"""The Burkhard stage of the workflow on the CI config: the jobs, the tidy table, the
figures and their targets, the claims file, the scripts run standalone and a clean failure."""

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml


from tests.configs import ci_config

from .conftest import copy_of_ci_workflow
from .snakemake_plan import planned_jobs

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "workflow" / "scripts"))
from _burkhard2024_points import grid_points  # noqa: E402  (the workflow's split of the grid into jobs)
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
CI = REPO / "config" / "ci.yaml"
CFG = ci_config()["burkhard2024"]
FIGURES = ["fig1a", "fig1b", "fig1c", "fig1d", "fig1e", "timing", "lls_limit"]


def snakemake(workdir, *args, config=CI, timeout=600):
    cmd = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir), "--cores", "2",
           "--scheduler", "greedy", *map(str, args), "--configfile", str(config)]  # --configfile takes the rest
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def stage(ci_workflow, tmp_path_factory):
    """A copy of the session's CI run (tests/conftest.py), which holds the whole stage:
    the rerun test below rewrites files."""
    return copy_of_ci_workflow(ci_workflow, tmp_path_factory.mktemp("burkhard2024"))


def test_one_monte_carlo_job_per_grid_point(stage):
    points = grid_points(CFG["experiments"])
    logs = sorted(p.name for p in (stage / "results" / "logs" / "burkhard2024").glob("mc_*.log"))
    assert logs == sorted(f"mc_{k}.log" for k in points)
    assert len(list((stage / "results" / "benchmarks" / "burkhard2024").glob("mc_*.tsv"))) == len(points)


def test_tidy_table_one_row_per_trial_method_and_grid_point(stage):
    d = stage / "results" / "burkhard2024"
    mc = pd.read_csv(d / "mc.csv.gz")
    points = grid_points(CFG["experiments"])
    expected = CFG["trials"] * sum(len(ms) for p in points.values() for _, _, ms in p["cases"])
    assert len(mc) == expected
    assert not mc.duplicated(["data_model", "n_poses", "noise_std", "g_error", "method", "trial"]).any()
    assert mc["valid"].mean() > 0.95
    s = pd.read_csv(d / "summary.csv")
    assert (s["n_trials"] == CFG["trials"]).all()
    for name in ("comparisons", "relative_errors", "lls_limit", "lls_limit_onsets", "mc_timing_summary",
                 "timing_summary"):
        assert len(pd.read_csv(d / f"{name}.csv")), name
    t = pd.read_csv(d / "timing_summary.csv")
    assert set(t["n_poses"]) == set(CFG["timing"]["n_poses"])
    assert {"full_lls", "full_als", "full_nlls", "bias_lls", "bias_nlls", "full_lls_batch"} <= set(t["method"])


def test_every_figure_and_its_target(stage):
    figs = stage / "results" / "figures"
    for f in FIGURES:
        for ext in ("png", "pdf"):
            assert (figs / f"burkhard2024_{f}.{ext}").stat().st_size > 5000, f
    # `snakemake -n` on the figure targets plans nothing (in this process: tests/snakemake_plan.py)
    assert planned_jobs(stage, [f"burkhard2024_{f}" for f in FIGURES], [CI]) == {}


def test_claims_file(stage):
    rows = pd.read_csv(stage / "results" / "claims" / "burkhard2024.csv", dtype=str, keep_default_na=False)
    rows = rows.set_index("claim_id")
    assert len(rows) == 11 and "table1_field_tests" not in rows.index
    assert rows.loc["max_errors_scale_nonorth", "verdict"] == "not_reproduced"
    deterministic = rows.drop(index=["max_errors_scale_nonorth", "speed_full", "speed_bias"])
    assert (deterministic["verdict"] == "reproduced").all(), deterministic["verdict"]
    for cid in ("speed_full", "speed_bias"):  # wall times: computed, not asserted either way
        assert rows.loc[cid, "verdict"] in ("reproduced", "not_reproduced")
        assert rows.loc[cid, "reproduced_value"].endswith("×")
    for cid, r in rows.iterrows():
        assert (stage / r["evidence"].split(":")[0]).is_file(), (cid, r["evidence"])


def stage_outputs(stage):
    """{path: bytes} of the gather's tables and every figure of the stage (PNG and PDF)."""
    paths = [*(stage / "results" / "burkhard2024").glob("*.csv"),
             *(stage / "results" / "figures").glob("burkhard2024_*.*")]
    return {p.relative_to(stage): p.read_bytes() for p in sorted(paths)}


def test_the_scripts_standalone_are_byte_identical(stage, tmp_path):
    """The stage's scripts also run outside Snakemake (mock object) and rewrite the same
    bytes: the gather's tables and every figure.  This is also the determinism check of the
    gather and figure jobs (a second run, from the same inputs, equals the CI run's), which
    tests/test_workflow_reruns.py therefore does not force again; it forces a Monte Carlo
    job, the claims and the ledger."""
    before = stage_outputs(stage)
    assert len([p for p in before if p.suffix == ".png"]) == len(FIGURES), sorted(before)
    env = dict(os.environ, ACCELCAL_CONFIG=str(CI))
    for script in ("burkhard2024_summary.py", "burkhard2024_figure.py", "burkhard2024_claims.py"):
        proc = subprocess.run([sys.executable, str(REPO / "workflow" / "scripts" / script)], cwd=stage, env=env,
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, (script, proc.stderr[-3000:])
    after = stage_outputs(stage)
    assert after.keys() == before.keys()
    assert sorted(str(p) for p in before if before[p] != after[p]) == []


def test_a_broken_stage_config_fails_before_any_job(tmp_path):
    cfg = ci_config()
    cfg["burkhard2024"]["experiments"]["fig1cd"]["g_error"] = [0.001, 0.01]
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(cfg))
    proc = snakemake(tmp_path / "work", "burkhard2024", config=path, timeout=120)
    assert proc.returncode != 0
    lines = [ln for ln in (proc.stdout + proc.stderr).splitlines() if ln.startswith("invalid config")]
    assert len(lines) == 1 and "burkhard2024.experiments.fig1cd.g_error" in lines[0], lines
    assert not (tmp_path / "work" / "results").exists()


def test_default_config_dry_run_splits_the_grid_into_jobs(default_dry_run):
    """One Monte Carlo job per grid point of the default config, read from the session's
    dry run of `all` on the default config (tests/conftest.py), which plans this stage's
    jobs as `-n burkhard2024` does."""
    workdir, error, jobs = default_dry_run
    assert error is None, error
    default = yaml.safe_load((REPO / "config" / "config.yaml").read_text())["burkhard2024"]
    assert jobs["burkhard2024_mc"] == len(grid_points(default["experiments"]))
    assert not (workdir / "results").exists()
