"""Wiring shared by the workflow scripts: logging, atomic table writes, and a mock of
the ``snakemake`` object so that every script also runs standalone (pypsa-eur style)::

    cd /work/main && .venv/bin/python workflow/scripts/foundation_claims.py

Standalone runs read config/config.yaml next to the workflow (or the file named by
$ACCELCAL_CONFIG) and use the workflow's default paths relative to the current directory.
"""

from __future__ import annotations

import gzip
import logging
import os
import sys
from pathlib import Path

import yaml

from accelcal.atomic import atomic_output

REPO = Path(__file__).resolve().parents[2]


class _Named(list):
    """A list whose items are also attributes, like Snakemake's input/output/log."""

    def __init__(self, items=None, **named):
        super().__init__(list(items or []) + list(named.values()))
        self.__dict__.update(named)


def load_config(path: str | os.PathLike | None = None) -> dict:
    path = Path(path or os.environ.get("ACCELCAL_CONFIG") or REPO / "config" / "config.yaml")
    with open(path) as f:
        return yaml.safe_load(f)


def mock_snakemake(rule: str, input=None, output=None, params=None, log=None, wildcards=None, threads=1):
    """Stand-in for the ``snakemake`` object of a script run outside Snakemake."""
    from types import SimpleNamespace

    def named(x):
        return _Named(x) if isinstance(x, (list, tuple)) else _Named(**(x or {}))

    return SimpleNamespace(rule=rule, input=named(input), output=named(output), params=named(params),
                           log=named(log or [f"results/logs/{rule}.log"]), wildcards=named(wildcards),
                           threads=threads, config=load_config())


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


def stage_config(stage: str) -> dict:
    """``config[stage]`` of the workflow config (for scripts run standalone)."""
    return load_config()[stage]


def write_csv(df, path: str | os.PathLike, **kwargs) -> Path:
    """Write a CSV atomically: a temporary file in the target directory, then rename.

    A name ending in ``.gz`` is gzip-compressed with an empty file name and no time stamp
    in the gzip header, so that rerunning a job gives byte-identical files.
    """
    path = Path(path)
    with atomic_output(path) as tmp:
        if path.name.endswith(".gz"):
            text = df.to_csv(index=False, **kwargs).encode()
            with open(tmp, "wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as gz:
                gz.write(text)
        else:
            df.to_csv(tmp, index=False, **kwargs)
    return path
