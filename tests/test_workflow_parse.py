"""What parsing the workflow costs and reads: the reproductions (accelcal_repro) it imports
while the Snakefile is parsed (each `snakemake` call, dry runs and every SLURM job, parses
it), and the compile job ahead of the jobs that call compiled kernels."""

import json
import subprocess
import sys

from tests.configs import CI_CONFIG, REPO

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
print(json.dumps({"modules": sorted(m for m in sys.modules if m.startswith("accelcal_repro.")
                                    and m.count(".") >= 1 and not m.endswith("__init__")),
                  "kernel_cache_users": cache}))
"""

#: The reproductions' modules the parse imports, each for a reason the stage files give:
#: the Burkhard grid points (one job per point: which pose counts each method allows, from
#: the core's registry).  The stage checks import nothing else (the first-call names and the
#: section list's pose count are checked by their jobs); a new parse-time import of a
#: reproduction shows here.
PARSE_IMPORTS = {"accelcal_repro.burkhard2024.grid"}

#: The jobs that call compiled kernels (each waits for the numba cache to be filled); the
#: Burkhard Monte Carlo runs the numpy implementations (`mc_kernels: numpy`) and does not wait.
KERNEL_USERS = {"burkhard2024_timing_run", "timing_filters", "batista2011_calibration_mc",
                "batista2011_filter_mc", "batista2011_error_budget", "batista2011_filter_example",
                "batista2011_filter_cost", "batista2011_observability_mc", "tereshkov_simulate", "tereshkov_sweep",
                "tereshkov_comparison", "measured_calibrate", "discrepancy_chunk", "discrepancy_session",
                "discrepancy_few_poses", "discrepancy_profiles"}


def test_the_parse_imports_only_the_reproduction_tables_the_dag_needs():
    out = subprocess.run([sys.executable, "-c", PARSE, str(REPO), str(CI_CONFIG)], capture_output=True, text=True,
                         cwd=REPO, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    leaves = {m for m in got["modules"] if not any(o.startswith(m + ".") for o in got["modules"])}
    assert PARSE_IMPORTS <= leaves, PARSE_IMPORTS - leaves
    # what those modules import in turn is allowed; no other leaf of the reproductions
    extra = {m for m in leaves - PARSE_IMPORTS
             if not m.startswith(("accelcal_repro.measured.", "accelcal_repro.montecarlo"))}
    assert not extra, extra
    assert set(got["kernel_cache_users"]) == KERNEL_USERS
