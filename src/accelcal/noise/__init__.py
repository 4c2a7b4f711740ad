"""Noise analysis of inertial-sensor data: Allan variance, noise terms, simulation, fit.

The building blocks of any analysis of a sensor's noise from rest data, independent of
the calibration (the discrepancy workflow's stochastic layer,
:mod:`accelcal.discrepancy.stochastic`, is built on them):

* :mod:`.allan` — the overlapping Allan variance of segmented rest data, pooled over the
  segments, with equivalent degrees of freedom and confidence intervals
  (:func:`allan_variance` → :class:`AllanVariance`);
* :mod:`.terms` — the noise-term library (:data:`TERMS`: white, quantization, flicker
  bias instability, random walk, drift ramp, Gauss–Markov, sinusoid; IEEE Std 952
  coefficients), the Allan variance of a noise model (:func:`model_avar`) and the checks
  of a model's entries (:func:`noise_term`, :func:`term_parameters`);
* :mod:`.simulation` — sampled noise of a model (:func:`simulate_segments`,
  :func:`simulate_noise`);
* :mod:`.allan_fit` — the fit of a model's coefficients to a measured Allan variance by
  Gamma maximum likelihood (:func:`fit_avar` → :class:`NoiseFit`), weighted by the
  model's own edf with a model-error variance (:func:`fit_avar_model_error`), and its
  intervals from correlated draws of the Allan variances (:func:`bootstrap_fits`);
* :mod:`.report` — the noise of a static recording (:func:`analyse_noise` →
  :class:`NoiseReport`: Allan deviations with intervals, the IEEE terms per axis with
  theirs, the static and resolution checks), :mod:`.export` its JSON and the Kalibr and
  OpenVINS files, :mod:`.figures` its figure (matplotlib, imported there only): what
  ``accelcal noise`` runs.

A noise model is a mapping ``{term id: coefficient}``; the two-parameter terms take
``(coefficient, shape)`` (``gauss_markov``: correlation time [s], ``sinusoid``:
frequency [Hz]).  Units: ``u`` is the data unit (counts, m/s², rad/s ...).

>>> import numpy as np
>>> from accelcal.noise import allan_variance, fit_avar, simulate_noise
>>> fs = 100.0
>>> x = simulate_noise(np.random.default_rng(0), 60_000, fs, {"white": 0.01, "random_walk": 1e-3}, size=3)
>>> av = allan_variance([x], fs)
>>> fit = fit_avar(av.taus, av.avar[:, 0], av.edf, ("white", "random_walk"), fs)
>>> fit.coefficients              # {'white': 0.01005, 'random_walk': 0.00081}: a 10-min record

Errors: :class:`AllanError` (data that give no Allan variance) and
:class:`NoiseModelError` (a model or fit the library cannot use), both
:class:`~accelcal.errors.AccelcalError`.  With the optional ``fast`` extra (numba) the
Allan sums, the fit and the Gauss–Markov recursion run compiled (:mod:`accelcal.kernels`),
with the same numbers to rounding.
"""

from .allan import (
    DEFAULT_MIN_EDF,
    NOISE_ALPHAS,
    AllanError,
    AllanVariance,
    allan_variance,
    avar_interval,
    check_segments,
    edf_overlapping,
    octave_m,
    pooled_edf,
)
from .allan_fit import (NoiseFit, bootstrap_fits, fit_avar, fit_avar_batch, fit_avar_model_error,
                        gamma_deviance, log_avar_covariance, model_edf)
from .report import NoiseAnalysisError, NoiseReport, analyse_noise
from .simulation import simulate_noise, simulate_segments
from .terms import TERMS, NoiseModelError, NoiseTerm, model_avar, noise_term, register_term, term_ids, term_parameters

__all__ = ["DEFAULT_MIN_EDF", "NOISE_ALPHAS", "TERMS", "AllanError", "AllanVariance",
           "NoiseAnalysisError", "NoiseFit", "NoiseModelError", "NoiseReport", "NoiseTerm", "allan_variance",
           "analyse_noise", "avar_interval", "bootstrap_fits", "check_segments", "edf_overlapping", "fit_avar",
           "fit_avar_batch", "fit_avar_model_error", "gamma_deviance", "log_avar_covariance", "model_avar",
           "model_edf", "noise_term", "octave_m", "pooled_edf", "register_term", "simulate_noise",
           "simulate_segments", "term_ids", "term_parameters"]
