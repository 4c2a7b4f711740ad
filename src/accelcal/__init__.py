"""accelcal: deterministic accelerometer errors (bias, scale factor, non-orthogonality and
beyond) from static poses, with the closed forms of Burkhard et al. (2024), a consistent
(ALS) correction, an iterative CasADi/IPOPT baseline and the Cramér–Rao bound.

>>> from accelcal import full_lls, bias_lls, full_nlls, bias_nlls
>>> from accelcal import ESTIMATORS        # the registry: every estimator and what it needs
>>> ESTIMATORS["full_lls"].min_poses
10

Names are loaded on first use (module ``__getattr__``, PEP 562): ``import accelcal``
imports neither numpy nor scipy, casadi, pandas or numba, so that the command line
starts at once; ``from accelcal import full_nlls`` imports what that function needs
(casadi only at its first solve).  Measured (CPU of a fresh process, median of 5):
``import accelcal`` 0.054 s, every public name imported at once 0.217 s, ``accelcal
--help`` 0.096 s: importing the names here would add 0.16 s to every command.

A recording, calibrated, saved, loaded and applied:

>>> import accelcal
>>> rec = accelcal.read("session.csv")                          # any supported format
>>> cal, poses = accelcal.calibrate_recording(rec, 9.80665, "full_lls")
>>> cal.quality.warnings                                         # () when the fit can be trusted
>>> cal.save("calibration.json")
>>> accelcal.load_calibration("calibration.json").apply(rec.acc, t=rec.t, temp=rec.temp)
"""

from __future__ import annotations

import importlib

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

from .registry import ESTIMATORS, resolve

__version__ = "0.1.0"


def _estimator_functions() -> dict[str, str]:
    """Public name -> ``'module:function'`` of every registered estimator of pose means and
    of its batched form (the registry is the one list of them; the gyroscope's estimators
    are in :mod:`accelcal.gyro`)."""
    return {path.partition(":")[2]: path for e in ESTIMATORS.values() if e.data == "poses"
            for path in (e.function, e.batch) if path}


#: Public name -> submodule that defines it (imported on first access); the estimators
#: come from the registry (:func:`_estimator_functions`).
_LAZY = {
    "m_from_params": "model", "params_from_m": "model",
    "nlls_batch": "nlls",
    "BatchResult": "results", "CalibrationResult": "results", "LLSResult": "results", "NLLSResult": "results",
    "CramerRaoBound": "uncertainty", "crlb": "uncertainty", "crlb_mean": "uncertainty",
    "Calibration": "calibration", "calibrate_recording": "calibration", "load_calibration": "calibration",
    "read": "formats",
}


def __getattr__(name: str):
    functions = _estimator_functions()
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    elif name in functions:
        value = resolve(functions[name])
    else:
        try:  # a submodule: accelcal.nlls, accelcal.batista, ...
            value = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


__all__ = sorted([
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
    "crlb",
    "crlb_mean",
    "m_from_params",
    "nlls_batch",
    "params_from_m",
    *_estimator_functions(),
])
