"""Simulators of the noise-term library: sampled noise of a model for segments of given lengths.

Every term draws from its own random stream, so two models simulated from generators in
the same state share the random numbers of their common terms (common random numbers:
the stochastic layer re-simulates the rests before and after a term is named with them).
How each term is drawn (Kasdin–Walter flicker filter, stationary AR(1), quantization as
differences of rounding errors, ...) is described in :mod:`accelcal.noise.terms`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .terms import TERMS, term_ids, term_parameters


def simulate_segments(rng: np.random.Generator, lengths: Sequence[int], fs: float,
                      terms: Mapping[str, object], size: int | None = None) -> list[np.ndarray]:
    """Noise of the model ``terms`` for rest segments of the given lengths.

    Every term draws from its own stream (spawned from ``rng`` for all of
    :data:`~accelcal.noise.terms.TERMS`, present or not), so two models simulated from generators in the
    same state share the random numbers of their common terms (common random numbers).

    Returns a list of arrays of shape ``(n_i,)`` (``size=None``) or ``(n_i, size)``.
    """
    vals = {k: term_parameters(k, v) for k, v in terms.items()}
    ids = term_ids()
    seeds = rng.integers(0, 2**63, size=len(ids))
    streams = {k: np.random.default_rng(int(s)) for k, s in zip(ids, seeds)}
    cols = 1 if size is None else int(size)
    out = []
    for n in lengths:
        y = np.zeros((int(n), cols))
        for k in ids:  # fixed order
            if k in vals:
                y += TERMS[k].simulate(*vals[k], streams[k], int(n), float(fs), cols)
        out.append(y[:, 0] if size is None else y)
    return out


def simulate_noise(rng: np.random.Generator, n: int, fs: float, terms: Mapping[str, object],
                   size: int | None = None) -> np.ndarray:
    """One noise record of ``n`` samples (see :func:`simulate_segments`)."""
    return simulate_segments(rng, [n], fs, terms, size)[0]


__all__ = ["simulate_noise", "simulate_segments"]
