"""One BLAS thread around the library's small, many-times-repeated linear algebra.

The discrepancy loop's likelihood runs LAPACK on stacks of 14-27-square matrices
(``numpy.linalg.eigh`` over the correlation-time grid, its bootstrap's replicates).  A
multi-threaded BLAS splits each small call over its threads, which then spin for each
other: on 2 cores a benchmark recording took 3.8 s of wall time (2.6 s CPU) with
OpenBLAS's default threads against 0.36 s with one (measured side by side; 10x).  The
command line and the workflow set one thread through the environment before numpy loads
(:data:`accelcal.cli.BLAS_THREADS`, the Snakefile); a Python user of the library gets it
from :func:`one_blas_thread` on the entry that runs the loop, which limits the BLAS
libraries and restores them after.  The libraries are found once, at the first call
(threadpoolctl's controller: 8 µs per call after that, where a fresh ``threadpool_limits``
scans every loaded library again, 3.4 ms per call in a benchmark chunk's process: 40 s of
CPU over a default run's ~12,000 calls); numpy's and scipy's BLAS are loaded by then.
"""

from __future__ import annotations

from functools import cache, wraps

from threadpoolctl import ThreadpoolController


def one_blas_thread(function):
    """``function`` run with every loaded BLAS limited to one thread (restored after)."""

    @wraps(function)
    def limited(*args, **kwargs):
        with _controller().limit(limits=1, user_api="blas"):
            return function(*args, **kwargs)

    return limited


@cache
def _controller() -> ThreadpoolController:
    """The loaded thread pools, found once (module docstring)."""
    return ThreadpoolController()


__all__ = ["one_blas_thread"]
