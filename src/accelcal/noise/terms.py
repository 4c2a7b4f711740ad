"""The noise-term library: each term's Allan variance, parameters and meaning.

A noise model is a mapping ``{term id: coefficient}`` (the two-parameter terms take
``(coefficient, shape)``); :func:`model_avar` gives its Allan variance,
:mod:`accelcal.noise.simulation` draws it and :mod:`accelcal.noise.allan_fit` fits it to
a measured Allan variance.

Noise terms (stable ids; ``u`` is the data unit, e.g. counts or m/s²; IEEE Std 952
coefficients; Allan variance as a function of τ; α = exponent of the one-sided PSD
``S_y(f) ∝ f^α``, used only for degrees of freedom)

====================  ==========  ==========  ==================================  =====
id                    parameter   unit        AVAR(τ)                             α
====================  ==========  ==========  ==================================  =====
``white``             N           u·s^½       N² / τ                              0
``quantization``      Q           u·s         3 Q² / τ²                           2
``bias_instability``  B           u           (2 ln 2 / π) B²                     −1
``random_walk``       K           u·s^−½      K² τ / 3                            −2
``drift_ramp``        R           u/s         R² τ² / 2                           (−2)
``gauss_markov``      σ, T_c      u, s        first-order Gauss–Markov (below)    −2/0
``sinusoid``          A, f₀       u, Hz       A² sin⁴(π f₀ τ) / (π f₀ τ)²          (−2)
====================  ==========  ==========  ==================================  =====

The per-sample standard deviation of the white term is ``N √fs``.

* ``quantization`` is IEEE 952's quantization noise: the *integrated* output (velocity,
  a pulse counter) is rounded to a step ``δ = √12 Q`` and the rate samples are its
  differences, so the rounding errors ``e_k`` (i.i.d. uniform on ``±δ/2``: Widrow's
  model, valid while the integral crosses many steps between samples) enter as
  ``(e_{k+1} − e_k) fs``: white PM, AVAR exactly ``3 Q²/τ²`` at every τ.  Rounding the
  *rate* samples themselves to an integer count (what the raw counts of the Xsens and
  MPU-6050 files are) is different: under the same uniform-rounding model those errors
  are white in the rate, variance ``Δ²/12`` (Δ = 1 count), i.e. they add
  ``Δ²/(12 fs)`` to ``N²`` and cannot be told apart from ``white``.  A ``quantization``
  term named on raw-count data therefore means white-PM-like (anti-correlated, short-τ)
  noise, not the ADC's rounding, which would only show if the noise were below one
  count (where the uniform model fails).
* ``bias_instability`` is flicker FM (``S_y = h₋₁/f`` with ``h₋₁ = B²/π``), whose
  Allan variance is the flat floor ``2 ln 2 h₋₁ = (2 ln 2/π) B²`` (ADEV 0.664 B).  It is
  simulated with the Kasdin–Walter (1992) fractional-difference filter (white input of
  variance ``B²``); that discrete process's AVAR exceeds the floor by 44 % at m = 1,
  15 % at m = 2, 5 % at m = 4 and < 2 % beyond (extra power near Nyquist), which
  matters only where white noise dominates.  Each segment starts its own sequence.
* ``gauss_markov``: the other common reading of "bias instability", a first-order
  Gauss–Markov (AR(1)) bias of standard deviation σ and correlation time ``T_c``; it
  also models white noise seen through a low-pass filter (AVAR below ``N²/τ`` at the
  shortest τ).  Its AVAR for ``m`` samples (exact for the sampled AR(1),
  ``ρ = exp(−1/(fs T_c))``) is ``(4 V(m) − V(2m)) / (2 m² τ₀²)`` with
  ``V(m) = σ² τ₀² [m + 2ρ (m(1−ρ) − (1−ρ^m)) / (1−ρ)²]``; rising like a random walk
  (``2σ²τ/(3T_c)``) below ``T_c``, falling like white noise (``2σ²T_c/τ``) above.
  ``T_c`` enters nonlinearly: it is profiled over a grid of 3 values per octave from
  ``1/(2 fs)`` to ``2 τ_max`` (the estimate has that resolution, ±12 %).  Not a default
  candidate of the discrepancy workflow's stochastic layer: it imitates a random walk
  or a flicker floor on short records (:mod:`accelcal.discrepancy.stochastic.layer`,
  "Identifiability").
* ``sinusoid``: a periodic disturbance ``A sin(2π f₀ t + φ)`` (IEEE 952's sinusoidal
  noise), random phase per rest; AVAR of the sampled sinusoid
  ``A² H_m² sin²(π f₀ τ)`` with ``H_m = sin(π f₀ τ)/(m sin(π f₀/fs))``: it rises like a
  ramp, peaks near ``τ = 0.37/f₀`` and falls to zero at ``τ = 1/f₀`` — the only term
  whose Allan deviation can fall faster than ``1/τ``.  ``f₀`` is profiled over 4 values
  per octave from ``1/(4 τ_max)`` to ``fs/4``.  A model holds at most one of the two
  two-parameter terms.
* ``random_walk``: rate random walk, cumulative sum of increments of variance
  ``K²/fs`` (the discrete walk adds ``K²/(6 fs² τ)``, white-like and below 1 %).
* ``drift_ramp``: a linear drift ``R t`` within each rest (deterministic).

:func:`noise_term` looks a term up and :func:`term_parameters` checks a model entry,
each with a one-line :class:`NoiseModelError` naming what is wrong.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import AccelcalError

LN2 = math.log(2.0)


class NoiseModelError(AccelcalError):
    """A noise model, or an Allan variance to fit one to, that the term library cannot use."""


@dataclass(frozen=True)
class NoiseTerm:
    """One noise term of the library.

    ``shape_key`` names the second, nonlinear parameter of the two-parameter terms
    (``gauss_markov``: correlation time, ``sinusoid``: frequency), None otherwise.
    """

    id: str
    symbol: str
    unit: str
    alpha: int
    meaning: str
    shape_key: str | None = None

    @property
    def n_parameters(self) -> int:
        """Free parameters of the term in a fit: 2 for the two-parameter terms, else 1."""
        return 2 if self.shape_key else 1

    def basis(self, tau, fs: float, shape: float | None = None) -> np.ndarray:
        """AVAR(τ) per unit squared coefficient (two-parameter terms need ``shape``)."""
        tau = np.asarray(tau, dtype=float)
        if self.id == "white":
            return 1.0 / tau
        if self.id == "quantization":
            return 3.0 / tau**2
        if self.id == "bias_instability":
            return np.full_like(tau, 2.0 * LN2 / math.pi)
        if self.id == "random_walk":
            return tau / 3.0
        if self.id == "drift_ramp":
            return tau**2 / 2.0
        if self.shape_key is None or shape is None or not shape > 0:
            raise NoiseModelError(f"{self.id} needs a positive {self.shape_key}")
        if self.id == "gauss_markov":
            return _gm_basis(tau, fs, shape)
        return _sine_basis(tau, fs, shape)

    def shape_grid(self, fs: float, tau_max: float) -> np.ndarray:
        """Values of the nonlinear parameter the fit profiles over (module docstring)."""
        if self.id == "gauss_markov":  # 3 per octave, 1/(2 fs) … 2 τ_max
            lo, hi, per = math.log2(0.5 / fs), math.log2(2.0 * tau_max), 3
        elif self.id == "sinusoid":     # 4 per octave, 1/(4 τ_max) … fs/4
            lo, hi, per = math.log2(0.25 / tau_max), math.log2(fs / 4.0), 4
        else:
            raise NoiseModelError(f"{self.id} has no nonlinear parameter")
        return 2.0 ** np.arange(lo, hi + 1e-9, 1.0 / per)


def _gm_basis(tau, fs, tc):
    """Exact AVAR of a sampled unit-variance AR(1) with ``ρ = exp(−1/(fs tc))`` at ``τ = m/fs``."""
    tau0 = 1.0 / fs
    m = np.asarray(tau, dtype=float) / tau0
    x = tau0 / tc
    one_minus_rho = -math.expm1(-x)

    def v(mm):  # Var(sum of mm samples) / τ0² ... in units of σ², times τ0² below
        return mm + 2 * math.exp(-x) * (mm * one_minus_rho + np.expm1(-mm * x)) / one_minus_rho**2

    return (4 * v(m) - v(2 * m)) / (2 * m**2)


def _sine_basis(tau, fs, f0):
    """AVAR of a sampled unit-amplitude sinusoid of random phase: ``H_m² sin²(π f0 τ)``,
    ``H_m = sin(π f0 m/fs) / (m sin(π f0/fs))`` (→ ``sin⁴(π f0 τ)/(π f0 τ)²`` for fs → ∞)."""
    tau = np.asarray(tau, dtype=float)
    m = tau * fs
    h = np.sin(math.pi * f0 * tau) / (m * math.sin(math.pi * f0 / fs))
    return h**2 * np.sin(math.pi * f0 * tau) ** 2


#: The noise-term library, in the fixed order used for drawing random numbers.
TERMS = {t.id: t for t in (
    NoiseTerm("white", "N", "u*s^0.5", 0, "white noise of the rate (velocity random walk)"),
    NoiseTerm("quantization", "Q", "u*s", 2, "rounding of the integrated output (white PM)"),
    NoiseTerm("bias_instability", "B", "u", -1, "flicker (1/f) bias: flat Allan floor 0.664 B"),
    NoiseTerm("random_walk", "K", "u/s^0.5", -2, "rate random walk of the bias"),
    NoiseTerm("drift_ramp", "R", "u/s", -2, "linear drift within each rest"),
    NoiseTerm("gauss_markov", "sigma", "u", -2, "first-order Gauss-Markov bias (or low-passed white noise)",
              "correlation_time_s"),
    NoiseTerm("sinusoid", "A", "u", -2, "periodic disturbance of amplitude A", "frequency_hz"),
)}
TERM_IDS = tuple(TERMS)


def noise_term(term_id: str) -> NoiseTerm:
    """The library's term ``term_id`` (raises :class:`NoiseModelError` naming the known ids)."""
    try:
        return TERMS[term_id]
    except KeyError:
        raise NoiseModelError(f"unknown noise term {term_id!r}; known: {', '.join(TERM_IDS)}") from None


def term_parameters(term_id: str, v) -> tuple[float, float | None]:
    """``(coefficient, shape or None)`` of a model entry ``{term_id: v}``, checked.

    One-parameter terms take a coefficient ``>= 0``; the two-parameter terms
    ``(coefficient >= 0, shape > 0)``.  Raises :class:`NoiseModelError` otherwise.
    """
    t = noise_term(term_id)
    if t.shape_key is not None:
        try:
            s, shape = (float(x) for x in v)
        except (TypeError, ValueError):
            raise NoiseModelError(f"{term_id} must be given as ({t.symbol}, {t.shape_key})") from None
        if not (np.isfinite(s) and s >= 0 and np.isfinite(shape) and shape > 0):
            raise NoiseModelError(f"{term_id} needs {t.symbol} >= 0 and {t.shape_key} > 0, got {v}")
        return s, shape
    try:
        s = float(v)
    except (TypeError, ValueError):
        raise NoiseModelError(f"coefficient of {term_id} must be a number, got {v!r}") from None
    if not (np.isfinite(s) and s >= 0):
        raise NoiseModelError(f"coefficient of {term_id} must be finite and >= 0, got {v}")
    return s, None


def model_avar(terms: Mapping[str, object], taus, fs: float) -> np.ndarray:
    """Allan variance of a noise model ``{id: coefficient}`` at ``taus`` (two-parameter terms: ``(coefficient, shape)``)."""
    taus = np.asarray(taus, dtype=float)
    out = np.zeros(taus.shape)
    for k, v in terms.items():
        s, shape = term_parameters(k, v)
        out = out + s**2 * noise_term(k).basis(taus, fs, shape)
    return out


__all__ = ["LN2", "NoiseModelError", "NoiseTerm", "TERMS", "TERM_IDS", "model_avar", "noise_term", "term_parameters"]
