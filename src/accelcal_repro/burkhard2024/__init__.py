"""Reproduction of Burkhard, Sharma, Skaloud (2024), "Linear estimation of deterministic
accelerometer errors": the simulation grids of Fig. 1, the compute-time claim, and where
the closed form stops being enough.

Modules: :mod:`~accelcal_repro.burkhard2024.grid` (the experiments of Fig. 1 as product grids),
:mod:`~accelcal_repro.burkhard2024.checks` (the paper's conclusions as rules on the tables,
shared by the ledger and the tests), :mod:`~accelcal_repro.burkhard2024.analysis` (relative
errors across the noise range, the LLS limit), :mod:`~accelcal_repro.burkhard2024.claims`
(ledger rows) and :mod:`~accelcal_repro.burkhard2024.figures` (matplotlib, imported lazily).
The Monte Carlo engine is :mod:`accelcal_repro.montecarlo`, the benchmark :mod:`accelcal_repro.timing`.
"""

from .grid import EXPERIMENTS, Experiment, experiments_from_config, select

__all__ = ["EXPERIMENTS", "Experiment", "experiments_from_config", "select"]
