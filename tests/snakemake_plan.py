"""What a dry run (`snakemake -n`) of the repository's workflow would run, computed in this
process through Snakemake's Python API: the same parse, DAG and rerun decisions as the
command line, without a Snakemake process per case (each costs ~1.4 s of CPU to start,
~0.55 s of it the SLURM executor plugin importing pandas, before it parses anything).

What only the command line shows (its one-line error, its exit status, its output) stays
tested through a subprocess: tests/test_config_schemas.py, tests/test_resilience.py."""

from collections import Counter
from pathlib import Path

import yaml
from snakemake.api import SnakemakeApi
from snakemake.settings.enums import Quietness, RerunTrigger
from snakemake.settings.types import (ConfigSettings, DAGSettings, DeploymentSettings, OutputSettings,
                                      ResourceSettings, StorageSettings, WorkflowSettings)

REPO = Path(__file__).resolve().parents[1]
#: The workflow profile the command line picks up (profiles/default/ beside the Snakefile).
PROFILE = REPO / "profiles" / "default" / "config.yaml"
#: Its keys that change which jobs a dry run plans, as DAGSettings fields.
PROFILE_DAG_KEYS = {"rerun-incomplete": "force_incomplete"}
#: Its keys that do not: how jobs run, not which (a new key must be placed in one of the two).
PROFILE_RUN_KEYS = {"cores", "scheduler", "printshellcmds", "keep-going", "latency-wait", "show-failed-logs",
                    "default-resources"}


def profile_dag_settings() -> dict:
    """The DAG settings the command line takes from the profile."""
    profile = yaml.safe_load(PROFILE.read_text())
    unknown = set(profile) - set(PROFILE_DAG_KEYS) - PROFILE_RUN_KEYS
    assert not unknown, f"{PROFILE}: does {sorted(unknown)} change the plan? Place it in tests/snakemake_plan.py"
    return {field: profile[key] for key, field in PROFILE_DAG_KEYS.items() if key in profile}


def planned_jobs(workdir, targets, configfiles=(), snakefile=REPO / "Snakefile", rerun_triggers=None,
                 replace_config=False) -> dict[int, tuple[str, tuple[str, ...]]]:
    """``{jobid: (rule, outputs)}`` of the jobs `snakemake -n TARGETS` plans in ``workdir``
    (what the dry run's job blocks list: tests/test_resilience.jobs_in), with the default
    profile's settings that decide the plan (an interrupted job's outputs are redone).  A
    broken config or a missing input raises Snakemake's own exception (WorkflowError,
    MissingInputException).
    ``rerun_triggers``: names as on the command line (``["params"]``)."""
    dag = {**profile_dag_settings(), "targets": set(map(str, targets))}
    if rerun_triggers is not None:
        dag["rerun_triggers"] = {RerunTrigger.parse_choice(t) for t in rerun_triggers}
    with SnakemakeApi(OutputSettings(quiet={Quietness.ALL})) as api:
        wf = api.workflow(resource_settings=ResourceSettings(cores=1), storage_settings=StorageSettings(),
                          config_settings=ConfigSettings(configfiles=[Path(c) for c in configfiles],
                                                         replace_workflow_config=replace_config),
                          workflow_settings=WorkflowSettings(), deployment_settings=DeploymentSettings(),
                          snakefile=Path(snakefile), workdir=Path(workdir))
        wf.dag(DAGSettings(**dag)).execute_workflow(executor="dryrun")
        # the DAG outlives the dry run, in which every job it would run was "finished"
        # (the dry run's executor); the jobs up to date were not
        return {job.jobid: (job.rule.name, tuple(map(str, job.output))) for job in wf._workflow.dag.finished_jobs}


def rule_counts(jobs) -> dict[str, int]:
    """``{rule: jobs}``, the dry run's 'Job stats' table."""
    return dict(Counter(rule for rule, _ in jobs.values()))
