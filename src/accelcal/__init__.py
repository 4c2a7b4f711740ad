"""accelcal: deterministic accelerometer errors (bias, scale factor, non-orthogonality and
beyond) from static poses, with the closed forms of Burkhard et al. (2024), a consistent
(ALS) correction, an iterative CasADi/IPOPT baseline and the Cramér–Rao bound.

>>> from accelcal import full_lls, bias_lls, full_nlls, bias_nlls

A recording, calibrated, saved, loaded and applied:

>>> import accelcal
>>> rec = accelcal.read("session.csv")                          # any supported format
>>> cal, poses = accelcal.calibrate_recording(rec, 9.80665, "full_lls")
>>> cal.quality.warnings                                         # () when the fit can be trusted
>>> cal.save("calibration.json")
>>> accelcal.load_calibration("calibration.json").apply(rec.acc, t=rec.t, temp=rec.temp)
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
from . import registry as _registry
from .calibration import Calibration, calibrate_recording, load_calibration
from .readers import read

__version__ = "0.1.0"

#: Estimator functions by the names the CLI uses, from the one registry (accelcal.registry).
ESTIMATORS = {e.cli_name: e.load() for e in _registry.ESTIMATORS.values()}

__all__ = [
    "ESTIMATORS",
    "Calibration",
    "calibrate_recording",
    "load_calibration",
    "read",
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
