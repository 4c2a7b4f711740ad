"""The first calls of the compiled kernels, as a script that a fresh process runs
(:func:`accelcal_repro.timing.compile_timing`), and their names (what the benchmark
config's ``compile_calls`` may list).  Light to import: the workflow's config check reads
the names while the Snakefile is parsed."""

#: Calls that trigger every compiled kernel once, in the order of the table (run in a
#: fresh process by :func:`compile_timing`).
SCRIPT = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from accelcal import kernels
from accelcal.als import full_als, full_als_batch
from accelcal.lls import bias_lls, bias_lls_batch, full_lls, full_lls_batch
from accelcal.batista.filter import covariance_sequence, kalman_filter
from accelcal.tereshkov.estimator import run_estimator
from accelcal.simulation import random_directions, sample_truth, simulate_poses
rows = [("import accelcal estimators", time.perf_counter() - t0)]
t0 = time.perf_counter()
import numba
rows.append(("import numba", time.perf_counter() - t0))
rng = np.random.default_rng(0)
tr = sample_truth(rng, 4)
z = simulate_poses(random_directions(rng, 24, 4), 9.8, tr["M"], tr["bias"], 1e-3, rng)
n = 50
t = np.arange(n) * 0.01
w = np.full((n, 3), 0.1)
a = np.zeros((n, 3))
f = np.zeros((1, n, 3))
f[..., 2] = -9.8
calls = [
    ("full_lls", lambda: full_lls(z[0], 9.8)),
    ("bias_lls", lambda: bias_lls(z[0], 9.8)),
    ("full_als", lambda: full_als(z[0], 9.8, 1e-3)),
    ("full_als (noise estimated)", lambda: full_als(z[0], 9.8)),
    ("full_lls_batch", lambda: full_lls_batch(z, 9.8)),
    ("bias_lls_batch", lambda: bias_lls_batch(z, 9.8)),
    ("full_als_batch", lambda: full_als_batch(z, 9.8, 1e-3)),
    ("kalman_filter", lambda: kalman_filter(t, a, w, a, np.zeros(9), np.ones(9))),
    ("covariance_sequence", lambda: covariance_sequence(t, w, np.ones(9))),
    ("tereshkov run_estimator", lambda: run_estimator(f * 0, f, f, np.zeros((1, n)), np.ones((1, n)), 0.01)),
]
wanted = json.loads(sys.argv[1])
for name, call in calls:
    if wanted == "all" or name in wanted:
        t0 = time.perf_counter()
        call()
        rows.append((name, time.perf_counter() - t0))
print(json.dumps({"backend": kernels.backend(), "rows": rows}))
"""
#: The calls :func:`accelcal_repro.timing.compile_timing` can time (names in :data:`SCRIPT`).
FIRST_CALLS = ("full_lls", "bias_lls", "full_als", "full_als (noise estimated)", "full_lls_batch", "bias_lls_batch",
               "full_als_batch", "kalman_filter", "covariance_sequence", "tereshkov run_estimator")


__all__ = ["FIRST_CALLS", "SCRIPT"]
