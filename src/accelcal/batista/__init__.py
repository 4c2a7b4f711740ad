"""Batista, Silvestre, Oliveira, Cardeira (2011): table calibration and online bias/gravity filter.

* :mod:`~accelcal.batista.model`: eq. (2) ``a_m = F [a + F2 a²] + b + n``, rotations;
* :mod:`~accelcal_repro.batista2011.trajectory`: stepped table attitudes, continuous attitudes;
* :mod:`~accelcal.batista.calibration`: Table I (SVD null vectors, quadratic iteration);
* :mod:`~accelcal.batista.crlb`: Cramér–Rao bound of the calibration design;
* :mod:`~accelcal.batista.filter`: the Kalman filter of eq. (7), exact discretisation;
* :mod:`~accelcal_repro.batista2011.montecarlo`: Monte Carlo experiments as tidy tables;
* :mod:`~accelcal_repro.batista2011.claims`, :mod:`~accelcal_repro.batista2011.figures`,
  :mod:`~accelcal_repro.batista2011.experiment`: ledger rows, figures, config → experiments.

>>> from accelcal.batista import calibrate, kalman_filter
"""

from .calibration import (PARAMETERS, TableCalibration, TableCalibrationBatch, WindowStatistics, calibrate,
                          calibrate_batch)
from .crlb import CalibrationBound, calibration_crlb
from .filter import STATES, FilterResult, covariance_sequence, kalman_filter, observability_gramian
from .model import accelerometer_output, correct_measurement

__all__ = [
    "PARAMETERS",
    "STATES",
    "CalibrationBound",
    "FilterResult",
    "TableCalibration",
    "TableCalibrationBatch",
    "WindowStatistics",
    "accelerometer_output",
    "calibrate",
    "calibrate_batch",
    "calibration_crlb",
    "correct_measurement",
    "covariance_sequence",
    "kalman_filter",
    "observability_gramian",
]
