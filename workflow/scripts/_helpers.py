"""Wiring shared by the workflow scripts: logging, atomic table writes, and a mock of
the ``snakemake`` object so that every script also runs standalone (pypsa-eur style)::

    cd /work/main && .venv/bin/python workflow/scripts/foundation_claims.py

Standalone runs build the rule's job from the Snakefile (:func:`mock_snakemake`), with
config/config.yaml extended by the file named in $ACCELCAL_CONFIG (e.g. config/ci.yaml),
and use the rule's paths relative to the current directory.
"""

from __future__ import annotations

import gzip
import json
import logging
import os
import sys
from pathlib import Path
from types import SimpleNamespace

import yaml

from accelcal.atomic import atomic_output

REPO = Path(__file__).resolve().parents[2]


def load_config(path: str | os.PathLike | None = None) -> dict:
    """The workflow config as Snakemake builds it: config/config.yaml, extended key by key
    by ``path`` (or $ACCELCAL_CONFIG), like ``--configfile``."""
    from snakemake.utils import update_config

    with open(REPO / "config" / "config.yaml") as f:
        config = yaml.safe_load(f)
    overlay = path or os.environ.get("ACCELCAL_CONFIG")
    if overlay:
        with open(overlay) as f:
            update_config(config, yaml.safe_load(f) or {})
    return config


def mock_snakemake(rule: str, configfile: str | os.PathLike | None = None, **wildcards):
    """The ``snakemake`` object of ``rule`` for a script run outside Snakemake (pypsa-eur's
    pattern): the Snakefile is parsed and the rule's job built, so its input, output, params,
    log and threads are the workflow's own (one place for paths).

    Parameters
    ----------
    rule : str
        Rule name.
    configfile : path, optional
        Config overlay, as ``--configfile`` (default: $ACCELCAL_CONFIG, else none).
    **wildcards
        Values of the rule's wildcards (e.g. ``chunk="0"``).

    Paths are relative to the current directory, which plays the role of
    ``snakemake --directory``: run the script from the repository root (or a work folder).
    """
    import snakemake as sm
    from snakemake.api import SnakemakeApi
    from snakemake.iocontainers import Snakemake
    from snakemake.settings.types import (
        ConfigSettings,
        DAGSettings,
        DeploymentSettings,
        OutputSettings,
        ResourceSettings,
        StorageSettings,
        WorkflowSettings,
    )

    overlay = configfile or os.environ.get("ACCELCAL_CONFIG")
    cwd = Path.cwd()
    try:
        with SnakemakeApi(OutputSettings()) as api:
            workflow = api.workflow(
                resource_settings=ResourceSettings(cores=1), storage_settings=StorageSettings(),
                config_settings=ConfigSettings(configfiles=[Path(overlay).resolve()] if overlay else []),
                workflow_settings=WorkflowSettings(), deployment_settings=DeploymentSettings(),
                snakefile=REPO / "Snakefile", workdir=cwd)._workflow
            workflow.dag_settings = DAGSettings(rerun_triggers=[])
            workflow.global_resources = {}
            job = sm.jobs.Job(workflow.get_rule(rule), sm.dag.DAG(workflow, rules=[workflow.get_rule(rule)]),
                              wildcards)
            smk = Snakemake(job.input, job.output, job.params, job.wildcards, job.threads, job.resources, job.log,
                            workflow.config, rule, None)
    finally:
        os.chdir(cwd)  # the API changes into the work directory
    for path in [*smk.log, *smk.output]:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
    return smk


def mock_snakemake_from_argv(default_rule: str, **default_wildcards):
    """:func:`mock_snakemake` for a script run from the command line::

        python workflow/scripts/SCRIPT.py [RULE] [WILDCARD=VALUE ...]

    RULE defaults to ``default_rule`` (scripts shared by several rules, such as the figure
    scripts, take the rule's name); wildcards not given take ``default_wildcards``."""
    args = sys.argv[1:]
    rule = args.pop(0) if args and "=" not in args[0] else default_rule
    wildcards = {**default_wildcards, **dict(a.split("=", 1) for a in args)}
    return mock_snakemake(rule, **wildcards)


def stage_figures(snakemake):
    """``(figure id, input, output)`` for each figure of a stage's figure job (common.smk's
    stage_figures): ``input`` holds that figure's named inputs under their own keys and
    ``output`` its ``png`` and ``pdf`` paths."""
    for fid in snakemake.params.figures:
        prefix = f"{fid}__"
        inp = SimpleNamespace(**{k.removeprefix(prefix): v for k, v in snakemake.input.items() if k.startswith(prefix)})
        out = SimpleNamespace(png=getattr(snakemake.output, f"{prefix}png"),
                              pdf=getattr(snakemake.output, f"{prefix}pdf"))
        yield fid, inp, out


def configure_logging(snakemake, level=logging.INFO) -> logging.Logger:
    """Log to the job's log file (and stderr) once; uncaught exceptions are logged too."""
    logfile = Path(snakemake.log[0])
    logfile.parent.mkdir(parents=True, exist_ok=True)
    logging.basicConfig(level=level, force=True, format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        handlers=[logging.FileHandler(logfile, mode="w"), logging.StreamHandler(sys.stderr)])
    logging.captureWarnings(True)
    log = logging.getLogger(snakemake.rule)

    def excepthook(kind, value, tb):
        log.error("uncaught exception", exc_info=(kind, value, tb))

    sys.excepthook = excepthook
    return log


def write_csv(df, path: str | os.PathLike, **kwargs) -> Path:
    """Write a CSV atomically: a temporary file in the target directory, then rename.

    A name ending in ``.gz`` is gzip-compressed with an empty file name and no time stamp
    in the gzip header, so that rerunning a job gives byte-identical files.  Level 1: on
    the Burkhard Monte Carlo table (48 MB of CSV) level 9 took 6.1 s of CPU for 16.6 MB,
    level 1 0.4 s for 19.1 MB; over a default run's ~90 tables that is ~33 s of CPU.
    """
    path = Path(path)
    with atomic_output(path) as tmp:
        if path.name.endswith(".gz"):
            text = df.to_csv(index=False, **kwargs).encode()
            with open(tmp, "wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0,
                                                 compresslevel=1) as gz:
                gz.write(text)
        else:
            df.to_csv(tmp, index=False, **kwargs)
    return path


def dataset_dirs(manifests) -> dict[str, Path]:
    """``{dataset: folder}`` from fetch manifests: each dataset's files sit in
    ``<folder>/<dataset>/`` (the shared copy or the verified download)."""
    dirs = {}
    for path in manifests:
        m = json.loads(Path(path).read_text())
        first = next(iter(m["files"].values()))["path"]
        dirs[m["dataset"]] = Path(first).parent.parent
    return dirs
