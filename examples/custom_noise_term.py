"""Adding a noise term: one class, registered, with all its behaviour on it.

The term: random telegraph noise ("popcorn" or burst noise of CMOS and MEMS parts), a bias
that switches between +A and -A at random, dwelling a mean time T_d in each state.  Its
autocovariance A² exp(−2|t|/T_d) is a Gauss–Markov process's with σ = A and T_c = T_d/2, so
its Allan variance and the variance between pose means are that process's; its simulation
is its own.  Once registered, the noise fit, the simulators, the discrepancy workflow's
pose-mean variances and the figures know it; ``tests/test_noise_term_conformance.py``
checks it as every other term (``tests/test_examples.py`` runs those checks on it).
In the package the class is one more entry of ``src/accelcal/noise/terms.py``.

Run: ``python examples/custom_noise_term.py``.
"""

from __future__ import annotations

import math

import numpy as np

from accelcal.noise import allan_variance, fit_avar, simulate_segments
from accelcal.noise.terms import TERMS, NoiseTerm, register_term


@register_term
class Telegraph(NoiseTerm):
    name = "random telegraph"
    id, symbol, unit, alpha = "telegraph", "A", "{u}", -2
    meaning = "a bias switching between +A and -A at random (popcorn noise)"
    colour, shape_key, example = "C7", "dwell_time_s", (1.0, 0.7)

    def _basis(self, tau, fs, shape):  # a Gauss–Markov process's, T_c = T_d / 2
        return TERMS["gauss_markov"].basis(tau, fs, shape / 2)

    def shape_grid(self, fs, tau_max):
        return 2 * TERMS["gauss_markov"].shape_grid(fs, tau_max)

    def edf(self, allan, shape=None):
        return TERMS["gauss_markov"].edf(allan, shape / 2)

    def simulate(self, v, shape, rng, n, fs, cols):
        """A two-state Markov chain: flip probability p per sample, so the correlation is (1 − 2p)^k."""
        p = -0.5 * math.expm1(-2.0 / (fs * shape))
        start = np.where(rng.random(cols) < 0.5, -1.0, 1.0)  # the stationary distribution
        flips = np.cumsum(rng.random((n, cols)) < p, axis=0)
        return v * start * (1.0 - 2.0 * (flips % 2))

    def interval_difference_variance(self, v2, shape, iv):
        return TERMS["gauss_markov"].interval_difference_variance(v2, shape / 2, iv)


if __name__ == "__main__":
    fs, truth = 100.0, {"white": 0.02, "telegraph": (0.05, 4.0)}
    rests = simulate_segments(np.random.default_rng(1), [60_000] * 4, fs, truth, size=3)
    allan = allan_variance(rests, fs)
    fit = fit_avar(allan.taus, allan.avar[:, 0], allan.edf, ("white", "telegraph"), fs)
    print(f"telegraph: A = {fit.coefficients['telegraph']:.3f} (true 0.05), "
          f"dwell time {fit.shape:.2g} s (true 4 s); white N = {fit.coefficients['white']:.4f} (true 0.02)")
