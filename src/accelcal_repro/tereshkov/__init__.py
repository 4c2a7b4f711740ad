"""Reproduction of Tereshkov, "An intuitive approach to inertial sensor bias estimation",
on the estimator of :mod:`accelcal.tereshkov`: simulated tractor runs (:mod:`.vehicle`),
Monte Carlo tables, convergence metrics and the installation sweep (:mod:`.montecarlo`),
ledger rows (:mod:`.claims`), figures (:mod:`.figures`) and the comparison with the
Batista 2011 Kalman filter (:mod:`.comparison`).

>>> from accelcal_repro.tereshkov.montecarlo import run_scenario, convergence_summary
"""
