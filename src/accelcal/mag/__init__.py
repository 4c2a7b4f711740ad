"""The magnetometer, calibrated from the same session as the accelerometer.

>>> from accelcal.mag import calibrate_magnetometer
>>> mcal = calibrate_magnetometer(rec.mag, raw_unit=rec.mag_unit, acc_cal=cal, poses=poses)
>>> print(mcal.summary())            # ± on every parameter and the trust lines
>>> mcal.apply(rec.mag)              # unit field (or µT) in the accelerometer's frame

Modules: :mod:`~accelcal.mag.model` (``m_cal = R A (m_raw - b)``), :mod:`~accelcal.mag.fit`
(field samples, the Li–Griffiths closed form, maximum likelihood, the Cramér–Rao bound),
:mod:`~accelcal.mag.registry` (the estimators of field samples),
:mod:`~accelcal.mag.align` (rotation to the accelerometer and dip, Kok & Schön),
:mod:`~accelcal.mag.trust` (bad columns, noise at the rests, coverage, disturbances),
:mod:`~accelcal.mag.calibrate` (a whole session), :mod:`~accelcal.mag.result` (JSON, summary),
:mod:`~accelcal.mag.export` (PX4, ArduPilot, Magneto).
"""

from __future__ import annotations

import importlib

#: Names loaded on first use (PEP 562): the command line's help text reads
#: :mod:`~accelcal.mag.registry`, which imports this package; measured (CPU of a fresh process,
#: median of 5) ``import accelcal.mag.registry`` 0.059 s, every module named here 0.147 s,
#: against 0.095 s for the whole ``import accelcal.cli``.
_LAZY = {
    "MagModel": "model", "FieldSamples": "fit", "EllipsoidFit": "fit", "fit_ellipsoid_ml": "fit",
    "fit_ellipsoid_lg": "fit", "fit_hard_iron": "fit", "crlb": "fit", "li_griffiths": "fit",
    "align": "align", "Alignment": "align", "dip_angles": "align", "heading_deg": "align",
    "calibrate_magnetometer": "calibrate", "MagCalibration": "result", "spreads": "result",
    "MAG_ESTIMATORS": "registry", "mag_estimator": "registry", "coverage": "trust",
}


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = sorted(_LAZY)
