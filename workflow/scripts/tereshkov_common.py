"""Shared by the tereshkov_* workflow scripts: the stage config for standalone runs."""

from __future__ import annotations

from _helpers import stage_config as _stage_config
from _helpers import write_csv

#: Atomic CSV (gzip-compressed, without time stamp, if the name ends in .gz).
write_table = write_csv


def stage_config() -> dict:
    """``config["tereshkov"]`` of the workflow config."""
    return _stage_config("tereshkov")
