"""The batched closed forms: the same refusals as the single forms, trial by trial, and a
throughput that stays far above the iterative baseline's.

The batches decide which trials are degenerate (coplanar, along one axis, identical) from
a moment screen, the compiled kernel's from the Gram matrix it forms anyway, and give the
reference geometry check only to the trials the screen does not pass.  The first tests put
thousands of trials on both sides of the screen's and the reference's thresholds and
compare every decision with the single-problem estimator's; the last one times the batches
against NLLS in the same process (a ratio, so the machine's speed and load cancel).
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from accelcal import kernels
from accelcal.errors import AccelcalError
from accelcal.lls import bias_lls, full_lls
from accelcal.lls_batch import bias_lls_batch, full_lls_batch
from accelcal.nlls import bias_nlls, full_nlls
from accelcal.simulation import random_directions, sample_truth, simulate_poses
from accelcal.validation import check_geometry, degenerate_trials

G = 9.8055
HAVE_NUMBA = kernels._resolve("auto") == "numba"
BACKENDS = ("numba", "numpy") if HAVE_NUMBA else ("numpy",)


@pytest.fixture(autouse=True)
def _restore_backend():
    previous = kernels.choice()
    yield
    kernels.set_backend(previous)


def near_threshold(rng, T: int, n: int, identity: bool) -> np.ndarray:
    """``T`` pose sets of ``n`` poses squeezed towards a plane (out-of-plane spread
    log-uniform over 0.005-0.3 of the in-plane one: the scatter's smallest normalised
    eigenvalue from ~1e-5 to ~0.04, across the reference's 1e-3 and the screen's 2e-3) or
    towards one axis, randomly rotated and offset; a few identical sets."""
    u = random_directions(rng, n, T)
    h = np.exp(rng.uniform(np.log(0.005), np.log(0.3), T))
    axis = rng.random(T) < 0.3  # squeeze two components: poses along one axis
    u[:, :, 2] *= h[:, None]
    u[axis, :, 1] *= h[axis, None]
    q, _ = np.linalg.qr(rng.normal(size=(T, 3, 3)))
    tr = sample_truth(rng, T)
    M = np.broadcast_to(np.eye(3), (T, 3, 3)) if identity else tr["M"]
    z = simulate_poses(np.einsum("tij,tnj->tni", q, u), G, M, tr["bias"], 1e-3, rng)
    z[: T // 50] = z[: T // 50, :1]  # identical poses
    return z


def single_outcome(f, z) -> str:
    try:
        f(z, G)
    except AccelcalError as e:
        return type(e).__name__
    return "ok"


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("batch, single, identity, n", [(full_lls_batch, full_lls, False, 16),
                                                        (bias_lls_batch, bias_lls, True, 6)])
def test_batches_refuse_exactly_the_trials_the_single_forms_refuse(backend, batch, single, identity, n):
    kernels.set_backend(backend)
    z = near_threshold(np.random.default_rng(5), 600, n, identity)
    status = batch(z, G).status
    expected = np.array([single_outcome(single, zt) for zt in z])
    refused = expected == "DegeneratePosesError"
    assert 0.2 < refused.mean() < 0.8  # both sides of the threshold are exercised
    np.testing.assert_array_equal(status == "DegeneratePosesError", refused)


def test_the_vectorised_screen_gives_the_reference_decisions():
    """:func:`degenerate_trials` (vectorised moment screen, reference check for the rest)
    against :func:`check_geometry` on every trial; and the screen does the work: a
    screen that passed nothing would only be slow, one that passed everything would fail."""
    z = near_threshold(np.random.default_rng(9), 4000, 12, identity=False)
    ref = np.zeros(len(z), bool)
    for t, zt in enumerate(z):
        try:
            check_geometry(zt)
        except AccelcalError:
            ref[t] = True
    np.testing.assert_array_equal(degenerate_trials(z), ref)
    assert not np.array_equal(degenerate_trials(z, clear=np.ones(len(z), bool)), ref)


def _cpu(f, z) -> float:
    """Thread CPU seconds of ``f(z, G)`` (a wait for a core on a loaded machine does not count)."""
    c0 = time.thread_time()
    f(z, G)
    return time.thread_time() - c0


def _interleaved_ratio(batch, single, z, problems: int = 20, chunk: int = 10_000, repeats: int = 3) -> tuple:
    """(problems/s of ``batch`` over all of ``z`` / problems/s of ``single`` on its first
    ``problems``, both rates).

    Side by side at a fine grain: the single-problem calls and the batch chunks alternate
    (a chunk after every few problems), each timed alone and kept at its best of
    ``repeats`` passes.  Timed apart (the batch first, then the NLLS), one of the two met
    another moment of the machine's load (on 2 shared cores at load 20 the SMT sibling and
    the caches change from one tenth of a second to the next), and the ratio of
    separate best-of timings spread from 1500x to 2400x (full) and 5400x to 9300x (bias)
    on one machine within a minute; interleaved it spread 1460-1730x and 5800-6800x."""
    chunks = [z[i:i + chunk] for i in range(0, len(z), chunk)]
    per = problems // len(chunks)
    t_single, t_batch = np.full(problems, np.inf), np.full(len(chunks), np.inf)
    for _ in range(repeats):
        for i in range(problems):
            t_single[i] = min(t_single[i], _cpu(single, z[i]))
            if i % per == per - 1:
                t_batch[i // per] = min(t_batch[i // per], _cpu(batch, chunks[i // per]))
    rate, base = len(z) / t_batch.sum(), problems / t_single.sum()
    return rate / base, rate, base


#: Interleaved measurements whose median the throughput test compares with its bars.
ROUNDS = 5


def _median_ratio(batch, single, z) -> tuple:
    """The median of :data:`ROUNDS` :func:`_interleaved_ratio` measurements (ratio, rates).

    A test that catches a 3x slip of a ratio it bars at B passes a ratio r only if
    B < r < 3B: the widest margin either way is sqrt(3) = 1.73x, at r = 1.73 B.  The batches
    sit at 1.4-1.9x their bars, so what keeps the test from flaking is the spread of the
    measurement, not its level: the median of 5 rounds (2.5 s more than of 3) falls below
    a bar only if 3 of 5 rounds do, where the median of 3 needed 2 of 3 (single rounds
    measured 1277-2051x for the full LLS, 4807-8525x for the bias-only LLS at load 17-26)."""
    return sorted((_interleaved_ratio(batch, single, z) for _ in range(ROUNDS)), key=lambda r: r[0])[ROUNDS // 2]


@pytest.mark.skipif(not HAVE_NUMBA, reason="the throughput goals are those of the compiled kernels")
def test_batches_run_thousands_of_times_faster_than_nlls():
    """At the benchmark's headline setting (24 poses, noise 1e-3 m/s²),
    the batched full LLS solves at least 1000x, the bias-only LLS at least 4000x the
    problems per second of the NLLS baseline, both timed here, interleaved
    (:func:`_median_ratio`, the median of five interleaved measurements; medians of three
    measured 1416-1899x and 5375-7251x at load 17-26 on 2 cores; the Python loop over the
    trials that once checked the geometry made them 300x, and a 3x slip of either kernel
    falls below: 472-633x and 1792-2417x)."""
    kernels.set_backend("numba")
    rng = np.random.default_rng(1)
    T, n = 20000, 24
    tr = sample_truth(rng, T)
    u = random_directions(rng, n, T)
    zf = simulate_poses(u, G, tr["M"], tr["bias"], 1e-3, rng)
    zb = simulate_poses(u, G, np.eye(3), tr["bias"], 1e-3, rng)
    for f, z in ((full_lls_batch, zf), (bias_lls_batch, zb), (full_nlls, zf[0]), (bias_nlls, zb[0])):
        f(z, G)  # warm-up: kernels loaded, CasADi's solver built
    full = _median_ratio(full_lls_batch, full_nlls, zf)
    bias = _median_ratio(bias_lls_batch, bias_nlls, zb)
    assert full[0] > 1000, "full_lls_batch {1:.0f}/s, {0:.0f}x NLLS ({2:.0f}/s)".format(*full)
    assert bias[0] > 4000, "bias_lls_batch {1:.0f}/s, {0:.0f}x NLLS ({2:.0f}/s)".format(*bias)
