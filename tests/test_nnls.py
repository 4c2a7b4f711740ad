"""The Allan-variance fit's non-negative least squares (Lawson-Hanson's active set, numpy batch
and compiled kernel) against the definition: the best least-squares solution over every support."""

from itertools import combinations

import numpy as np
import pytest

from accelcal import kernels
from accelcal.noise.allan_fit import _nnls_batch

FAST = kernels.compiled("noise._fast") if kernels._resolve("auto") == "numba" else None


def enumerated(A, b):
    """The optimum by enumeration: the feasible unconstrained solution of least residual over all supports."""
    p = A.shape[1]
    best, best_x = float(b @ b), np.zeros(p)
    for size in range(1, p + 1):
        for idx in combinations(range(p), size):
            sol = np.linalg.lstsq(A[:, idx], b, rcond=None)[0]
            if np.all(sol >= 0):
                r = A[:, idx] @ sol - b
                if r @ r < best:
                    best, best_x = float(r @ r), np.zeros(p)
                    best_x[list(idx)] = sol
    return best_x


def problems(rng, G=120):
    """Weighted Allan-variance fits as the noise analysis meets them (the five IEEE terms'
    bases on 17 octaves, random sizes, Gamma scatter), columns scaled to unit norm, and
    random dense ones of 2-6 columns."""
    tau = 2.0 ** np.arange(17) / 100.0
    H = np.column_stack([3 / tau**2, 1 / tau, np.full_like(tau, 0.44), tau / 3, tau**2 / 2])
    out = []
    for g in range(G):
        if g % 2:
            c = np.exp(rng.uniform(-12, 0, 5)) * (rng.random(5) < 0.7)
            y = H @ c * rng.gamma(20, 1 / 20, len(tau))
            A, b = H / y[:, None], np.ones(len(tau))  # relative residuals, as the scoring's weights
        else:
            p = int(rng.integers(2, 7))
            A, b = rng.standard_normal((12, p)), rng.standard_normal(12)
        out.append((A / np.linalg.norm(A, axis=0), b))
    return out


@pytest.mark.parametrize("which", ["numpy", "compiled"])
def test_active_set_finds_the_enumerated_optimum(which):
    if which == "compiled" and FAST is None:
        pytest.skip("numba not installed")
    rng = np.random.default_rng(5)
    worst = 0.0
    for A, b in problems(rng):
        want = enumerated(A, b)
        got = _nnls_batch(A[None], b[None])[0] if which == "numpy" else FAST._nnls_small(A, b)
        assert np.all(got >= 0)
        worst = max(worst, float(np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-300)))
    assert worst < 1e-10, worst


def test_a_batch_solves_each_problem_as_alone():
    """Problems of one batch that take different numbers of steps do not disturb each other."""
    rng = np.random.default_rng(6)
    ps = [pr for pr in problems(rng, 60) if pr[0].shape == (17, 5)]
    A, b = np.stack([a for a, _ in ps]), np.stack([b for _, b in ps])
    alone = np.array([_nnls_batch(a[None], v[None])[0] for a, v in zip(A, b)])
    assert np.array_equal(_nnls_batch(A, b), alone)
