"""Shared wiring of the Batista (2011) scripts: the stage's config and standalone defaults.

Outside Snakemake (``.venv/bin/python workflow/scripts/batista2011_<x>.py`` from the
repository root) a script uses ``config["batista2011"]`` of config/config.yaml (or of
$ACCELCAL_CONFIG) and the workflow's default paths.
"""

from __future__ import annotations

from _helpers import mock_snakemake, write_csv
from _helpers import stage_config as _stage_config

#: Tables of the stage (default paths, relative to the working directory).
OUT = "results/batista2011"
TABLES = {
    "errors": f"{OUT}/calibration_errors.csv.gz",
    "bounds": f"{OUT}/calibration_bounds.csv",
    "summary": f"{OUT}/calibration_summary.csv",
    "comparison": f"{OUT}/calibration_lls_comparison.csv",
    "filter_runs": f"{OUT}/filter_runs.csv.gz",
    "filter_summary": f"{OUT}/filter_summary.csv.gz",
    "filter_example": f"{OUT}/filter_example.csv.gz",
    "error_budget": f"{OUT}/filter_error_budget.csv",
    "filter_cost": f"{OUT}/filter_cost.csv",
    "observability": f"{OUT}/observability.csv",
    "gramian": f"{OUT}/gramian.csv",
}


def stage_config() -> dict:
    return _stage_config("batista2011")


def standalone(rule: str, input=None, output=None, **params):
    """``snakemake`` stand-in with ``params.cfg`` = the stage config."""
    return mock_snakemake(rule, input=input, output=output, params={"cfg": stage_config(), **params})


write_table = write_csv
