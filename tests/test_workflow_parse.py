"""What parsing the workflow costs and reads: no module of accelcal or of the reproductions
(accelcal_repro) is imported while the Snakefile is parsed (each `snakemake` call, dry runs
and every SLURM job, parses it: the tables the DAG needs are read as JSON), the grid split
at parse equals the registry's, and the compile job comes ahead of the jobs that call
compiled kernels."""

import json
import subprocess
import sys

from accelcal_repro.burkhard2024.grid import experiments_from_config
from accelcal_repro.montecarlo import DATA_MODELS, METHODS, min_poses

from tests.configs import CI_CONFIG, REPO, ci_config

PARSE = """
import json, sys, tempfile
from pathlib import Path
from snakemake.api import SnakemakeApi
from snakemake.settings.types import (ConfigSettings, DeploymentSettings, OutputSettings, ResourceSettings,
                                      StorageSettings, WorkflowSettings)
with SnakemakeApi(OutputSettings(quiet={"all"})) as api:
    wf = api.workflow(resource_settings=ResourceSettings(cores=1), storage_settings=StorageSettings(),
                      config_settings=ConfigSettings(configfiles=[Path(sys.argv[2])]),
                      workflow_settings=WorkflowSettings(), deployment_settings=DeploymentSettings(),
                      snakefile=Path(sys.argv[1]) / "Snakefile", workdir=Path(tempfile.mkdtemp()))._workflow
    cache = [r.name for r in wf.rules if "results/timing/kernel_cache.csv" in map(str, r.input)]
print(json.dumps({"modules": sorted(m for m in sys.modules if m.split(".")[0] in ("accelcal", "accelcal_repro")),
                  "kernel_cache_users": cache, "burkhard_points": wf.globals["BURKHARD_POINTS"]}))
"""

#: The jobs that call compiled kernels (each waits for the numba cache to be filled); the
#: Burkhard Monte Carlo runs the numpy implementations (`mc_kernels: numpy`) and does not wait.
KERNEL_USERS = {"burkhard2024_timing_run", "timing_filters", "batista2011_calibration_mc",
                "batista2011_filter_mc", "batista2011_error_budget", "batista2011_filter_example",
                "batista2011_filter_cost", "batista2011_observability_mc", "tereshkov_simulate", "tereshkov_sweep",
                "tereshkov_comparison", "measured_calibrate", "discrepancy_chunk", "discrepancy_session",
                "discrepancy_few_poses", "discrepancy_profiles"}


def test_the_parse_imports_no_accelcal_module():
    out = subprocess.run([sys.executable, "-c", PARSE, str(REPO), str(CI_CONFIG)], capture_output=True, text=True,
                         cwd=REPO, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["modules"] == [], got["modules"]
    assert set(got["kernel_cache_users"]) == KERNEL_USERS
    # the split read from the registry's table as JSON is the one its jobs check (Experiment)
    experiments = ci_config()["burkhard2024"]["experiments"]
    exps = experiments_from_config(experiments)
    want = {(e.data_model, n, s, g, m) for e in exps.values() for n in e.n_poses for s in e.noise_std
            for g in e.g_error for m in e.methods if n >= min_poses(m)}
    have = {(dm, p["n_poses"], p["noise_std"], g, m) for p in got["burkhard_points"].values()
            for dm, g, ms in p["cases"] for m in ms}
    assert have == want
    for p in got["burkhard_points"].values():
        assert [dm for dm, _, _ in p["cases"]] == [dm for dm in DATA_MODELS if dm in {c[0] for c in p["cases"]}]
        for _, _, ms in p["cases"]:
            assert ms == [m for m in METHODS if m in ms]
