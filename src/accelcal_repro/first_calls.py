"""The first calls of the compiled kernels (:func:`kernel_first_calls`), as a script that a
fresh process runs (:func:`accelcal_repro.timing.compile_timing`), and their names (what
the benchmark config's ``compile_calls`` may list; the benchmark job checks them).

The estimators' calls come from the registry (every estimator with a compiled kernel:
its single-problem form, the same without the noise level if it uses one, then the
batched forms; those that use no noise level first), the filters' are listed here."""

from __future__ import annotations

from functools import partial

import numpy as np

from accelcal.batista.filter import covariance_sequence, kalman_filter
from accelcal.errors import AccelcalError
from accelcal.registry import estimators
from accelcal.simulation import random_directions, sample_truth, simulate_poses
from accelcal.tereshkov.estimator import run_estimator

#: Calls that trigger every compiled kernel once, in the order of the table (run in a
#: fresh process by :func:`accelcal_repro.timing.compile_timing`).
SCRIPT = """
import json, sys, time
t0 = time.perf_counter()
from accelcal import kernels
from accelcal_repro.first_calls import compiled_estimators, kernel_first_calls
for e in compiled_estimators():
    e.load(), e.load_batch()
rows = [("import accelcal estimators", time.perf_counter() - t0)]
t0 = time.perf_counter()
import numba
rows.append(("import numba", time.perf_counter() - t0))
calls = kernel_first_calls()
wanted = json.loads(sys.argv[1])
for name, call in calls:
    if wanted == "all" or name in wanted:
        t0 = time.perf_counter()
        call()
        rows.append((name, time.perf_counter() - t0))
print(json.dumps({"backend": kernels.backend(), "rows": rows}))
"""
#: The filters' first calls in :data:`SCRIPT`, after the estimators'.
FILTER_CALLS = ("kalman_filter", "covariance_sequence", "tereshkov run_estimator")


def compiled_estimators():
    """The registered accelerometer estimators with a compiled kernel, those that use no
    noise level first (registry order otherwise)."""
    return sorted(estimators("accelerometer", compiled=True), key=lambda e: e.needs_noise)


def estimator_calls(z, g: float, noise_std: float) -> list[tuple[str, object]]:
    """``(name, call)`` of every compiled estimator on the poses ``z`` (T, n, 3): its
    single-problem form on ``z[0]`` (told ``noise_std`` if it uses a noise level), the
    same without the noise level (``'<name> (noise estimated)'``), then the batched
    forms on all of ``z``."""
    out = []
    for e in compiled_estimators():
        out.append((e.name, partial(e.fit, z[0], g, noise_std)))
        if e.needs_noise:
            out.append((f"{e.name} (noise estimated)", partial(e.fit, z[0], g)))
    out += [(e.batch_name, partial(e.fit_batch, z, g, noise_std)) for e in compiled_estimators() if e.batch]
    return out


def kernel_first_calls() -> list[tuple[str, object]]:
    """``(name, call)`` of every compiled kernel's first call, in :data:`SCRIPT`'s order: the
    estimators' (:func:`estimator_calls` on 24 simulated poses), then the filters'
    (:data:`FILTER_CALLS`, on 50 steps)."""
    rng = np.random.default_rng(0)
    tr = sample_truth(rng, 4)
    z = simulate_poses(random_directions(rng, 24, 4), 9.8, tr["M"], tr["bias"], 1e-3, rng)
    n = 50
    t = np.arange(n) * 0.01
    w = np.full((n, 3), 0.1)
    a = np.zeros((n, 3))
    f = np.zeros((1, n, 3))
    f[..., 2] = -9.8
    filters = (partial(kalman_filter, t, a, w, a, np.zeros(9), np.ones(9)),
               partial(covariance_sequence, t, w, np.ones(9)),
               partial(run_estimator, f * 0, f, f, np.zeros((1, n)), np.ones((1, n)), 0.01))
    return estimator_calls(z, 9.8, 1e-3) + list(zip(FILTER_CALLS, filters))


def first_call_names() -> tuple[str, ...]:
    """The names of the calls of :data:`SCRIPT`, in its order (without running anything)."""
    return tuple(name for name, _ in estimator_calls([None], 0.0, 0.0)) + FILTER_CALLS


#: The calls :func:`accelcal_repro.timing.compile_timing` can time.
FIRST_CALLS = first_call_names()


def check_calls(calls, where: str = "benchmark.compile_calls") -> None:
    """``calls`` is ``'all'`` or names of :data:`FIRST_CALLS`, else one-line
    :class:`~accelcal.errors.AccelcalError` naming the config key (the benchmark job checks
    this, so that parsing the Snakefile imports no reproduction)."""
    if calls == "all":
        return
    for i, name in enumerate(calls):
        if name not in FIRST_CALLS:
            raise AccelcalError(f"{where}.{i}: {name!r} is not a first call of a compiled kernel; "
                                f"known: {', '.join(FIRST_CALLS)}")


__all__ = ["FILTER_CALLS", "FIRST_CALLS", "SCRIPT", "check_calls", "compiled_estimators", "estimator_calls",
           "first_call_names", "kernel_first_calls"]
