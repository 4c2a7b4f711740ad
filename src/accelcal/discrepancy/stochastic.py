"""Stochastic layer of the discrepancy workflow: which noise term does the simulator miss?

The simulator's noise model starts as white noise.  This module compares the Allan
deviation of the measured rest intervals with that model, names the missing noise term
(if any) by a calibrated test, adds it, re-simulates the rests and reports how much the
Allan-deviation gap shrinks, and what the named term means for the static-pose means
the deterministic calibration works with.

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
  candidate (see Identifiability).
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

Identifiability (measured: 4 simulated sessions × 3 axes per row, one 52 s rest and
twenty 8 s rests at 100 Hz, N = 0.1, each term crossing the white line 1–3 octaves
below τ_max).  With the default candidates the layer named nothing on 12/12 white-only
axes and named the injected term first on 12/12 quantization, 12/12 flicker, 9/12 random
walk (one ramp, one flicker, one sinusoid instead), 11/12 ramp (one random walk) and
12/12 sinusoid axes.  Adding ``gauss_markov`` turned 6/12 flicker axes and 4/12 random
walk axes into Gauss–Markov ones; an injected Gauss–Markov bias (T_c = 1 s) is named
``gauss_markov`` on 8/12 axes when it is a candidate and ``bias_instability`` or
``sinusoid`` when not.  The flicker floor is the one-parameter reading of "bias
instability" that records this short can identify.

Fit.  The model AVAR is linear in the squared coefficients ``c = (N², Q², …) ≥ 0`` (for
a given ``T_c`` or ``f₀``, which are profiled over their grids).  Each pooled AVAR point ``Â_j`` is treated as ``A_j χ²_{ν_j}/ν_j``
(Gamma, shape ``ν_j/2``) with ``ν_j`` the pooled white-FM edf of :mod:`.allan`; ``c``
maximises this likelihood subject to ``c ≥ 0`` (Fisher scoring = iteratively
reweighted non-negative least squares with weights ``ν_j/A_j²``).  Deviance
``D = Σ ν_j (Â_j/A_j − 1 − ln(Â_j/A_j))``.

Test (exactly).  Start from ``white``.  At each step, for every remaining candidate
``k`` fit current + ``k``; ``LR_k = D_current − D_{current+k}`` and
``ΔBIC_k = −LR_k + p_k ln(n_τ)`` (``p_k`` = 1, 2 for the two-parameter terms).  The AVAR
points at neighbouring τ are correlated, the edf are approximations, ``c_k = 0`` lies on
the boundary and ``T_c``/``f₀`` are not identified under the null, so ``LR`` is not χ²: its null
distribution comes from a parametric bootstrap — ``n_boot`` synthetic data sets of the
fitted current model with the measured segment lengths, each refitted with current and
every current + k.  Per-candidate p-value ``(1 + #{LR*_k ≥ LR_k}) / (n_boot + 1)``;
the multiple-comparison correction over candidates is the max-statistic one
(Westfall–Young): candidate ``k``'s adjusted p-value is
``(1 + #{max_k' LR*_k' ≥ LR_k}) / (n_boot + 1)``, which holds the family-wise error of the
step at ``alpha`` whatever the dependence between candidates.  The candidate with the
smallest ``ΔBIC`` is named when its adjusted p-value is below ``alpha`` *and*
``ΔBIC < 0``; the search stops at the first step that names nothing or after
``max_terms`` terms.  Step 1 is a level-``alpha`` test of "white is enough", so
white-only data get a term named with probability ≤ ``alpha`` per axis.  Standard
errors: standard deviation of the refitted coefficients over the ``n_boot`` bootstrap
sets of the final model.  Step 1's null (white only) is the same on every axis up to its scale ``N``, and the
statistics (deviances, LR, ΔBIC) are scale-free, so one bootstrap at ``N = 1`` serves all
axes (its coefficients times each axis's ``N`` give the standard errors): exact, and a
third of the cost of a bootstrap per axis.

Gap (one definition, before and after).  The rests are re-simulated ``n_resim`` times
with the fitted model (same segment lengths; white-only fit "before", final model
"after", common random numbers) and the simulated Allan variance is the mean over the
replicates.  With ``r_j = log10(ADEV_measured(τ_j) / ADEV_simulated(τ_j))`` and
``s_j = 1/(ln 10 √(2 ν_j))`` the standard error of the measured ``log10 ADEV`` (white-FM
edf ``ν_j``: the same yardstick before and after)::

    gap     = sqrt(mean_j (r_j / s_j)²)   ≈ 1 when the model explains the data to
                                          within its sampling noise
    log_gap = sqrt(mean_j r_j²)           decades; dominated by the noisy long τ

Homogeneity.  Pooling assumes every rest is the same process.  The layer also reports,
per τ, the ratio of the Allan deviation of the other rests (pooled) to that of the
longest rest, with a two-sided F-test p-value (white-FM edf): hand-placed poses that are
noisier than the initial rest show up there, and then a term named on the pooled curve
describes the poses' disturbance as much as the sensor.

Pose-residual implication.  The deterministic calibration averages each static pose and
absorbs one common bias per axis, so what noise leaves in its residuals is the scatter
of the pose-mean errors about their common mean.  For poses ``i`` (start ``a_i``,
duration ``T_i``, disjoint, gap ``g_ij``) each term gives ``D_ij = Var(ē_i − ē_j)`` in
closed form:

* white ``N² (1/T_i + 1/T_j)``; quantization ``2Q² (1/T_i² + 1/T_j²)`` (``+ 2Q²/(T_i T_j)``
  if the intervals touch);
* random walk ``K² (g_ij + (T_i + T_j)/3)``; ramp ``R² (c_i − c_j)²`` (``c`` = mid times; a
  drift that lasts the whole session is the deterministic layer's bias drift);
* flicker ``−h₋₁ (F_i + F_j − 2 G_ij)`` with ``F = ln T − 3/2`` and ``G_ij`` the mean of
  ``ln|s − s'|`` over the two intervals (flicker's generalised covariance is
  ``−h₋₁ ln|t|``);
* Gauss–Markov ``W(T_i)/T_i² + W(T_j)/T_j² − 2σ²T_c² (1−e^{−T_i/T_c})(1−e^{−T_j/T_c}) e^{−g_ij/T_c}/(T_i T_j)``
  with ``W(T) = 2σ² (T_c T − T_c² (1 − e^{−T/T_c}))``;
* sinusoid (one coherent oscillation over the session, random phase)
  ``(A²/2) (s_i² + s_j² − 2 s_i s_j cos(2π f₀ (c_i − c_j)))`` with ``s = sin(π f₀ T)/(π f₀ T)``.

For adjacent equal intervals each reduces to ``2 AVAR(T)``.  The covariance of the
centred pose means is ``−½ P D P`` (``P = I − 11ᵀ/n``); its diagonal is the expected
squared pose-mean error per pose and axis.  A pose with unit gravity direction ``u``
sees ``Σ_axes u_a² v_a`` in its scalar residual (:func:`expected_residual_std`); the
nine calibration parameters absorb a little more than the common bias, so this slightly
overestimates the residual.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from .allan import AllanVariance, allan_variance, check_segments, pooled_edf

LN2 = math.log(2.0)


class StochasticError(AccelcalError):
    """Rest data or settings the stochastic layer cannot use."""


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
            raise StochasticError(f"{self.id} needs a positive {self.shape_key}")
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
            raise StochasticError(f"{self.id} has no nonlinear parameter")
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
#: Default candidates: the one-parameter terms and the sinusoid.  ``gauss_markov`` is
#: opt-in: it imitates a random walk or a flicker floor over 3 decades of τ (module
#: docstring, "Identifiability").
DEFAULT_CANDIDATES = ("quantization", "bias_instability", "random_walk", "drift_ramp", "sinusoid")
DEFAULT_N_BOOT = 199
DEFAULT_N_RESIM = 16


def _term(term_id: str) -> NoiseTerm:
    try:
        return TERMS[term_id]
    except KeyError:
        raise StochasticError(f"unknown noise term {term_id!r}; known: {', '.join(TERM_IDS)}") from None


def _value(term_id: str, v) -> tuple[float, float | None]:
    """(coefficient, shape or None) of a model entry; two-parameter terms are ``(coefficient, shape)``."""
    t = _term(term_id)
    if t.shape_key is not None:
        try:
            s, shape = (float(x) for x in v)
        except (TypeError, ValueError):
            raise StochasticError(f"{term_id} must be given as ({t.symbol}, {t.shape_key})") from None
        if not (np.isfinite(s) and s >= 0 and np.isfinite(shape) and shape > 0):
            raise StochasticError(f"{term_id} needs {t.symbol} >= 0 and {t.shape_key} > 0, got {v}")
        return s, shape
    try:
        s = float(v)
    except (TypeError, ValueError):
        raise StochasticError(f"coefficient of {term_id} must be a number, got {v!r}") from None
    if not (np.isfinite(s) and s >= 0):
        raise StochasticError(f"coefficient of {term_id} must be finite and >= 0, got {v}")
    return s, None


def model_avar(terms: Mapping[str, object], taus, fs: float) -> np.ndarray:
    """Allan variance of a noise model ``{id: coefficient}`` at ``taus`` (two-parameter terms: ``(coefficient, shape)``)."""
    taus = np.asarray(taus, dtype=float)
    out = np.zeros(taus.shape)
    for k, v in terms.items():
        s, shape = _value(k, v)
        out = out + s**2 * _term(k).basis(taus, fs, shape)
    return out


# --------------------------------------------------------------------------- simulation


def simulate_segments(rng: np.random.Generator, lengths: Sequence[int], fs: float,
                      terms: Mapping[str, object], size: int | None = None) -> list[np.ndarray]:
    """Noise of the model ``terms`` for rest segments of the given lengths.

    Every term draws from its own stream (spawned from ``rng`` for all of
    :data:`TERM_IDS`, present or not), so two models simulated from generators in the
    same state share the random numbers of their common terms (common random numbers).

    Returns a list of arrays of shape ``(n_i,)`` (``size=None``) or ``(n_i, size)``.
    """
    vals = {k: _value(k, v) for k, v in terms.items()}
    seeds = rng.integers(0, 2**63, size=len(TERM_IDS))
    streams = {k: np.random.default_rng(int(s)) for k, s in zip(TERM_IDS, seeds)}
    cols = 1 if size is None else int(size)
    out = []
    for n in lengths:
        y = np.zeros((int(n), cols))
        for k in TERM_IDS:  # fixed order
            if k in vals:
                y += _simulate_term(k, *vals[k], streams[k], int(n), float(fs), cols)
        out.append(y[:, 0] if size is None else y)
    return out


def simulate_noise(rng: np.random.Generator, n: int, fs: float, terms: Mapping[str, object],
                   size: int | None = None) -> np.ndarray:
    """One noise record of ``n`` samples (see :func:`simulate_segments`)."""
    return simulate_segments(rng, [n], fs, terms, size)[0]


def _simulate_term(k: str, v: float, shape, rng: np.random.Generator, n: int, fs: float, cols: int) -> np.ndarray:
    if k == "white":
        return v * math.sqrt(fs) * rng.standard_normal((n, cols))
    if k == "quantization":
        half_step = math.sqrt(3.0) * v  # δ/2 with δ = √12 Q
        e = rng.uniform(-half_step, half_step, (n + 1, cols))
        return np.diff(e, axis=0) * fs
    if k == "bias_instability":
        return v * _kasdin_flicker(rng, n, cols)
    if k == "random_walk":
        return np.cumsum(v / math.sqrt(fs) * rng.standard_normal((n, cols)), axis=0)
    if k == "drift_ramp":
        t = np.arange(n, dtype=float)[:, None] / fs
        return np.broadcast_to(v * t, (n, cols)).copy()
    if k == "sinusoid":  # a random phase per segment and column
        phase = rng.uniform(0.0, 2 * math.pi, cols)
        t = np.arange(n, dtype=float)[:, None] / fs
        return v * np.sin(2 * math.pi * shape * t + phase)
    rho = math.exp(-1.0 / (fs * shape))  # gauss_markov: stationary AR(1)
    e = rng.standard_normal((n, cols)) * v * math.sqrt(1.0 - rho * rho)
    e[0] = rng.standard_normal(cols) * v  # start in the stationary distribution
    from .. import kernels

    fast = kernels.compiled("discrepancy._fast")
    if fast is not None:  # the same recursion, compiled (and no scipy.signal import: ~1 s of CPU)
        return fast.ar1(e, rho)
    from scipy.signal import lfilter

    return lfilter([1.0], [1.0, -rho], e, axis=0)


def _kasdin_flicker(rng: np.random.Generator, n: int, cols: int) -> np.ndarray:
    """Flicker (1/f) noise: the Kasdin–Walter filter ``h_k = h_{k-1} (k − 1/2)/k`` on unit white noise."""
    from scipy.fft import next_fast_len

    k = np.arange(1, n)
    h = np.concatenate([[1.0], np.cumprod((k - 0.5) / k)])
    w = rng.standard_normal((n, cols))
    # zero padding to at least 2n - 1: linear, not circular, convolution; a length with
    # small prime factors (2n itself can have a large one, e.g. 2 x 1741, and FFT slowly)
    nfft = next_fast_len(2 * n, real=True)
    spec = np.fft.rfft(w, nfft, axis=0) * np.fft.rfft(h, nfft)[:, None]
    return np.fft.irfft(spec, nfft, axis=0)[:n]


# --------------------------------------------------------------------------- fit


@dataclass(frozen=True)
class NoiseFit:
    """Gamma maximum-likelihood fit of an Allan-variance model (module docstring).

    ``c`` are the squared coefficients in the order of ``term_ids``; ``shape`` the
    nonlinear parameter of the model's two-parameter term (NaN without one);
    ``deviance`` the Gamma deviance over the τ points.
    """

    term_ids: tuple[str, ...]
    c: np.ndarray
    shape: float
    deviance: float

    @property
    def coefficients(self) -> dict[str, float]:
        """IEEE 952 coefficient of each term (σ for ``gauss_markov``, A for ``sinusoid``)."""
        return {k: float(math.sqrt(max(v, 0.0))) for k, v in zip(self.term_ids, self.c)}

    @property
    def model(self) -> dict[str, object]:
        """The model in the form :func:`simulate_segments` and :func:`model_avar` take."""
        return {k: ((v, self.shape) if TERMS[k].shape_key else v) for k, v in self.coefficients.items()}

    def avar(self, taus, fs: float) -> np.ndarray:
        return model_avar(self.model, taus, fs)


def gamma_deviance(avar_measured, avar_model, edf) -> np.ndarray:
    """``Σ ν (r − 1 − ln r)`` over the last axis, ``r = measured / model``."""
    r = np.asarray(avar_measured) / np.asarray(avar_model)
    return np.sum(np.asarray(edf) * (r - 1.0 - np.log(r)), axis=-1)


def _nnls_batch(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Non-negative least squares for a batch of small problems, ``A`` (G, k, p), ``b`` (G, k).

    The solution is the least-squares solution on its support, so the best feasible
    least-squares solution over all 2^p − 1 supports is the optimum (p ≤ 7 here).
    """
    G, _, p = A.shape
    best_x = np.zeros((G, p))
    bb = np.einsum("gk,gk->g", b, b)
    best = bb.copy()
    # the Gram matrix and Aᵀb once; a support's objective is bᵀb − 2 xᵀAᵀb + xᵀ(AᵀA)x
    gram_all = np.einsum("gki,gkj->gij", A, A)
    rhs_all = np.einsum("gki,gk->gi", A, b)
    for s in range(1, p + 1):
        for idx in combinations(range(p), s):
            gram = gram_all[:, idx][:, :, idx] + 1e-12 * np.eye(s)
            rhs = rhs_all[:, idx]
            x = np.linalg.solve(gram, rhs[..., None])[..., 0]
            obj = bb - 2 * np.einsum("gi,gi->g", x, rhs) + np.einsum("gi,gij,gj->g", x, gram_all[:, idx][:, :, idx], x)
            ok = np.all(x >= 0, axis=1) & (obj < best)
            best = np.where(ok, obj, best)
            best_x[ok] = 0.0
            best_x[np.ix_(ok, idx)] = x[ok]
    return best_x


def _irls(H: np.ndarray, y: np.ndarray, edf: np.ndarray, max_iter: int = 200, tol: float = 1e-10):
    """Gamma ML with identity link and ``c ≥ 0`` for a batch: ``H`` (G, k, p), ``y`` (G, k) → (c, deviance).

    Fisher scoring (weighted NNLS with weights ``ν/A²`` at the current model), with step
    halving whenever a step would raise the deviance (the Gamma deviance is not convex
    in ``c``, and plain scoring can cycle); each problem stops when its deviance changes
    by less than ``tol`` relative.
    """
    from .. import kernels

    fast = kernels.compiled("discrepancy._fast")
    if fast is not None:  # the same algorithm, compiled (accelcal[fast])
        return fast.irls_gamma(H, y, edf, max_iter, tol)
    G = y.shape[0]
    floor = 1e-12 * y.max(axis=1, keepdims=True)
    sw = np.sqrt(edf)
    c = np.zeros((G, H.shape[2]))
    model = y.copy()  # first weights from the data themselves
    dev = np.full(G, np.inf)
    active = np.arange(G)
    for _ in range(max_iter):
        Ha, ya, fa = H[active], y[active], floor[active]
        w = sw / model[active]
        A = Ha * w[:, :, None]
        scale = np.linalg.norm(A, axis=1)
        scale[scale == 0] = 1.0
        c_new = _nnls_batch(A / scale[:, None, :], ya * w) / scale
        m_new = np.maximum(np.einsum("gkp,gp->gk", Ha, c_new), fa)
        d_new = gamma_deviance(ya, m_new, edf)
        d_old = dev[active]
        for _ in range(30):  # step halving towards the previous (feasible) c
            worse = d_new > d_old
            if not worse.any():
                break
            c_new[worse] = 0.5 * (c_new[worse] + c[active][worse])
            m_new[worse] = np.maximum(np.einsum("gkp,gp->gk", Ha[worse], c_new[worse]), fa[worse])
            d_new[worse] = gamma_deviance(ya[worse], m_new[worse], edf)
        keep = d_new <= d_old
        c_new[~keep], m_new[~keep], d_new[~keep] = c[active][~keep], model[active][~keep], d_old[~keep]
        converged = np.abs(d_old - d_new) <= tol * (1.0 + np.abs(d_new))
        c[active], model[active], dev[active] = c_new, m_new, d_new
        active = active[~converged]
        if active.size == 0:
            break
    return c, dev


def fit_avar_batch(taus, avar, edf, term_ids: Sequence[str], fs: float) -> list[NoiseFit]:
    """:func:`fit_avar` for many data sets at once, ``avar`` shape (G, k)."""
    taus, edf = np.asarray(taus, dtype=float), np.asarray(edf, dtype=float)
    y = np.atleast_2d(np.asarray(avar, dtype=float))
    if y.shape[1] != taus.size or np.any(y <= 0) or not np.all(np.isfinite(y)):
        raise StochasticError("Allan variance must be positive and finite at every tau (constant data?)")
    term_ids = tuple(term_ids)
    for k in term_ids:
        _term(k)
    G = y.shape[0]
    shaped = [k for k in term_ids if TERMS[k].shape_key]
    if len(shaped) > 1:
        raise StochasticError(f"at most one two-parameter term per model, got {shaped}")
    if not shaped:
        H = np.column_stack([_term(k).basis(taus, fs) for k in term_ids])
        c, dev = _irls(np.broadcast_to(H, (G,) + H.shape), y, edf)
        return [NoiseFit(term_ids, c[g], float("nan"), float(dev[g])) for g in range(G)]
    grid = TERMS[shaped[0]].shape_grid(fs, taus.max())
    Hs = np.stack([np.column_stack([_term(k).basis(taus, fs, sh) for k in term_ids]) for sh in grid])
    H = np.broadcast_to(Hs[None], (G,) + Hs.shape).reshape(G * grid.size, *Hs.shape[1:])
    c, dev = _irls(H, np.repeat(y, grid.size, axis=0), edf)
    c, dev = c.reshape(G, grid.size, -1), dev.reshape(G, grid.size)
    best = np.argmin(dev, axis=1)
    return [NoiseFit(term_ids, c[g, best[g]], float(grid[best[g]]), float(dev[g, best[g]])) for g in range(G)]


def fit_avar(taus, avar, edf, term_ids: Sequence[str], fs: float) -> NoiseFit:
    """Fit ``AVAR(τ) = Σ c_k basis_k(τ)``, ``c ≥ 0``, by Gamma maximum likelihood.

    Parameters
    ----------
    taus, avar, edf : array_like, shape (k,)
        Averaging times [s], measured Allan variance (> 0) and its degrees of freedom.
    term_ids : sequence of str
        Terms of the model (ids of :data:`TERMS`); at most one two-parameter term,
        whose nonlinear parameter is profiled over :meth:`NoiseTerm.shape_grid`.
    fs : float
        Sampling rate [Hz] (the Gauss–Markov basis is that of the sampled process).
    """
    return fit_avar_batch(taus, np.asarray(avar, dtype=float)[None], edf, term_ids, fs)[0]


def _n_params(term_id: str) -> int:
    return 2 if TERMS[term_id].shape_key else 1


# --------------------------------------------------------------------------- pose implication


def _phi(x):
    """Second antiderivative of ln|x| (zero at 0): ``x²/2 ln|x| − 3x²/4``."""
    x = np.asarray(x, dtype=float)
    ax = np.abs(x)
    return np.where(ax > 0, 0.5 * x**2 * np.log(np.where(ax > 0, ax, 1.0)) - 0.75 * x**2, 0.0)


def pose_difference_variance(term_id: str, value, starts, durations) -> np.ndarray:
    """``D_ij = Var(ē_i − ē_j)`` of one noise term's mean over disjoint intervals (module docstring).

    Parameters
    ----------
    term_id : str
    value : float or (float, float)
        The term's coefficient (``(coefficient, shape)`` for the two-parameter terms).
    starts, durations : array_like, shape (n,)
        Start [s] and duration [s] of each interval; intervals must not overlap.

    Returns
    -------
    ndarray, shape (n, n)
    """
    s, shape = _value(term_id, value)
    a = np.asarray(starts, dtype=float)
    T = np.asarray(durations, dtype=float)
    if a.shape != T.shape or a.ndim != 1 or a.size == 0 or np.any(T <= 0):
        raise StochasticError("need 1-D starts and positive durations of the same length")
    order = np.argsort(a)
    if np.any(a[order][1:] < (a + T)[order][:-1] - 1e-9 * T.max()):
        raise StochasticError("pose intervals overlap")
    v2 = s**2
    ai, aj = a[:, None], a[None, :]
    Ti, Tj = T[:, None], T[None, :]
    first_end = np.where(ai <= aj, ai + Ti, aj + Tj)
    gap = np.maximum(np.maximum(ai, aj) - first_end, 0.0)
    if term_id == "white":
        D = v2 * (1 / Ti + 1 / Tj)
    elif term_id == "quantization":
        touch = np.isclose(gap, 0.0, atol=1e-9 * T.max())
        D = 2 * v2 * (1 / Ti**2 + 1 / Tj**2 + np.where(touch, 1 / (Ti * Tj), 0.0))
    elif term_id == "random_walk":
        D = v2 * (gap + (Ti + Tj) / 3)
    elif term_id == "drift_ramp":
        D = v2 * ((ai + Ti / 2) - (aj + Tj / 2)) ** 2
    elif term_id == "bias_instability":
        F = np.log(T) - 1.5
        # mean of ln|s' − s| over s in the earlier interval, s' in the later one
        lo, hi = np.where(ai <= aj, ai, aj), np.where(ai <= aj, aj, ai)
        Tl, Th = np.where(ai <= aj, Ti, Tj), np.where(ai <= aj, Tj, Ti)
        Gm = (_phi(hi + Th - lo) - _phi(hi - lo) - _phi(hi + Th - lo - Tl) + _phi(hi - lo - Tl)) / (Tl * Th)
        D = -(v2 / math.pi) * (F[:, None] + F[None, :] - 2 * Gm)
    elif term_id == "sinusoid":  # one coherent oscillation over the session, random phase
        sinc = np.sinc(shape * T)  # numpy's sinc is sin(πx)/(πx)
        D = 0.5 * v2 * (sinc[:, None] ** 2 + sinc[None, :] ** 2 - 2 * sinc[:, None] * sinc[None, :]
                        * np.cos(2 * math.pi * shape * ((ai + Ti / 2) - (aj + Tj / 2))))
    else:  # gauss_markov
        tc = shape
        W = 2 * v2 * (tc * T + tc**2 * np.expm1(-T / tc))
        E = -np.expm1(-T / tc)
        cov = v2 * tc**2 * E[:, None] * E[None, :] * np.exp(-gap / tc) / (Ti * Tj)
        D = (W / T**2)[:, None] + (W / T**2)[None, :] - 2 * cov
    D = np.array(D, dtype=float)
    np.fill_diagonal(D, 0.0)
    return D


def centred_pose_variance(D: np.ndarray) -> np.ndarray:
    """Diagonal of ``−½ P D P`` (``P = I − 11ᵀ/n``): variance of each pose-mean error about the common mean."""
    return D.mean(axis=1) - 0.5 * np.diag(D) - 0.5 * D.mean()


def pose_residual_implication(terms: Mapping[str, object], starts, durations, fs: float,
                              tau_max: float | None = None) -> dict:
    """What a noise model means for the pose means of a calibration session.

    Parameters
    ----------
    terms : mapping
        Noise model ``{id: coefficient}`` (two-parameter terms: ``(coefficient, shape)``).
    starts, durations : array_like
        Start and duration [s] of each static pose.
    fs : float
        Sampling rate [Hz].
    tau_max : float, optional
        Longest τ the noise model was fitted on: the session is usually much longer,
        and the drift of pose means over the session extrapolates the model's
        time-correlated terms from ``tau_max`` to the session length (reported as
        ``session_over_tau_max``).

    Returns
    -------
    dict
        ``pose_mean_std_white`` / ``_model``: RMS over poses of the expected error of a
        pose mean about the session's common mean, white term only / whole model (data
        unit); ``pose_mean_std_excess`` = sqrt of the difference of their squares (what
        the other terms add); ``by_term`` that RMS per term; ``inflation`` = model /
        white; ``adev_excess_at_median_duration`` = sqrt(AVAR_model(T) − N²/T) at the
        median pose duration T (extra std of a pose mean against an adjacent one);
        ``pose_mean_var_white`` / ``_model``: per-pose variances.  A ``gauss_markov``
        term with ``T_c`` below a tenth of the shortest pose is white noise seen through
        a low-pass filter at the scale of the poses: it counts as white here (with
        ``N² = 2σ²T_c``), not as excess.
    """
    starts = np.asarray(starts, dtype=float)
    durations = np.asarray(durations, dtype=float)
    per_term = {k: centred_pose_variance(pose_difference_variance(k, v, starts, durations))
                for k, v in terms.items()}
    white_like = ["white"]
    n2_white = _value("white", terms["white"])[0] ** 2 if "white" in terms else 0.0
    if "gauss_markov" in terms:
        sigma, tc = _value("gauss_markov", terms["gauss_markov"])
        if tc < 0.1 * durations.min():
            white_like.append("gauss_markov")
            n2_white += 2 * sigma**2 * tc
    v_white = np.sum([per_term[k] for k in white_like if k in per_term] or [np.zeros(starts.shape)], axis=0)
    v_model = np.sum(list(per_term.values()), axis=0)
    T = float(np.median(durations))
    excess_avar = model_avar(terms, [T], fs)[0] - n2_white / T
    return {
        "n_poses": int(starts.size),
        "session_length_s": float((starts + durations).max() - starts.min()),
        "median_pose_duration_s": T,
        "session_over_tau_max": (float((starts + durations).max() - starts.min()) / tau_max
                                 if tau_max else float("nan")),
        "pose_mean_std_white": float(np.sqrt(v_white.mean())),
        "pose_mean_std_model": float(np.sqrt(v_model.mean())),
        "pose_mean_std_excess": float(np.sqrt(max(v_model.mean() - v_white.mean(), 0.0))),
        "inflation": float(np.sqrt(v_model.mean() / v_white.mean())) if v_white.mean() > 0 else float("nan"),
        "by_term": {k: float(np.sqrt(max(v.mean(), 0.0))) for k, v in per_term.items()},
        "adev_excess_at_median_duration": float(np.sqrt(max(excess_avar, 0.0))),
        "pose_mean_var_white": v_white.tolist(),
        "pose_mean_var_model": v_model.tolist(),
    }


# --------------------------------------------------------------------------- homogeneity


def segment_homogeneity(allan_longest: AllanVariance, allan_others: AllanVariance | None) -> dict:
    """Allan deviation of the other rests relative to the longest, with two-sided F-test p-values.

    Returns lists over the τ where both have terms (empty without other rests):
    ``taus``, ``adev_ratio`` (shape (k, d) as nested lists) and ``p_value``.
    """
    if allan_others is None:
        return {"taus": [], "adev_ratio": [], "p_value": []}
    k = min(allan_longest.taus.size, allan_others.taus.size)
    ratio = allan_others.avar[:k] / allan_longest.avar[:k]
    nu_o, nu_l = allan_others.edf[:k, None], allan_longest.edf[:k, None]
    cdf = dist.f_cdf(ratio, nu_o, nu_l)
    p = np.minimum(1.0, 2 * np.minimum(cdf, 1 - cdf))
    return {"taus": allan_longest.taus[:k], "adev_ratio": np.sqrt(ratio), "p_value": p}


# --------------------------------------------------------------------------- the layer


@dataclass(frozen=True)
class AxisStochastic:
    """Stochastic layer result of one axis (arrays over the τ grid)."""

    axis: str
    taus: np.ndarray
    n_terms: np.ndarray
    edf: np.ndarray
    adev_measured: np.ndarray
    adev_ci: np.ndarray                 # (k, 2): 68.3 % chi-square interval, edf of the final model
    adev_longest_rest: np.ndarray       # the longest rest alone (NaN beyond its reach)
    adev_model_before: np.ndarray       # white-only fit, theory
    adev_model_after: np.ndarray        # final fit, theory
    adev_resim_before: np.ndarray       # re-simulated rests, white-only fit
    adev_resim_after: np.ndarray        # re-simulated rests, final fit
    fit_before: dict                    # {id: {"value", "se"[, "correlation_time_s", ...]}}
    fit_after: dict
    tests: tuple                        # one dict per step
    named: tuple[str, ...]
    gap_before: float                   # RMS standardised log-ratio (module docstring)
    gap_after: float
    log_gap_before: float               # RMS log10 ratio [decades]
    log_gap_after: float
    homogeneity: dict
    pose_residual_implication: dict

    @property
    def model_after(self) -> dict:
        """The final noise model in the form :func:`simulate_segments` takes."""
        return {k: ((v["value"], v[TERMS[k].shape_key]) if TERMS[k].shape_key else v["value"])
                for k, v in self.fit_after.items()}

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["named"] = list(self.named) if self.named else ["none"]
        d["tests"] = list(self.tests)
        return _json(d)


@dataclass(frozen=True)
class StochasticResult:
    """Stochastic layer on rest data: per-axis Allan deviations, named terms, gaps and implications."""

    fs: float
    seed: int
    alpha: float
    candidates: tuple[str, ...]
    n_boot: int
    n_resim: int
    segment_lengths: tuple[int, ...]
    axes: tuple[AxisStochastic, ...]
    unit: str = "u"
    notes: tuple[str, ...] = field(default_factory=tuple)

    def axis(self, name: str) -> AxisStochastic:
        for a in self.axes:
            if a.axis == name:
                return a
        raise KeyError(name)

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in ("fs", "seed", "alpha", "n_boot", "n_resim", "unit")}
        out["candidates"] = list(self.candidates)
        out["segment_lengths"] = list(self.segment_lengths)
        out["notes"] = list(self.notes)
        out["terms"] = {k: {"parameter": t.symbol, "unit": t.unit.replace("u", self.unit, 1), "meaning": t.meaning}
                        for k, t in TERMS.items()}
        out["axes"] = {a.axis: a.to_dict() for a in self.axes}
        return _json(out)


def _json(obj):
    """Numpy to plain Python; NaN/inf to None."""
    if isinstance(obj, dict):
        return {str(k): _json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _json(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


def rest_segments(acc, intervals) -> list[np.ndarray]:
    """Cut the rests ``[start, stop)`` (e.g. :attr:`accelcal.static.StaticPoses.intervals`) out of ``acc``."""
    acc = np.asarray(acc, dtype=float)
    iv = np.asarray(intervals, dtype=int)
    if iv.ndim != 2 or iv.shape[1] != 2 or np.any(iv[:, 0] < 0) or np.any(iv[:, 1] > len(acc)) \
            or np.any(iv[:, 1] <= iv[:, 0]):
        raise StochasticError(f"intervals must be [start, stop) rows within the {len(acc)} samples")
    return [acc[a:b] for a, b in iv]


def stochastic_layer(segments, fs: float, *, seed: int, alpha: float = 0.05, max_terms: int = 3,
                     candidates: Sequence[str] = DEFAULT_CANDIDATES, intervals=None,
                     n_boot: int = DEFAULT_N_BOOT, n_resim: int = DEFAULT_N_RESIM,
                     axis_names: Sequence[str] | None = None, unit: str = "u") -> StochasticResult:
    """Name the noise terms a white-noise simulator misses, per axis, and show the gap shrink.

    Parameters
    ----------
    segments : sequence of array_like, each shape (n_i, d)
        Rest intervals of the recording (rate samples in the data's unit).
    fs : float
        Sampling rate [Hz].
    seed : int
        Seeds the bootstrap and the re-simulation (results are deterministic).
    alpha : float
        Family-wise level of each step's test.
    max_terms : int
        Most terms named beyond white.
    candidates : sequence of str
        Candidate terms (ids of :data:`TERMS` other than ``white``).
    intervals : array_like of int, shape (n_segments, 2), optional
        Sample ranges ``[start, stop)`` of the segments in the recording, for the pose
        times of the pose-residual implication; default: the segments back to back,
        which understates the drift of time-correlated terms between poses.
    n_boot : int
        Parametric-bootstrap data sets per test step (and for the standard errors).
    n_resim : int
        Re-simulations averaged into the simulated Allan deviation of the gap.
    axis_names : sequence of str, optional
        Default ``x, y, z`` for three columns, else ``0, 1, …``.
    unit : str
        Name of the data unit, for the output.

    Returns
    -------
    StochasticResult

    Raises
    ------
    StochasticError, AllanError (both :class:`~accelcal.errors.AccelcalError`)
        Non-finite or too short segments, too little data for four octaves of τ,
        constant data, bad settings.
    """
    segs = check_segments(segments, fs)
    lengths = tuple(int(s.shape[0]) for s in segs)
    d = segs[0].shape[1]
    cand = tuple(dict.fromkeys(candidates))
    for k in cand:
        _term(k)
    if "white" in cand:
        raise StochasticError("'white' is the base model, not a candidate")
    if not 0 < alpha < 1:
        raise StochasticError(f"alpha must be in (0, 1), got {alpha}")
    if max_terms < 0 or n_boot < 19 or n_resim < 1:
        raise StochasticError("need max_terms >= 0, n_boot >= 19 (p-values down to 0.05) and n_resim >= 1")
    allan = allan_variance(segs, fs)
    if allan.taus.size < 4:
        raise StochasticError(f"the rests reach only {allan.taus.size} octaves of tau (longest rest "
                              f"{max(lengths) / fs:.2f} s); need at least 4 to tell noise terms apart")
    if np.any(allan.avar <= 0):
        raise StochasticError("a rest axis is constant: zero Allan variance (stuck sensor?)")
    names = tuple(axis_names) if axis_names is not None else (("x", "y", "z") if d == 3 else
                                                             tuple(str(i) for i in range(d)))
    if len(names) != d:
        raise StochasticError(f"{len(names)} axis names for {d} columns")
    if intervals is None:
        ends = np.cumsum(lengths)
        iv = np.column_stack([ends - np.array(lengths), ends])
    else:
        iv = np.asarray(intervals, dtype=int)
        if iv.shape != (len(lengths), 2) or np.any(iv[:, 1] - iv[:, 0] != np.array(lengths)):
            raise StochasticError("intervals must be (n_segments, 2) [start, stop) rows matching the segment lengths")
    starts, durations = iv[:, 0] / float(fs), (iv[:, 1] - iv[:, 0]) / float(fs)

    longest = int(np.argmax(lengths))
    m_long = allan.m[allan.m <= lengths[longest] // 2]
    allan_long = allan_variance([segs[longest]], fs, m=m_long)
    others = [s for i, s in enumerate(segs) if i != longest and s.shape[0] >= 2]
    m_oth = allan.m[allan.m <= max((s.shape[0] for s in others), default=0) // 2]
    allan_oth = allan_variance(others, fs, m=m_oth) if others and m_oth.size else None

    # Step 1's null (white only) is the same for every axis up to the scale N, and its
    # statistics are scale-free: one bootstrap at N = 1 serves all axes (exact).
    unit_white = NoiseFit(("white",), np.array([1.0]), float("nan"), 0.0)
    shared = _bootstrap(np.random.default_rng(np.random.SeedSequence([int(seed), 1 << 20])), unit_white, lengths,
                        float(fs), allan.m, allan.edf, allan.taus, list(cand) if max_terms > 0 else [], n_boot)
    axes = []
    for j in range(d):
        boot_seq, resim_seq = np.random.SeedSequence([int(seed), j]).spawn(2)
        adev_long = np.full(allan.taus.size, np.nan)
        adev_long[: m_long.size] = allan_long.adev[:, j]
        homog = segment_homogeneity(allan_long, allan_oth)
        homog = {"taus": homog["taus"], "adev_ratio": np.asarray(homog["adev_ratio"])[:, j] if len(homog["taus"])
                 else [], "p_value": np.asarray(homog["p_value"])[:, j] if len(homog["taus"]) else []}
        axes.append(_one_axis(names[j], allan, j, lengths, float(fs), cand, alpha, max_terms, n_boot, n_resim,
                              np.random.default_rng(boot_seq), resim_seq, starts, durations, adev_long, homog,
                              shared))
    notes = ("intervals not given: pose times assume the rests back to back",) if intervals is None else ()
    return StochasticResult(fs=float(fs), seed=int(seed), alpha=float(alpha), candidates=cand, n_boot=int(n_boot),
                            n_resim=int(n_resim), segment_lengths=lengths, axes=tuple(axes), unit=unit, notes=notes)


def _bootstrap(rng, fit: NoiseFit, lengths, fs, m, edf, taus, extra: Sequence[str], n_boot: int):
    """Refit ``n_boot`` synthetic data sets of ``fit``'s model with its own terms and with each term + extra[k].

    Returns (refitted coefficients (n_boot, p), refitted correlation times (n_boot,),
    LR (n_boot, len(extra))).
    """
    sims = simulate_segments(rng, lengths, fs, fit.model, size=n_boot)
    av = allan_variance(sims, fs, m=m).avar.T  # (n_boot, k)
    null = fit_avar_batch(taus, av, edf, fit.term_ids, fs)
    coefs = np.array([[math.sqrt(max(v, 0.0)) for v in f.c] for f in null])
    shapes = np.array([f.shape for f in null])
    dev0 = np.array([f.deviance for f in null])
    lr = np.empty((n_boot, len(extra)))
    for i, k in enumerate(extra):
        alt = fit_avar_batch(taus, av, edf, fit.term_ids + (k,), fs)
        lr[:, i] = np.maximum(dev0 - np.array([f.deviance for f in alt]), 0.0)
    return coefs, shapes, lr


def _fit_table(fit: NoiseFit, coefs: np.ndarray, shapes: np.ndarray, fs: float, tau_max: float) -> dict:
    """Coefficients with bootstrap standard errors; the nonlinear parameter's error also counts
    its grid step (uniform rounding, step²/12), else a grid-limited estimate would show 0."""
    se = coefs.std(axis=0, ddof=1)
    out = {}
    for i, (k, v) in enumerate(fit.coefficients.items()):
        out[k] = {"value": v, "se": float(se[i])}
        key = TERMS[k].shape_key
        if key:
            grid = TERMS[k].shape_grid(fs, tau_max)
            step = fit.shape * (grid[1] / grid[0] - 1.0)
            out[k][key] = fit.shape
            out[k][key.rsplit("_", 1)[0] + "_se"] = float(np.sqrt(np.var(shapes, ddof=1) + step**2 / 12))
    return out


def _one_axis(name, allan: AllanVariance, j, lengths, fs, cand, alpha, max_terms, n_boot, n_resim, rng,
              resim_seq, starts, durations, adev_long, homog, shared=None) -> AxisStochastic:
    taus, edf, m = allan.taus, allan.edf, allan.m
    avar = allan.avar[:, j]
    log_n = math.log(taus.size)
    current = fit_avar(taus, avar, edf, ("white",), fs)
    before = current
    table_before = None
    boot_current = None
    tests = []
    named: list[str] = []
    while len(named) < max_terms:
        # at most one two-parameter term per model: once one is named the others drop out
        has_shaped = any(TERMS[k].shape_key for k in current.term_ids)
        remaining = [k for k in cand if k not in current.term_ids and not (has_shaped and TERMS[k].shape_key)]
        if not remaining:
            break
        alts = {k: fit_avar(taus, avar, edf, current.term_ids + (k,), fs) for k in remaining}
        lr_obs = np.array([max(current.deviance - alts[k].deviance, 0.0) for k in remaining])
        if current.term_ids == ("white",) and shared is not None and list(remaining) == list(cand):
            n_white = current.coefficients["white"]
            coefs, shapes, lr_boot = shared[0] * n_white, shared[1], shared[2]
        else:
            coefs, shapes, lr_boot = _bootstrap(rng, current, lengths, fs, m, edf, taus, remaining, n_boot)
        boot_current = (coefs, shapes)
        if table_before is None:
            table_before = _fit_table(before, coefs, shapes, fs, taus.max())
        # a bootstrap LR equal to the observed one up to round-off counts as ≥
        tol = 1e-9 * max(1.0, float(lr_obs.max()))
        p_raw = (1 + (lr_boot >= lr_obs[None, :] - tol).sum(axis=0)) / (n_boot + 1)
        p_adj = (1 + (lr_boot.max(axis=1)[:, None] >= lr_obs[None, :] - tol).sum(axis=0)) / (n_boot + 1)
        dbic = -lr_obs + np.array([_n_params(k) for k in remaining]) * log_n
        best = int(np.argmin(dbic))
        accept = bool(p_adj[best] < alpha and dbic[best] < 0)
        tests.append({
            "step": len(tests) + 1,
            "current_model": list(current.term_ids),
            "candidates": {k: {"statistic": float(lr_obs[i]), "p_value": float(p_raw[i]),
                               "p_value_adjusted": float(p_adj[i]), "delta_bic": float(dbic[i]),
                               "value": alts[k].coefficients[k],
                               **({TERMS[k].shape_key: alts[k].shape} if TERMS[k].shape_key else {})}
                           for i, k in enumerate(remaining)},
            "best": remaining[best],
            "named": remaining[best] if accept else None,
        })
        if not accept:
            break
        named.append(remaining[best])
        current = alts[remaining[best]]
        boot_current = None
    if boot_current is None and current.term_ids == ("white",) and shared is not None:
        boot_current = (shared[0] * current.coefficients["white"], shared[1])
        if table_before is None:
            table_before = _fit_table(before, *boot_current, fs, taus.max())
    if boot_current is None:  # the final model was never the null of a test: bootstrap its standard errors
        coefs, shapes, _ = _bootstrap(rng, current, lengths, fs, m, edf, taus, [], n_boot)
        boot_current = (coefs, shapes)
        if table_before is None:
            table_before = _fit_table(before, coefs, shapes, fs, taus.max())
    after = current

    # CI with the edf of the final model: Satterthwaite mix of the terms' edf at each τ.
    parts, nus = [], []
    for k, c in zip(after.term_ids, after.c):
        parts.append(c * _term(k).basis(taus, fs, after.shape if TERMS[k].shape_key else None))
        if k == "gauss_markov":  # random-walk-like below T_c, white-like above
            nus.append(np.where(taus < after.shape, allan.edf_for(-2), allan.edf_for(0)))
        else:
            nus.append(allan.edf_for(_term(k).alpha))
    total = np.sum(parts, axis=0)
    nu_mix = total**2 / np.sum([p**2 / np.maximum(nu, 1e-12) for p, nu in zip(parts, nus)], axis=0)
    lo, hi = allan.adev_interval(0.683, np.column_stack([nu_mix] * allan.avar.shape[1]))

    resim = {}
    for label, fit in (("before", before), ("after", after)):
        if label == "after" and fit is before:  # nothing named: the same simulation (common random numbers)
            resim[label] = resim["before"]
            continue
        rng_r = np.random.default_rng(resim_seq)  # same state for both: common random numbers
        sims = simulate_segments(rng_r, lengths, fs, fit.model, size=n_resim)
        resim[label] = np.sqrt(allan_variance(sims, fs, m=m).avar.mean(axis=1))
    adev = np.sqrt(avar)
    se_log10 = 1.0 / (math.log(10.0) * np.sqrt(2.0 * edf))

    def gaps(sim):
        r = np.log10(adev / sim)
        return float(np.sqrt(np.mean(r**2))), float(np.sqrt(np.mean((r / se_log10) ** 2)))

    log_gb, gb = gaps(resim["before"])
    log_ga, ga = gaps(resim["after"])
    return AxisStochastic(
        axis=name, taus=taus, n_terms=allan.n_terms, edf=edf, adev_measured=adev,
        adev_ci=np.column_stack([lo[:, j], hi[:, j]]), adev_longest_rest=adev_long,
        adev_model_before=np.sqrt(before.avar(taus, fs)), adev_model_after=np.sqrt(after.avar(taus, fs)),
        adev_resim_before=resim["before"], adev_resim_after=resim["after"],
        fit_before=table_before, fit_after=_fit_table(after, *boot_current, fs, taus.max()), tests=tuple(tests),
        named=tuple(named), gap_before=gb, gap_after=ga, log_gap_before=log_gb, log_gap_after=log_ga,
        homogeneity=homog,
        pose_residual_implication=pose_residual_implication(after.model, starts, durations, fs, float(taus.max())))


def expected_residual_std(result: StochasticResult, directions) -> dict:
    """Expected std of each pose's scalar calibration residual from the noise models, white only and full.

    ``directions``: (n_poses, 3) gravity direction of each pose in the sensor frame
    (e.g. the pose means, normalised), one row per segment of ``result``.  The residual
    ``‖M⁻¹(z − b)‖ − g`` of pose ``i`` moves by ``uᵢ · eᵢ`` for a pose-mean error ``eᵢ``,
    so its variance is ``Σ_a u_ia² v_ia`` with ``v`` the per-axis centred pose-mean
    variances of :func:`pose_residual_implication`.  Returns ``{"white": (n,), "model": (n,)}``.
    """
    if len(result.axes) != 3:
        raise StochasticError("expected_residual_std needs the three axes of an accelerometer")
    u = np.asarray(directions, dtype=float)
    if u.shape != (len(result.segment_lengths), 3) or not np.all(np.isfinite(u)) \
            or np.any(np.linalg.norm(u, axis=1) == 0):
        raise StochasticError(f"directions must be finite non-zero rows, shape ({len(result.segment_lengths)}, 3)")
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    out = {}
    for label in ("white", "model"):
        v = np.column_stack([a.pose_residual_implication[f"pose_mean_var_{label}"] for a in result.axes])
        out[label] = np.sqrt(np.sum(u**2 * v, axis=1))
    return out


# --------------------------------------------------------------------------- figure

#: Short labels of the terms in figures.
TERM_LABELS = {"white": "white", "quantization": "quantization", "bias_instability": "bias instability (flicker)",
               "random_walk": "random walk", "drift_ramp": "drift ramp", "gauss_markov": "Gauss-Markov", "sinusoid": "sinusoid"}


def plot_allan(fig_or_axes, result: StochasticResult, title: str = "", wander_check: dict | None = None):
    """Measured vs simulated Allan deviation, before and after the named terms, one panel per axis.

    Draws, per axis: the measured ADEV (all rests pooled) with its 68 % interval, the
    longest rest alone (thin grey), the white-only model (dashed) and the final model
    (solid) as theory lines, and the re-simulated rests of both models (open markers),
    with the named terms and the gap before → after in the panel title.

    Parameters
    ----------
    fig_or_axes : matplotlib.figure.Figure or sequence of Axes
        A figure to fill (one row of panels) or one Axes per axis of ``result``.
    result : StochasticResult
    title : str
        Figure title (only when a figure is given).
    wander_check : dict, optional
        ``noise_implication["allan_check"]`` of the report: also draws what the bias wander
        estimated from the pose residuals predicts (white + wander, with the band of its
        95 % interval, green), where the check compared it (markers).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    from matplotlib.figure import Figure

    from ..plotting import RC

    n = len(result.axes)
    with matplotlib.rc_context(RC):
        if isinstance(fig_or_axes, Figure):
            fig = fig_or_axes
            axs = list(np.atleast_1d(fig.subplots(1, n, squeeze=False)[0]))
        else:
            axs = list(fig_or_axes)
            if len(axs) != n:
                raise StochasticError(f"{len(axs)} axes given for {n} result axes")
            fig = axs[0].figure
        for ax, a in zip(axs, result.axes):
            t = a.taus
            yerr = np.abs(np.vstack([a.adev_measured - a.adev_ci[:, 0], a.adev_ci[:, 1] - a.adev_measured]))
            ax.errorbar(t, a.adev_measured, yerr=yerr, fmt="o", color="k", ms=3.5, capsize=2, lw=0.9,
                        label="measured (all rests, 68 % CI)", zorder=4)
            if np.any(np.isfinite(a.adev_longest_rest)):
                ax.plot(t, a.adev_longest_rest, color="0.55", lw=0.9, label="measured, longest rest only", zorder=3)
            ax.plot(t, a.adev_model_before, ls="--", color="C0", lw=1.2, label="white only (fit)")
            ax.plot(t, a.adev_resim_before, ls="none", marker="s", mfc="none", color="C0", ms=4,
                    label="white only, re-simulated")
            named = " + ".join(TERM_LABELS.get(k, k) for k in a.named) or "none"
            if a.named:
                ax.plot(t, a.adev_model_after, ls="-", color="C3", lw=1.4, label="white + named (fit)")
                ax.plot(t, a.adev_resim_after, ls="none", marker="^", mfc="none", color="C3", ms=4,
                        label="white + named, re-simulated")
            ax.set(xscale="log", yscale="log", xlabel="averaging time τ [s]")
            ax.set_title(f"{a.axis}: + {named}\ngap {a.gap_before:.1f} → {a.gap_after:.1f}", fontsize=8.5)
            wc = (wander_check or {}).get("axes", {}).get(a.axis)
            if wc:
                tw = np.asarray(wc["taus"], float)
                band = np.asarray(wc["adev_predicted_band"], float)
                ax.fill_between(tw, band[:, 0], np.minimum(band[:, 1], 10 * np.nanmax(a.adev_measured)), color="C2",
                                alpha=0.18, lw=0, label="white + bias wander from the poses (95 %)")
                ax.plot(tw, wc["adev_predicted"], color="C2", lw=1.2)
                cmp = np.asarray(wc["compared"], bool)
                ax.plot(tw[cmp], np.asarray(wc["adev_predicted"], float)[cmp], "D", color="C2", ms=3.5,
                        mfc="none", label=f"compared: {wc['verdict']}")
        axs[0].set_ylabel(f"Allan deviation [{result.unit}]")
        axs[0].legend(loc="lower left", fontsize=6.5)
        if isinstance(fig_or_axes, Figure) and title:
            fig.suptitle(title, fontsize=9.5)
    return fig


__all__ = ["DEFAULT_CANDIDATES", "AxisStochastic", "NoiseFit", "NoiseTerm", "StochasticError", "StochasticResult",
           "TERMS", "TERM_IDS", "centred_pose_variance", "expected_residual_std", "fit_avar", "fit_avar_batch",
           "gamma_deviance", "model_avar", "plot_allan", "pose_difference_variance", "pose_residual_implication",
           "rest_segments", "segment_homogeneity", "simulate_noise", "simulate_segments", "stochastic_layer"]
