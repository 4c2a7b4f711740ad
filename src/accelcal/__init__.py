"""accelcal: deterministic accelerometer errors (bias, scale factor, non-orthogonality and
beyond) from static poses, with the closed forms of Burkhard et al. (2024), a consistent
(ALS) correction, an iterative CasADi/IPOPT baseline and the Cramér–Rao bound.

>>> from accelcal import full_lls, bias_lls, full_nlls, bias_nlls
"""

from .als import full_als
from .errors import (
    AccelcalError,
    DegeneratePosesError,
    InputShapeError,
    NonFiniteError,
    NotConvergedError,
    NotPositiveDefiniteError,
    RecordingError,
    TooFewPosesError,
)
from .lls import bias_lls, bias_lls_batch, full_lls, full_lls_batch
from .model import m_from_params, params_from_m
from . import nlls
from .nlls import bias_nlls, full_nlls, nlls_batch
from .results import BatchResult, CalibrationResult, LLSResult, NLLSResult
from .uncertainty import CramerRaoBound, crlb, crlb_mean

__version__ = "0.1.0"

#: Estimators by the names the CLI and the workflow use.
ESTIMATORS = {
    "full-lls": full_lls,
    "full-als": full_als,
    "full-nlls": full_nlls,
    "bias-lls": bias_lls,
    "bias-nlls": bias_nlls,
}

__all__ = [
    "ESTIMATORS",
    "AccelcalError",
    "BatchResult",
    "CalibrationResult",
    "CramerRaoBound",
    "DegeneratePosesError",
    "InputShapeError",
    "LLSResult",
    "NLLSResult",
    "NonFiniteError",
    "NotConvergedError",
    "NotPositiveDefiniteError",
    "RecordingError",
    "TooFewPosesError",
    "bias_lls",
    "bias_lls_batch",
    "bias_nlls",
    "crlb",
    "crlb_mean",
    "full_als",
    "full_lls",
    "full_lls_batch",
    "full_nlls",
    "m_from_params",
    "nlls_batch",
    "params_from_m",
]
