"""Monte Carlo experiments of Batista et al. (2011), Sec. V, as pure functions returning tidy tables.

* :func:`calibration_montecarlo`: Table I (and its linear-only variant, and the full
  LLS of Burkhard et al. 2024 on the window means) on simulated stepped-table data,
  one row per run × data set × method × parameter.
* :func:`calibration_bounds`: the CRLB of the design, and :func:`asymptotic_bias`:
  the estimator's own O(σ²) bias (errors in variables), one row per parameter.
* :func:`calibration_summary`, :func:`lls_comparison`: statistics over runs.
* :func:`filter_montecarlo`: the online filter on many noise realisations of a shared
  attitude trajectory, one row per run × (decimated) time sample, plus a summary over
  runs per time sample.
* :func:`filter_example`: one run of the exact filter (its own covariance), for Figs. 4–5.
* :func:`filter_error_budget`: steady-state errors with one noise source at a time.
* :func:`observability_table`, :func:`gramian_table`: errors along and across the
  rotation axis; the observability Gramian.
* :func:`filter_cost`: wall time per step of the filter.

Every random draw comes from the ``numpy.random.Generator`` passed in.  The Monte Carlos
take one generator per run (:func:`run_streams`), so that a run's numbers do not depend
on which other runs share its job: the workflow splits the runs into chunks (separate
jobs, e.g. on a cluster) and merges them (:func:`merge_filter_moments`) to the same
tables as one job would write.

Modules: :mod:`.calibration` (the calibration experiment), :mod:`.filter` (the filter
experiments), :mod:`.shared_gain` (the many-run filter they use), :mod:`.observability`,
:mod:`.streams`.
"""

from .calibration import (DATASETS, METHODS, CalibrationDesign, asymptotic_bias, calibration_bounds,
                          calibration_design, calibration_montecarlo, calibration_summary, lls_comparison)
from .filter import (FilterMonteCarlo, FilterScenario, filter_cost, filter_error_budget, filter_example,
                     filter_montecarlo, filter_scenario, filter_summary, initial_estimate, merge_filter_moments)
from .observability import gramian_table, observability_table
from .shared_gain import shared_gain_filter
from .streams import run_streams, stream

__all__ = [
    "DATASETS",
    "METHODS",
    "CalibrationDesign",
    "FilterMonteCarlo",
    "FilterScenario",
    "asymptotic_bias",
    "calibration_bounds",
    "calibration_design",
    "calibration_montecarlo",
    "calibration_summary",
    "filter_cost",
    "filter_error_budget",
    "filter_example",
    "filter_montecarlo",
    "filter_scenario",
    "filter_summary",
    "gramian_table",
    "initial_estimate",
    "lls_comparison",
    "merge_filter_moments",
    "observability_table",
    "run_streams",
    "shared_gain_filter",
    "stream",
]
