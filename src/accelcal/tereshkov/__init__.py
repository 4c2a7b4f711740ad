"""Tereshkov, "An intuitive approach to inertial sensor bias estimation": a strapdown AHRS
with a GNSS-aided "virtual platform" whose residual torques give closed-form gyro and
accelerometer bias estimates (eqs. 1–3, 12, 14), on simulated land-vehicle runs.

>>> from accelcal.tereshkov import TereshkovParams, run_estimator

Modules: :mod:`.estimator` (the estimator, batched over runs), :mod:`.rotations`,
:mod:`.errors`.  The paper's simulated land-vehicle runs (vehicle, Monte Carlo,
claims, figures, comparison with the Batista 2011 filter) are reproduced in
:mod:`accelcal_repro.tereshkov`.
"""

from .errors import InvalidParameterError
from .estimator import (EstimatorState, TereshkovParams, TereshkovResult, accel_bias_from_torque,
                        G, concat_results, initial_state, run_estimator, steady_state_torque)

__all__ = [
    "EstimatorState",
    "G",
    "InvalidParameterError",
    "TereshkovParams",
    "TereshkovResult",
    "accel_bias_from_torque",
    "concat_results",
    "initial_state",
    "run_estimator",
    "steady_state_torque",
]
