"""Calibrations that know their quality, save and load themselves, and apply themselves.

One class per method (as imucal's ``CalibrationInfo`` subclasses), all holding the model
``z = M P(x) + b + β Δt + γ ΔT`` of :mod:`accelcal.effects` (the plain
``z = M x + b`` when no effect was fitted):

==========================  ================  =============================================
class                       ``cal_type``      made by
==========================  ================  =============================================
:class:`FullLLSCalibration`   ``full_lls``    :func:`calibrate_recording` / ``calibrate``
:class:`FullALSCalibration`   ``full_als``    (the registry's estimators,
:class:`FullNLLSCalibration`  ``full_nlls``   :mod:`accelcal.registry`)
:class:`BiasLLSCalibration`   ``bias_lls``
:class:`BiasNLLSCalibration`  ``bias_nlls``
:class:`ExtendedCalibration`  ``extended``    the discrepancy loop: base model + the named
                                              effects (``accelcal discrepancy``'s report)
==========================  ================  =============================================

A class declares its method-specific keys once, as its own dataclass fields;
:func:`calibrate_poses` fills them from the estimator result's attributes of the same
names, and a file's class is found from its ``cal_type`` among the subclasses
(:func:`calibration_class`), so a new estimator's class needs no table here.

Apply.  :meth:`Calibration.apply` turns raw samples into calibrated specific force in
m/s²: ``y = M⁻¹(z - b - β Δt - γ ΔT)``, then per axis ``P_j(x_j) = y_j`` solved for
``x_j`` (Newton; exact at once without polynomial effects), with ``Δt = t - t_ref`` and
``ΔT = T - T_ref`` against the references of the calibration session.  Raw data must be
in the unit the calibration was fitted in (``unit``: m/s² or counts; g and mg are
converted, counts against an m/s² calibration only through the calibration's own
nominal conversion, ``input_offset``/``input_sensitivity``).

File format (JSON, ``format: accelcal-calibration``, ``format_version`` below).  The keys
the CLI always wrote keep their meaning (``method``, ``g``, ``n_poses``, ``bias``, ``M``,
``scale_factors``, ``nonorthogonality_deg``, ``residual_rms``, ``residuals``,
``standard_errors``, ``poses``, ...); new ones: ``cal_type``, ``unit`` and ``units``
(every quantity's unit spelled out: ``M`` and ``gain`` are counts per m/s² for raw
counts, dimensionless for m/s²), ``gain``, ``quality`` (:mod:`accelcal.quality`),
``standard_errors_noise``, ``effects``, ``input``, ``static``.  :func:`load_calibration`
reads it (and older files without a version: format 0), and also the report of
``accelcal discrepancy`` (its ``model_after``: base model + named effects).  A newer
format version than this code knows is refused with the version it needs.
"""

from .base import (APPLICABLE_EFFECTS, FORMAT, FORMAT_VERSION, Calibration, CalibrationFileError, EffectTerm,
                   calibration_class, load_calibration)
from .classes import (BiasLLSCalibration, BiasNLLSCalibration, ExtendedCalibration, FullALSCalibration,
                      FullLLSCalibration, FullNLLSCalibration)
from .fitting import calibrate_poses, calibrate_recording, pose_noise_std

__all__ = ["APPLICABLE_EFFECTS", "BiasLLSCalibration", "BiasNLLSCalibration", "Calibration", "CalibrationFileError",
           "EffectTerm", "ExtendedCalibration", "FORMAT", "FORMAT_VERSION", "FullALSCalibration", "FullLLSCalibration",
           "FullNLLSCalibration", "calibrate_poses", "calibrate_recording", "calibration_class", "load_calibration",
           "pose_noise_std"]
