"""Simulators of the noise-term library: sampled noise of a model for segments of given lengths.

Every term draws from its own random stream, so two models simulated from generators in
the same state share the random numbers of their common terms (common random numbers:
the stochastic layer re-simulates the rests before and after a term is named with them).
How each term is drawn (Kasdin–Walter flicker filter, stationary AR(1), quantization as
differences of rounding errors, ...) is described in :mod:`accelcal.noise.terms`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .. import kernels
from .terms import TERM_IDS, term_parameters


def simulate_segments(rng: np.random.Generator, lengths: Sequence[int], fs: float,
                      terms: Mapping[str, object], size: int | None = None) -> list[np.ndarray]:
    """Noise of the model ``terms`` for rest segments of the given lengths.

    Every term draws from its own stream (spawned from ``rng`` for all of
    :data:`TERM_IDS`, present or not), so two models simulated from generators in the
    same state share the random numbers of their common terms (common random numbers).

    Returns a list of arrays of shape ``(n_i,)`` (``size=None``) or ``(n_i, size)``.
    """
    vals = {k: term_parameters(k, v) for k, v in terms.items()}
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
    fast = kernels.compiled("noise._fast")
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


__all__ = ["simulate_noise", "simulate_segments"]
