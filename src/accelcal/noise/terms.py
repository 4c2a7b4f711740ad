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

from .. import kernels
from ..errors import AccelcalError

LN2 = math.log(2.0)


class NoiseModelError(AccelcalError):
    """A noise model, or an Allan variance to fit one to, that the term library cannot use."""


class NoiseTerm:
    """One noise term of the library: its parameters and all its behaviour.

    A term is one subclass with one instance in :data:`TERMS` (:func:`register_term`); what
    the library does with a term (its Allan variance, the profile grid of its nonlinear
    parameter, its simulation, the variance of the difference of two interval means, its
    label and colour in figures, its unit in the reports, its octave correlation in the
    bootstrap, whether the noise report fits, plans, exports and warns about it) is a method
    or attribute here, never a branch on its id elsewhere (``tests/test_noise_term_table.py``).
    ``shape_key`` names the second, nonlinear parameter of the two-parameter terms
    (``gauss_markov``: correlation time, ``sinusoid``: frequency), None otherwise.
    """

    id: str
    symbol: str
    unit: str      # the coefficient's unit, ``{u}`` standing for the data unit (e.g. ``{u}/sqrt(Hz)``)
    alpha: int
    meaning: str
    name: str      # what figures and summaries call it
    colour: str    # matplotlib colour of the term in every figure
    shape_key: str | None = None
    #: A model entry of the term for the conformance suite (``(coefficient, shape)`` for two parameters).
    example: object = 1.0
    #: Exponent μ of a power-law Allan variance ``∝ τ^μ`` (None: not one power law); orders the IEEE terms.
    avar_slope: int | None = None
    #: One of the IEEE Std 952 terms the noise report fits (:func:`ieee_terms`).
    ieee: bool = False
    #: Correlation of ln AVAR between octaves 1…6 apart, overlapping estimator on a long record
    #: (:func:`accelcal.noise.allan_fit.octave_correlations` measures it: 1000 simulated records of
    #: 2^16 samples, averaged over m = 4 … 1024); None: the correlated bootstrap cannot draw the term.
    octave_correlation: tuple[float, ...] | None = None
    #: Beyond 6 octaves: this correlation, times ``far_decay`` per octave beyond the sixth (None: constant).
    far_correlation: float = 0.0
    far_decay: float | None = None
    #: What the record-length planner (:mod:`accelcal.noise.planner`) calls the term; None: not planned.
    planned_as: str | None = None
    #: The exported value the term gives (:func:`accelcal.noise.export.exported_values`: the
    #: keys of Kalibr's ``*_noise_density`` and ``*_random_walk``); None: not exported.
    exported_as: str | None = None
    #: Whether the noise report warns when a record does not resolve the term (a long-τ term
    #: a short record cannot see).
    warn_unresolved: bool = False
    #: Allan-deviation floor per unit coefficient (flicker: ``√(2 ln 2/π)`` as the reports quote
    #: it, 0.664); None: the term has no floor.
    floor_factor: float | None = None

    @property
    def label(self) -> str:
        """Figure label: the name and the coefficient's symbol."""
        return f"{self.name} {self.symbol}"

    @property
    def n_parameters(self) -> int:
        """Free parameters of the term in a fit: 2 for the two-parameter terms, else 1."""
        return 2 if self.shape_key else 1

    def unit_of(self, data_unit: str) -> str:
        """The coefficient's unit for data in ``data_unit`` (:attr:`unit` with ``{u}`` the data unit)."""
        return self.unit.format(u=data_unit)

    def octave_rho(self, d: np.ndarray) -> np.ndarray:
        """Correlation of ln AVAR between τ ``d`` octaves apart (:attr:`octave_correlation`, then the far tail)."""
        if self.octave_correlation is None:
            known = ", ".join(k for k, t in TERMS.items() if t.octave_correlation is not None)
            raise NoiseModelError(f"the correlated bootstrap knows the octave correlations of {known}, not of {self.id}")
        table = np.array((1.0,) + tuple(self.octave_correlation))
        far = self.far_correlation * (self.far_decay ** (d - 6) if self.far_decay is not None else 1.0)
        return np.where(d <= 6, table[np.minimum(d, 6)], far)

    def basis(self, tau, fs: float, shape: float | None = None) -> np.ndarray:
        """AVAR(τ) per unit squared coefficient (two-parameter terms need ``shape``)."""
        tau = np.asarray(tau, dtype=float)
        if self.shape_key is not None and (shape is None or not shape > 0):
            raise NoiseModelError(f"{self.id} needs a positive {self.shape_key}")
        return self._basis(tau, fs, shape)

    def _basis(self, tau: np.ndarray, fs: float, shape: float | None) -> np.ndarray:
        raise NotImplementedError

    def shape_grid(self, fs: float, tau_max: float) -> np.ndarray:
        """Values of the nonlinear parameter the fit profiles over (module docstring)."""
        raise NoiseModelError(f"{self.id} has no nonlinear parameter")

    def edf(self, allan, shape: float | None = None) -> np.ndarray:
        """Degrees of freedom of ``allan``'s Allan variances where this term dominates (by its α)."""
        return allan.edf_for(self.alpha)

    def simulate(self, v: float, shape: float | None, rng: np.random.Generator, n: int, fs: float,
                 cols: int) -> np.ndarray:
        """``(n, cols)`` samples of the term with coefficient ``v`` for one segment (module docstring)."""
        raise NotImplementedError

    def white_level(self, v, shortest: float) -> float | None:
        """``N²`` the term (model entry ``v``) adds to the white noise of means over intervals
        at least ``shortest`` seconds long, when it acts as white noise there; None when not."""
        return None

    def interval_difference_variance(self, v2: float, shape: float | None, iv: "IntervalPairs") -> np.ndarray:
        """``Var(ē_i − ē_j)`` of the term's means over the interval pairs ``iv`` (coefficient² ``v2``)."""
        raise NotImplementedError


@dataclass(frozen=True)
class IntervalPairs:
    """Disjoint intervals (start ``a``, duration ``T``) as broadcast pairs ``i`` (rows), ``j`` (columns)."""

    a: np.ndarray
    T: np.ndarray

    @property
    def ai(self):
        return self.a[:, None]

    @property
    def aj(self):
        return self.a[None, :]

    @property
    def Ti(self):
        return self.T[:, None]

    @property
    def Tj(self):
        return self.T[None, :]

    @property
    def gap(self) -> np.ndarray:
        """Time between the end of the earlier interval and the start of the later one."""
        first_end = np.where(self.ai <= self.aj, self.ai + self.Ti, self.aj + self.Tj)
        return np.maximum(np.maximum(self.ai, self.aj) - first_end, 0.0)

    @property
    def mid_difference(self) -> np.ndarray:
        return (self.ai + self.Ti / 2) - (self.aj + self.Tj / 2)


#: The noise-term library, in the fixed order used for drawing random numbers.
TERMS: dict[str, NoiseTerm] = {}


def register_term(cls: type[NoiseTerm]) -> type[NoiseTerm]:
    """Class decorator: one instance of ``cls`` becomes the entry ``TERMS[cls.id]`` (appended:
    the order of :data:`TERMS` is the order of the random streams, so new terms go last)."""
    if cls.id in TERMS:
        raise NoiseModelError(f"noise term {cls.id!r} is already registered")
    TERMS[cls.id] = cls()
    return cls


def unregister_term(term_id: str) -> None:
    """Remove a term added at run time (tests and examples)."""
    TERMS.pop(term_id, None)


@register_term
class White(NoiseTerm):
    example = 1.0
    name = "white noise"
    id, symbol, unit, alpha = "white", "N", "{u}/sqrt(Hz)", 0
    meaning = "white noise of the rate (velocity random walk)"
    colour = "C0"
    avar_slope, ieee, octave_correlation = -1, True, (0.52, 0.18, 0.06, 0.03, 0.03, 0.03)
    planned_as, exported_as = "noise density", "noise_density"

    def _basis(self, tau, fs, shape):
        return 1.0 / tau

    def simulate(self, v, shape, rng, n, fs, cols):
        return v * math.sqrt(fs) * rng.standard_normal((n, cols))

    def interval_difference_variance(self, v2, shape, iv):
        return v2 * (1 / iv.Ti + 1 / iv.Tj)

    def white_level(self, v, shortest):
        return term_parameters(self.id, v)[0] ** 2


@register_term
class Quantization(NoiseTerm):
    example = 1.0
    name = "quantization"
    id, symbol, unit, alpha = "quantization", "Q", "{u}*s", 2
    meaning = "rounding of the integrated output (white PM)"
    colour = "C4"
    avar_slope, ieee, octave_correlation = -2, True, (0.12, 0.31, 0.30, 0.30, 0.31, 0.28)
    far_correlation = 0.28

    def _basis(self, tau, fs, shape):
        return 3.0 / tau**2

    def simulate(self, v, shape, rng, n, fs, cols):
        half_step = math.sqrt(3.0) * v  # δ/2 with δ = √12 Q
        e = rng.uniform(-half_step, half_step, (n + 1, cols))
        return np.diff(e, axis=0) * fs

    def interval_difference_variance(self, v2, shape, iv):
        touch = np.isclose(iv.gap, 0.0, atol=1e-9 * iv.T.max())  # adjacent means share a rounding error
        return 2 * v2 * (1 / iv.Ti**2 + 1 / iv.Tj**2 + np.where(touch, 1 / (iv.Ti * iv.Tj), 0.0))


@register_term
class BiasInstability(NoiseTerm):
    example = 1.0
    name = "bias instability (flicker)"
    id, symbol, unit, alpha = "bias_instability", "B", "{u}", -1
    meaning = "flicker (1/f) bias: flat Allan floor 0.664 B"
    colour = "C2"
    avar_slope, ieee, octave_correlation = 0, True, (0.69, 0.32, 0.14, 0.07, 0.04, 0.0)
    planned_as, warn_unresolved, floor_factor = "bias instability", True, 0.664

    def _basis(self, tau, fs, shape):
        return np.full_like(tau, 2.0 * LN2 / math.pi)

    def simulate(self, v, shape, rng, n, fs, cols):
        return v * _kasdin_flicker(rng, n, cols)

    def interval_difference_variance(self, v2, shape, iv):
        # flicker's generalised covariance is −h₋₁ ln|t|: F = ln T − 3/2 and the mean of
        # ln|s' − s| over s in the earlier interval, s' in the later one
        F = np.log(iv.T) - 1.5
        ai, aj, Ti, Tj = iv.ai, iv.aj, iv.Ti, iv.Tj
        lo, hi = np.where(ai <= aj, ai, aj), np.where(ai <= aj, aj, ai)
        Tl, Th = np.where(ai <= aj, Ti, Tj), np.where(ai <= aj, Tj, Ti)
        Gm = (_phi(hi + Th - lo) - _phi(hi - lo) - _phi(hi + Th - lo - Tl) + _phi(hi - lo - Tl)) / (Tl * Th)
        return -(v2 / math.pi) * (F[:, None] + F[None, :] - 2 * Gm)


@register_term
class RandomWalk(NoiseTerm):
    example = 1.0
    name = "random walk"
    id, symbol, unit, alpha = "random_walk", "K", "{u}/s/sqrt(Hz)", -2
    meaning = "rate random walk of the bias"
    colour = "C3"
    avar_slope, ieee, octave_correlation = 1, True, (0.89, 0.67, 0.48, 0.34, 0.23, 0.16)
    far_correlation, far_decay = 0.16, 0.7
    planned_as, exported_as, warn_unresolved = "random walk", "random_walk", True

    def unit_of(self, data_unit):  # u·s^-½ = u/s/√Hz, spelled out for SI data
        return _SI_WALK_UNITS.get(data_unit, super().unit_of(data_unit))

    def _basis(self, tau, fs, shape):
        return tau / 3.0

    def simulate(self, v, shape, rng, n, fs, cols):
        return np.cumsum(v / math.sqrt(fs) * rng.standard_normal((n, cols)), axis=0)

    def interval_difference_variance(self, v2, shape, iv):
        return v2 * (iv.gap + (iv.Ti + iv.Tj) / 3)


@register_term
class DriftRamp(NoiseTerm):
    example = 1.0
    name = "drift ramp"
    id, symbol, unit, alpha = "drift_ramp", "R", "{u}/s", -2
    meaning = "linear drift within each rest"
    colour = "C1"
    avar_slope, ieee = 2, True
    # α = −2 like the random walk: the bootstrap draws its octaves with the walk's correlations
    octave_correlation, far_correlation, far_decay = RandomWalk.octave_correlation, 0.16, 0.7

    def _basis(self, tau, fs, shape):
        return tau**2 / 2.0

    def simulate(self, v, shape, rng, n, fs, cols):
        t = np.arange(n, dtype=float)[:, None] / fs
        return np.broadcast_to(v * t, (n, cols)).copy()

    def interval_difference_variance(self, v2, shape, iv):
        return v2 * iv.mid_difference ** 2


@register_term
class GaussMarkov(NoiseTerm):
    example = (1.0, 0.7)
    name = "Gauss-Markov"
    id, symbol, unit, alpha = "gauss_markov", "sigma", "{u}", -2
    meaning = "first-order Gauss-Markov bias (or low-passed white noise)"
    colour, shape_key = "C5", "correlation_time_s"

    def _basis(self, tau, fs, shape):
        return _gm_basis(tau, fs, shape)

    def shape_grid(self, fs, tau_max):  # 3 per octave, 1/(2 fs) … 2 τ_max
        return _octave_grid(math.log2(0.5 / fs), math.log2(2.0 * tau_max), 3)

    def edf(self, allan, shape=None):  # random-walk-like below T_c, white-like above
        return np.where(allan.taus < shape, allan.edf_for(-2), allan.edf_for(0))

    def simulate(self, v, shape, rng, n, fs, cols):
        rho = math.exp(-1.0 / (fs * shape))  # stationary AR(1)
        e = rng.standard_normal((n, cols)) * v * math.sqrt(1.0 - rho * rho)
        e[0] = rng.standard_normal(cols) * v  # start in the stationary distribution
        fast = kernels.compiled("noise._fast")
        if fast is not None:  # the same recursion, compiled (and no scipy.signal import: ~1 s of CPU)
            return fast.ar1(e, rho)
        from scipy.signal import lfilter

        return lfilter([1.0], [1.0, -rho], e, axis=0)

    def white_level(self, v, shortest):  # white noise through a low-pass filter well below the intervals
        sigma, tc = term_parameters(self.id, v)
        return 2 * sigma**2 * tc if tc < 0.1 * shortest else None

    def interval_difference_variance(self, v2, shape, iv):
        tc, T = shape, iv.T
        W = 2 * v2 * (tc * T + tc**2 * np.expm1(-T / tc))
        E = -np.expm1(-T / tc)
        cov = v2 * tc**2 * E[:, None] * E[None, :] * np.exp(-iv.gap / tc) / (iv.Ti * iv.Tj)
        return (W / T**2)[:, None] + (W / T**2)[None, :] - 2 * cov


@register_term
class Sinusoid(NoiseTerm):
    example = (1.0, 0.3)
    name = "sinusoid"
    id, symbol, unit, alpha = "sinusoid", "A", "{u}", -2
    meaning = "periodic disturbance of amplitude A"
    colour, shape_key = "C6", "frequency_hz"

    def _basis(self, tau, fs, shape):
        return _sine_basis(tau, fs, shape)

    def shape_grid(self, fs, tau_max):  # 4 per octave, 1/(4 τ_max) … fs/4
        return _octave_grid(math.log2(0.25 / tau_max), math.log2(fs / 4.0), 4)

    def simulate(self, v, shape, rng, n, fs, cols):  # a random phase per segment and column
        phase = rng.uniform(0.0, 2 * math.pi, cols)
        t = np.arange(n, dtype=float)[:, None] / fs
        return v * np.sin(2 * math.pi * shape * t + phase)

    def interval_difference_variance(self, v2, shape, iv):  # one coherent oscillation, random phase
        sinc = np.sinc(shape * iv.T)  # numpy's sinc is sin(πx)/(πx)
        return 0.5 * v2 * (sinc[:, None] ** 2 + sinc[None, :] ** 2 - 2 * sinc[:, None] * sinc[None, :]
                           * np.cos(2 * math.pi * shape * iv.mid_difference))


#: The random walk coefficient's unit spelled out for SI data (u·s^-½ = u/s/√Hz).
_SI_WALK_UNITS = {"m/s^2": "m/s^3/sqrt(Hz)", "rad/s": "rad/s^2/sqrt(Hz)"}


def _octave_grid(lo: float, hi: float, per: int) -> np.ndarray:
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


def _kasdin_flicker(rng: np.random.Generator, n: int, cols: int) -> np.ndarray:
    """Flicker (1/f) noise: the Kasdin–Walter filter ``h_k = h_{k-1} (k − 1/2)/k`` on unit white noise."""
    from scipy.fft import next_fast_len  # scipy.fft only where flicker is drawn (import cost)

    k = np.arange(1, n)
    h = np.concatenate([[1.0], np.cumprod((k - 0.5) / k)])
    w = rng.standard_normal((n, cols))
    # zero padding to at least 2n - 1: linear, not circular, convolution; a length with
    # small prime factors (2n itself can have a large one, e.g. 2 x 1741, and FFT slowly)
    nfft = next_fast_len(2 * n, real=True)
    spec = np.fft.rfft(w, nfft, axis=0) * np.fft.rfft(h, nfft)[:, None]
    return np.fft.irfft(spec, nfft, axis=0)[:n]


def _phi(x):
    """Second antiderivative of ln|x| (zero at 0): ``x²/2 ln|x| − 3x²/4``."""
    x = np.asarray(x, dtype=float)
    ax = np.abs(x)
    return np.where(ax > 0, 0.5 * x**2 * np.log(np.where(ax > 0, ax, 1.0)) - 0.75 * x**2, 0.0)


def term_ids() -> tuple[str, ...]:
    """The registered terms' ids in registry order (the order of the random streams)."""
    return tuple(TERMS)



def ieee_terms() -> tuple[str, ...]:
    """The IEEE Std 952 terms the noise report fits (:attr:`NoiseTerm.ieee`), in the order of the τ
    where they act, short to long (their Allan-variance slopes)."""
    return tuple(sorted((k for k, t in TERMS.items() if t.ieee), key=lambda k: TERMS[k].avar_slope))


def exported_term(key: str) -> NoiseTerm:
    """The term whose coefficient the exports write as ``key`` (:attr:`NoiseTerm.exported_as`)."""
    found = [t for t in TERMS.values() if t.exported_as == key]
    if len(found) != 1:
        raise NoiseModelError(f"{len(found)} noise terms are exported as {key!r}; the exports need exactly one")
    return found[0]


def noise_term(term_id: str) -> NoiseTerm:
    """The library's term ``term_id`` (raises :class:`NoiseModelError` naming the known ids)."""
    try:
        return TERMS[term_id]
    except KeyError:
        raise NoiseModelError(f"unknown noise term {term_id!r}; known: {', '.join(TERMS)}") from None


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


__all__ = ["LN2", "IntervalPairs", "NoiseModelError", "NoiseTerm", "TERMS", "exported_term", "ieee_terms",
           "model_avar", "noise_term", "register_term", "term_ids", "term_parameters", "unregister_term"]
