"""Discrepancy workflow: where simulation and measured data disagree, and which effect is missing.

Deterministic layer (pose residuals): :func:`discrepancy` fits the base model of Burkhard
et al. (2024) and tests a library of candidate effects (:mod:`.effects`) as nested
extensions (:mod:`.fit`, on the pose data of :mod:`.poses` and the model's residuals of
:mod:`.residuals`), by default under the wander null: white per-pose noise plus a bias
wander or a per-placement offset estimated jointly with the calibration (:mod:`.wander_model`),
tests calibrated by a parametric bootstrap, outlier poses against the exact null of the
largest studentised residual.  :mod:`.detect` chooses the loop of the null:
:mod:`.wander_loop` (wander, its statistics in the subpackage :mod:`.wander`) or
:mod:`.white_loop` (white); what both share is one module per job: the decision
:mod:`.rules`, the :mod:`.statistics` (gap, Holm, the MDE's non-centrality), the
:mod:`.identifiability` checks before any test and the :mod:`.results` (candidate rows,
outliers, the result and its JSON); :mod:`.schema` defines every status value of the report.

Stochastic layer (rest data): :func:`stochastic_layer` compares the Allan deviation of
the measured rests with the simulator's noise model, names the missing noise term and
re-simulates (the subpackage :mod:`.stochastic`, on the noise analysis of
:mod:`accelcal.noise`).

:func:`discrepancy_report` runs both layers on a recording (:mod:`.report`, the
``accelcal discrepancy`` command) and joins them (:mod:`.noise_implication`, with the
wander's :mod:`.allan_check`); its result :class:`DiscrepancyReport` is in :mod:`.results`;
:mod:`.figures` draws them.  The
benchmark is ``accelcal_repro.discrepancy``.
"""

from .wander import WanderError, WanderFit
from .detect import discrepancy
from .figures import plot_allan
from .fit import PoseData, fit, pose_data, pose_data_from_static
from .identifiability import identifiability
from .report import discrepancy_report
from .results import DiscrepancyReport, DiscrepancyResult
from .rules import NULLS, Rules
from .stochastic import (
    DEFAULT_CANDIDATES,
    StochasticError,
    StochasticResult,
    expected_residual_std,
    rest_segments,
    stochastic_layer,
)

__all__ = [
    "NULLS",
    "WanderError",
    "WanderFit",
    "DiscrepancyReport",
    "DiscrepancyResult",
    "PoseData",
    "Rules",
    "discrepancy_report",
    "discrepancy",
    "fit",
    "identifiability",
    "pose_data",
    "pose_data_from_static",
    "DEFAULT_CANDIDATES",
    "StochasticError",
    "StochasticResult",
    "expected_residual_std",
    "plot_allan",
    "rest_segments",
    "stochastic_layer",
]
