"""Compiled block loop of the shared-gain filter Monte Carlo
(:func:`accelcal_repro.batista2011.montecarlo.shared_gain.shared_gain_filter`).

Many runs share one gain sequence (the covariance does not depend on the data), so each
run's state is only propagated with its own rates and updated with the shared gain.  The
per-step rotation blocks are the core filter's compiled ones
(:func:`accelcal.batista.filter.rotation_blocks`, as compiled in the kernel module that
:func:`accelcal.kernels.compiled` loads).

Imported only when the filter kernels run compiled (it imports numba).

The kernel's disk cache depends on the core kernel file too (:func:`_also_depends_on`):
numba compiles ``rotation_blocks`` into this kernel's machine code but checks only this
file when it loads the cache, so a change to the core kernels would otherwise leave a
stale kernel in the cache.
"""

from __future__ import annotations

import os

import numpy as np

from accelcal.kernels import compiled, jit

_FILTER_KERNELS = compiled("batista._filter_kernels")
if _FILTER_KERNELS is None:
    raise ImportError("the shared-gain kernel needs the compiled filter kernels (numba; ACCELCAL_KERNELS is not numpy)")
rotation_blocks = _FILTER_KERNELS.rotation_blocks


@jit
def shared_gain_block(dt, x, a_prev, w_prev, a, w, y, gains, store, out, row):
    """Runs ``x`` (T, 9) with their last samples ``a_prev``, ``w_prev`` (T, 3) through
    the samples ``a``, ``w``, ``y`` (T, B, 3) with gains ``gains`` (B, 9, 3), as
    :meth:`accelcal_repro.batista2011.montecarlo.shared_gain._FilterState.run_block`: the state is
    propagated with each run's own rates and updated with the shared gain.  After
    sample ``b`` with ``store[b]`` the states go to ``out[:, row]`` (then ``row + 1``).
    ``x``, ``a_prev`` and ``w_prev`` are updated in place."""
    E, J0, J1 = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    coef = np.empty(5)
    vn, gn = np.empty(3), np.empty(3)
    for t in range(x.shape[0]):
        r = row
        for b in range(a.shape[1]):
            w0 = w_prev[t] if b == 0 else w[t, b - 1]
            a0 = a_prev[t] if b == 0 else a[t, b - 1]
            rotation_blocks(0.5 * (w0[0] + w[t, b, 0]), 0.5 * (w0[1] + w[t, b, 1]), 0.5 * (w0[2] + w[t, b, 2]), dt,
                    E, J0, J1, coef)
            for i in range(3):
                s = 0.0
                for m in range(3):
                    s += (E[i, m] * (x[t, m] + dt * x[t, 3 + m]) + J0[i, m] * (a[t, b, m] - x[t, 6 + m])
                          + J1[i, m] / dt * (a0[m] - a[t, b, m]))
                vn[i] = s
                s = 0.0
                for m in range(3):
                    s += E[i, m] * x[t, 3 + m]
                gn[i] = s
            r0, r1, r2 = y[t, b, 0] - vn[0], y[t, b, 1] - vn[1], y[t, b, 2] - vn[2]
            G = gains[b]
            for i in range(3):
                x[t, i] = vn[i] + G[i, 0] * r0 + G[i, 1] * r1 + G[i, 2] * r2
                x[t, 3 + i] = gn[i] + G[3 + i, 0] * r0 + G[3 + i, 1] * r1 + G[3 + i, 2] * r2
                x[t, 6 + i] = x[t, 6 + i] + G[6 + i, 0] * r0 + G[6 + i, 1] * r1 + G[6 + i, 2] * r2
            if store[b]:
                for i in range(9):
                    out[t, r, i] = x[t, i]
                r += 1
        for i in range(3):
            a_prev[t, i] = a[t, a.shape[1] - 1, i]
            w_prev[t, i] = w[t, w.shape[1] - 1, i]


def _also_depends_on(dispatcher, path) -> None:
    """Make ``dispatcher``'s disk cache stale when the file ``path`` changes, as when its own does.

    numba keys a cached function on its own source file's modification time and size;
    compiled functions it calls from other files are part of its machine code but not of
    that key.  Their file's time and size are added to it here.  Without a disk cache (the
    in-memory fallback of :func:`accelcal.kernels.jit`) there is nothing to do.
    """
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is None:
        return
    st = os.stat(path)
    cache_file._source_stamp = (cache_file._source_stamp, (st.st_mtime, st.st_size))


_also_depends_on(shared_gain_block, _FILTER_KERNELS.__file__)
