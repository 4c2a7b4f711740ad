"""Shared by the measured_* scripts when they run standalone (outside Snakemake)."""

from __future__ import annotations

import os

from _helpers import REPO, stage_config


def measured_config() -> dict:
    """The `measured` mapping of the workflow config, with data_dir resolved against the
    project root as the rule file does."""
    m = dict(stage_config("measured"))
    m["data_dir"] = os.path.normpath(os.path.join(REPO, m["data_dir"]))
    return m
