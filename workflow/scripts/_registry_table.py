"""The estimator registry's table as the workflow reads it while it is parsed.

The registry (:mod:`accelcal.registry`) is built from ``src/accelcal/estimators.json``; the
workflow reads the same file as plain JSON (standard library only), so that parsing it (every
``snakemake`` call and every SLURM job) imports no accelcal module: the config check's
estimator names and the Burkhard grid's pose minima (``_burkhard2024_points.py``) come from
the registry's own rows, not from a copy.
"""

from __future__ import annotations

import json
from pathlib import Path

#: The estimator registry's table (accelcal.registry.TABLE_PATH: the file it is built from).
ESTIMATOR_TABLE = Path(__file__).resolve().parents[2] / "src" / "accelcal" / "estimators.json"


def accelerometer_estimators(table_path: Path = ESTIMATOR_TABLE) -> dict[str, dict]:
    """``{name: {"model", "fewest"}}`` of the registry's accelerometer estimators, in the
    registry's order; fewest poses: the row's ``min_poses`` (accelcal.registry.Estimator.min_poses,
    the same number: the rule lives in the table, not in either reader)."""
    with open(table_path, encoding="utf-8") as f:
        table = json.load(f)
    return {e["name"]: {"model": e["model"], "fewest": e["min_poses"]}
            for e in table["estimators"] if e["sensor"] == "accelerometer"}
