"""The rests' pooled Allan variances (accelcal.discrepancy.wander.rests.rest_allan) against
their definition, one rest and one octave at a time (the vectorised form must give the same
numbers, bit for bit: the sums are taken in the same order)."""

import numpy as np
import pytest

from accelcal.discrepancy.wander.rests import MIN_BLOCKS, MIN_TAU_SHARE, rest_allan


def _reference(x, iv, fs):
    """The module docstring's statistic, written out: every rest, every octave."""
    lengths = iv[:, 1] - iv[:, 0]
    ms = [1 << j for j in range(20) if int(lengths.max()) // (1 << j) >= MIN_BLOCKS]
    ms = [m for m in ms if m >= MIN_TAU_SHARE * float(np.median(lengths))]
    s2, cnt = np.zeros((3, len(ms))), np.zeros(len(ms))
    for a0, a1 in iv:
        for k, m in enumerate(ms):
            nb = (a1 - a0) // m
            if nb < MIN_BLOCKS:
                continue
            y = x[a0:a0 + nb * m].reshape(nb, m, 3).mean(axis=1)
            d = np.diff(y, axis=0)
            s2[:, k] += 0.5 * np.sum(d * d, axis=0)
            cnt[k] += nb - 1
    return np.asarray(ms, float), s2 / cnt, 2.0 * cnt / 3.0


@pytest.mark.parametrize("seed", range(6))
def test_rest_allan_is_its_definition(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2000, 20000))
    x = rng.standard_normal((n, 3)) * rng.uniform(0.1, 50) + rng.uniform(-1e4, 1e4, 3)
    if seed % 2:   # rests of one length, as a simulated session's
        L = int(rng.integers(40, 700))
        starts = np.arange(0, n - L, L + 37)
        iv = np.c_[starts, starts + L]
    else:          # rests of any lengths
        iv = np.sort(rng.choice(n, 2 * int(rng.integers(1, 30)), replace=False)).reshape(-1, 2)
    fs = 100.0
    got = rest_allan(x, iv, fs)
    m, avar, dof = _reference(x, iv, fs)
    assert got is not None
    assert np.array_equal(got.m, m) and np.array_equal(got.taus, m / fs)
    assert np.array_equal(got.avar, avar)
    assert np.array_equal(got.dof, np.broadcast_to(dof, (3, m.size)))


def test_rest_allan_none_without_blocks():
    assert rest_allan(np.zeros((10, 3)), np.array([[0, 3]]), 100.0) is None
