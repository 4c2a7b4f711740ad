"""Measured data: calibration of public real-IMU recordings and its evaluation without ground truth.

Modules: :mod:`~accelcal_repro.measured.data` (fetch and verify the recordings),
:mod:`~accelcal_repro.measured.sources` (which recording is which, readers, canonical CSV),
:mod:`~accelcal_repro.measured.calibrate` (poses → estimators → tidy tables),
:mod:`~accelcal.evaluation` (χ² against the pose noise, leave-one-pose-out,
bootstrap over poses, agreement), :mod:`~accelcal_repro.measured.peer` (imucal's Ferraris
calibration, imported lazily), :mod:`~accelcal_repro.measured.claims` (ledger rows) and
:mod:`~accelcal_repro.measured.figures` (matplotlib, imported lazily).
"""

from .data import DATASETS, DatasetError, fetch_file
from .sources import SOURCES, fetch_source

__all__ = ["DATASETS", "SOURCES", "DatasetError", "fetch_file", "fetch_source"]
