"""Stochastic layer of the discrepancy workflow: which noise term does the simulator miss?

The Allan deviation of a recording's rests is compared with a white-noise simulator, the
missing noise term is named by a calibrated test and what it means for the static-pose
means is worked out.  The noise analysis it builds on (Allan variance, noise-term
library, simulators, Allan-deviation fit) is the core package :mod:`accelcal.noise`.

* :mod:`.layer`: the layer itself (:func:`stochastic_layer`: test, re-simulation, gap,
  homogeneity of the rests);
* :mod:`.implication`: what a noise model implies for the pose means and residuals;
* :mod:`.results`: its result classes and its error.
"""

from .implication import (
    centred_pose_variance,
    expected_residual_std,
    pose_difference_variance,
    pose_residual_implication,
)
from .layer import (
    DEFAULT_CANDIDATES,
    DEFAULT_N_BOOT,
    DEFAULT_N_RESIM,
    rest_segments,
    segment_homogeneity,
    stochastic_layer,
)
from .results import AxisStochastic, StochasticError, StochasticResult

__all__ = ["DEFAULT_CANDIDATES", "DEFAULT_N_BOOT", "DEFAULT_N_RESIM", "AxisStochastic", "StochasticError",
           "StochasticResult", "centred_pose_variance", "expected_residual_std", "pose_difference_variance",
           "pose_residual_implication", "rest_segments", "segment_homogeneity", "stochastic_layer"]
