"""Tereshkov, "An intuitive approach to inertial sensor bias estimation": a strapdown AHRS
with a GNSS-aided "virtual platform" whose residual torques give closed-form gyro and
accelerometer bias estimates (eqs. 1–3, 12, 14), on simulated land-vehicle runs.

>>> from accelcal.tereshkov import TereshkovParams, run_estimator
>>> from accelcal.tereshkov.montecarlo import run_scenario, convergence_summary

Modules: :mod:`.vehicle` (tractor paths, IMU and GNSS synthesis), :mod:`.estimator`
(the estimator, batched over runs), :mod:`.montecarlo` (tidy tables, convergence
metrics, installation sweep), :mod:`.claims` (ledger rows), :mod:`.figures`,
:mod:`.comparison` (against the Batista 2011 Kalman filter).
"""

from .errors import InvalidParameterError
from .estimator import (EstimatorState, TereshkovParams, TereshkovResult, accel_bias_from_torque,
                        concat_results, initial_state, run_estimator, steady_state_torque)
from .vehicle import (G, Path, SensorSpec, VehicleBatch, VehicleState, field_path, installation_dcm,
                      sensor_chunks, stack_paths, straight_path, vehicle_state)

__all__ = [
    "EstimatorState",
    "G",
    "InvalidParameterError",
    "Path",
    "SensorSpec",
    "TereshkovParams",
    "TereshkovResult",
    "VehicleBatch",
    "VehicleState",
    "accel_bias_from_torque",
    "concat_results",
    "field_path",
    "initial_state",
    "installation_dcm",
    "run_estimator",
    "sensor_chunks",
    "stack_paths",
    "steady_state_torque",
    "straight_path",
    "vehicle_state",
]
