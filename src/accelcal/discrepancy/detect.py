"""The deterministic layer: which candidate effect do the pose residuals ask for?

Two noise models for the null hypothesis (``Rules.null``).  ``wander`` (the default):
white per-pose noise times a common scale plus a bias wander estimated jointly with the
calibration, likelihood-ratio tests calibrated by a parametric bootstrap, outlier poses,
ambiguity between candidates and with the wander (:mod:`.wander`, :mod:`.wander_loop`).
``white``: white per-pose noise times a common scale and F-tests (:mod:`.white_loop`,
the benchmark's negative control: on sessions whose bias wanders it names
``bias_drift`` far more often than α).  Both share the identifiability checks, the
result class and its JSON (:mod:`.rules`, :mod:`.results`).

:func:`discrepancy` runs the loop of the null ``rules.null`` chooses.
"""

from __future__ import annotations

from ..threads import one_blas_thread
from .fit import PoseData
from .results import DiscrepancyResult
from .rules import Rules
from .wander_loop import discrepancy_wander
from .white_loop import discrepancy_white


@one_blas_thread  # small stacked eigenproblems: threads only spin (accelcal.threads)
def discrepancy(data: PoseData, rules: Rules | None = None, report: bool = True) -> DiscrepancyResult:
    """Run the deterministic layer (module docstring) on one pose set.

    ``report=False``: the decisions without what only a report shows (wander null: the
    final noise model's intervals and excess reading, :func:`~.wander_loop.discrepancy_wander`;
    white null: the LOPO gaps and estimates of candidates that cannot pass,
    :func:`~.white_loop.discrepancy_white`): a benchmark's detection.

    Raises
    ------
    AccelcalError
        The base model cannot be fitted (too few or degenerate poses: the full model
        needs at least 10).
    """
    rules = rules or Rules()
    if rules.null == "wander":
        return discrepancy_wander(data, rules, report)
    return discrepancy_white(data, rules, report)


__all__ = ["discrepancy"]
